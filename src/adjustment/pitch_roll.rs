//! The height-field solver: the three adjustment steps (pitch, roll, fine
//! pitch) on a filled [`HeightField`], for the straight feather.
//!
//! Geometry. With roll β applied before pitch α, the posed kite is one plane
//! through the root; over a horizontal point (x, y) of the root frame its
//! height is `x·tan α + y·tan β / cos α`, and the kite point there has shaft
//! coordinate `x0 = x / cos α + y0·sin β·tan α` and lateral coordinate
//! `y0 = y / cos β`. So the steps work in slopes (`p = tan α`, lateral
//! slope `q = tan β / cos α`), with no per-cell trigonometry.
//!
//! Semantics (a height field is a "lid" problem). A cell constrains the
//! feather only while the posed kite covers it (cell rounded outward by half
//! a cell in kite coordinates); then the kite's lowest point over the cell
//! must clear the cell's height. Everything under a cell's top counts as
//! solid, which is what makes the field safe for steep obstacles whose cell
//! maximum hides their lower parts. A feather may also clear a tall cell near
//! its tip by pitching until its tip no longer covers it (the tip then
//! stops at the obstacle's side instead of climbing over it).
//!
//! The smallest clear pitch is found by jumping upward from the lowest
//! allowed pitch: at the current pitch, every covered cell that is violated
//! stays violated until its own threshold (the pitch that clears it, or the
//! one at which the tip leaves it), so the pitch jumps to the largest such
//! threshold; the loop ends at the first pitch where no covered cell is
//! violated, which is therefore clear (every cell it covers is checked).
//!
//! The root socket (see `height_field`): nothing within the first 2.5 % of
//! the shaft constrains the pitch; heights beyond it are judged at its end.

use super::raster::{ceil_i32, floor_i32, max_f, min_f};
use super::{AdjustParams, AdjustSteps, HeightField};
use crate::feather::FeatherPose;

/// Jump iterations before giving up (reported as a clamp). Real fields need
/// two to five.
const MAX_JUMPS: usize = 64;
/// Free height under a vane is capped at this fraction of the width when
/// balancing volumes (empty space far below does not pull the roll).
const FREE_HEIGHT_CAP_PER_WIDTH: f32 = 0.5;
/// Rolls whose lateral slope is below this (about 0.3°) are not worth a
/// second pitch search: the feather stays unrolled.
const MIN_LATERAL_SLOPE: f32 = 0.005;

/// What the steps chose for one feather size.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct PoseChoice {
    /// The pose (full size; the caller sets the scale).
    pub(crate) pose: FeatherPose,
    /// Whether a pitch or roll limit bound.
    pub(crate) clamped: bool,
    /// Whether the feather needs more than the highest pitch to clear
    /// everything (before any fluffiness).
    pub(crate) too_steep: bool,
}

/// Runs the steps on a filled field, for the field's shape.
pub(crate) fn choose_pose(
    field: &mut HeightField,
    previous: FeatherPose,
    params: &AdjustParams,
    steps: AdjustSteps,
) -> PoseChoice {
    let (p_lo, p_hi) = (params.min_pitch.tan(), params.max_pitch.tan());
    let max_roll = params.max_roll.abs();
    let mut clamped = false;
    // Step 1 (Full only): pitch with the feather unrolled.
    let step1 = match steps {
        AdjustSteps::Full => {
            field.combine_heights(params, 0.0);
            let m = field.min_pitch_slope(0.0, p_lo, p_hi);
            clamped |= m.bound;
            Some(m)
        }
        AdjustSteps::FinePitchOnly => None,
    };
    // Step 2: roll towards balanced free volume under the vanes, as far as
    // that lowers the feather without lifting any part (Full), or keep the
    // previous roll (FinePitchOnly).
    let roll = match step1 {
        Some(m) => {
            let (q, p2, bound2) = field.settling_lateral_slope(m.p, m.binding, max_roll.tan());
            clamped |= bound2;
            (q / (1.0 + p2 * p2).sqrt()).atan()
        }
        None => previous.roll,
    };
    let roll = if roll.is_finite() { roll } else { 0.0 };
    if roll.abs() > max_roll {
        clamped = true;
    }
    let mut roll = roll.clamp(-max_roll, max_roll);
    // Step 3: fine pitch with the roll fixed (with the collision allowance).
    // Unrolled and with nothing to sink into, it is step 1 again.
    let allowance = params.collision_allowance.max(0.0) * field.shape.thickness;
    let mut m3 = match step1 {
        Some(m) if roll == 0.0 && allowance == 0.0 => m,
        _ => {
            field.combine_heights(params, allowance);
            field.min_pitch_slope(roll, p_lo, p_hi)
        }
    };
    // Re-check of step 2: step 2 worked from an estimate; if the re-pitched
    // feather lifts a vane corner above the unrolled one after all, halve
    // the roll (twice at most), else drop it.
    if let Some(m1) = step1 {
        let unrolled = field.highest_corner(m1.p, 0.0);
        let mut tries = 0;
        while roll != 0.0 && field.highest_corner(m3.p, roll) > unrolled {
            tries += 1;
            roll = if tries > 2 { 0.0 } else { 0.5 * roll };
            m3 = field.min_pitch_slope(roll, p_lo, p_hi);
        }
    }
    clamped |= m3.bound;
    let p3 = m3.p;
    let pitch = p3.atan() + params.fluffiness.max(0.0);
    if pitch > params.max_pitch {
        clamped = true;
    }
    let pitch = pitch.clamp(params.min_pitch, params.max_pitch);
    PoseChoice { pose: FeatherPose::new(pitch, roll), clamped, too_steep: m3.steep }
}

impl HeightField {
    /// Fills `need`: per cell the height the feather must clear, the higher
    /// of the body (plus the clearance angle, taken at the cell's near edge) and the obstacle tops (plus the
    /// clearance, minus `allowance`). Cells with nothing get `EMPTY` (−∞),
    /// which no pitch violates.
    pub(crate) fn combine_heights(&mut self, params: &AdjustParams, allowance: f32) {
        let floor = self.floor;
        let body_slope = params.body_clearance_angle.max(0.0).tan();
        let obstacle_lift = params.clearance.max(0.0) * self.shape.thickness - allowance;
        // Unchanged layers (the same fill judged again, or a shorter size
        // on it) combine to the same heights.
        let key = (body_slope, obstacle_lift);
        if self.need_for.is_some_and(|k| k.0.to_bits() == key.0.to_bits() && k.1.to_bits() == key.1.to_bits()) {
            return;
        }
        self.need_for = Some(key);
        let u = self.u;
        // The clearance angle is measured from the cell's near edge (not
        // before `clearance_from`), not from the distance the steps judge
        // at: judging farther out must only ever relax a requirement, and
        // where the skin falls away (a negative height) a farther distance
        // would add clearance instead.
        let (far, from, dx) = (&self.col_far[..u], self.clearance_from, self.dx);
        for j in 0..self.v {
            let r = j * u..(j + 1) * u;
            let (need, body, obstacle) = (&mut self.need[r.clone()], &self.body[r.clone()], &self.obstacle[r]);
            for i in 0..u {
                // Both sides computed first, then selected: keeps it branch-free.
                let (b, o) = (body[i], obstacle[i]);
                let near = max_f(far[i] - dx, from);
                let (b_need, o_need) = (b + near * body_slope, o + obstacle_lift);
                let b_need = if b > floor { b_need } else { EMPTY };
                let o_need = if o > floor { o_need } else { EMPTY };
                need[i] = if b_need > o_need { b_need } else { o_need };
            }
        }
    }

    /// The shaft interval `[xa, xb]` of the flat kite where its half width
    /// is at least `a` (`a ≤ 0`: the whole shaft; empty as `xa > xb`).
    fn kite_interval(&self, a: f32) -> [f32; 2] {
        let s = &self.shape;
        let half = 0.5 * s.width;
        if a <= 0.0 {
            return [0.0, s.length];
        }
        if a > half {
            return [1.0, 0.0];
        }
        let corner = s.vane_split * s.length;
        [a / half * corner, s.length - a / half * (s.length - corner)]
    }

    /// Step 1 and 3: the smallest slope `p = tan α ≥ p_lo` at which the
    /// kite rolled by `roll` clears every cell it covers. `bound` is set
    /// when no pitch up to `p_hi` is clear (`p = p_hi` then) or when `p_lo`
    /// itself is clear (the lower limit binds).
    ///
    /// Per row, the covered columns form one run (the kite's shaft
    /// coordinate grows along the row). Near the root the kite is narrower
    /// than the row, so those cells are judged on the part of the row the
    /// kite can reach; beyond, the whole row is under the kite and the
    /// lateral term is the same for every cell, so a cell's requirement is
    /// `(h − lateral) / edge` and the row's largest one is found in a loop
    /// the compiler vectorises. Only cells whose requirement beats the
    /// running maximum are revisited for the tip-exit threshold.
    pub(crate) fn min_pitch_slope(&mut self, roll: f32, p_lo: f32, p_hi: f32) -> MinPitch {
        let (sb, cb) = roll.sin_cos();
        let tb = sb / cb;
        let (half_dx, half_dy) = (0.5 * self.dx, 0.5 * self.dy);
        // Row spans in kite coordinates, widened by half a cell across.
        for j in 0..self.v {
            let a = self.row_y[j].abs() / cb - half_dy / cb;
            self.row_span[j] = self.kite_interval(a);
        }
        let half_width_cb = 0.5 * self.shape.width * cb;
        let rise_cb = 0.5 * self.shape.width / (self.shape.vane_split * self.shape.length) * cb;
        let (u, first, inv_dx) = (self.u, self.first_col, 1.0 / self.dx);
        let mut p = p_lo;
        let mut binding = None;
        for jump in 0..MAX_JUMPS {
            let sec = (1.0 + p * p).sqrt();
            let q = tb * sec;
            // Half a cell in kite shaft coordinates.
            let mx = half_dx * sec + (sb * p).abs() * half_dy / cb;
            let mut need = p;
            let mut need_cell = None;
            for j in 0..self.v {
                let [xa, xb] = self.row_span[j];
                if xa > xb {
                    continue;
                }
                let (xa, xb) = (xa - mx, xb + mx);
                let y = self.row_y[j];
                let k = y / cb * sb;
                // Covered columns: x0 = x·sec + k·p within [xa, xb].
                let col = |x0: f32| ((x0 - k * p) / sec) * inv_dx - 0.5;
                let i_lo = ceil_i32(col(xa)).max(first as i32);
                let i_hi = floor_i32(col(xb)).min(u as i32 - 1);
                if i_lo > i_hi {
                    continue;
                }
                let (i_lo, i_hi) = (i_lo as usize, i_hi as usize);
                // From i_full on the kite spans the whole row.
                let y_out = y.abs() + half_dy;
                let shear_rise = (sb * p).abs() * y_out / cb * rise_cb;
                let i_full = if half_width_cb < y_out {
                    i_hi + 1
                } else {
                    let far = (y_out - shear_rise) / (sec * rise_cb);
                    (i_lo..=i_hi).find(|&i| self.col_far[i] >= far).unwrap_or(i_hi + 1)
                };
                let row = j * u;
                let ctx = CellContext { p, q, k, xb, y, half_dy, sec, rise_cb, shear_rise, half_width_cb };
                for i in i_lo..i_full.min(i_hi + 1) {
                    if let Some((t, p_req)) = self.clipped_cell_threshold(&ctx, i, row + i, need) {
                        need = t;
                        need_cell = Some(Binding { cell: (row + i) as u32, clears: t == p_req });
                    }
                }
                if i_full > i_hi {
                    continue;
                }
                let lateral = min_f(q * (y - half_dy), q * (y + half_dy));
                let run = i_full..i_hi + 1;
                let best = max_requirement(
                    &self.need[row + run.start..row + run.end],
                    &self.inv_near[run.clone()],
                    &self.inv_far[run.clone()],
                    lateral,
                );
                if best <= need {
                    continue;
                }
                for i in run {
                    let n = self.need[row + i] - lateral;
                    let p_req = n * if n > 0.0 { self.inv_near[i] } else { self.inv_far[i] };
                    if p_req > need {
                        let t = cell_threshold(p, p_req, self.col_x[i], k, xb);
                        if t > need {
                            need = t;
                            need_cell = Some(Binding { cell: (row + i) as u32, clears: t == p_req });
                        }
                    }
                }
            }
            if need <= p {
                return MinPitch { p, bound: jump == 0, steep: false, binding };
            }
            if need > p_hi {
                return MinPitch { p: p_hi, bound: true, steep: true, binding: None };
            }
            binding = need_cell;
            p = need.max(p + 1e-6 * (1.0 + p.abs()));
        }
        MinPitch { p: p.min(p_hi), bound: true, steep: true, binding: None }
    }

    /// The requirement `p_req` of a cell near the root, where the kite is
    /// narrower than the cell's row: the lowest point of the kite over the
    /// cell lies on the part of the row within the kite's widest
    /// half-width over the cell's shaft range. `None` when the kite misses
    /// the cell or the cell is empty.
    #[inline]
    fn clipped_requirement(&self, c: &CellContext, i: usize, cell: usize) -> Option<(f32, f32)> {
        let h = self.need[cell];
        let reach = min_f(self.col_far[i] * c.sec * c.rise_cb + c.shear_rise, c.half_width_cb);
        let (y_lo, y_hi) = (max_f(c.y - c.half_dy, -reach), min_f(c.y + c.half_dy, reach));
        if y_lo > y_hi || h == EMPTY {
            return None;
        }
        let lateral = min_f(c.q * y_lo, c.q * y_hi);
        let n = h - lateral;
        Some((n * if n > 0.0 { self.inv_near[i] } else { self.inv_far[i] }, lateral))
    }

    /// The threshold of a clipped cell and its requirement, if the
    /// threshold beats `need`.
    #[inline]
    fn clipped_cell_threshold(&self, c: &CellContext, i: usize, cell: usize, need: f32) -> Option<(f32, f32)> {
        let (p_req, _) = self.clipped_requirement(c, i, cell)?;
        if p_req <= need {
            return None;
        }
        let t = cell_threshold(c.p, p_req, self.col_x[i], c.k, c.xb);
        (t > need).then_some((t, p_req))
    }

    /// Height above the tangent plane of the higher vane corner at pitch
    /// slope `p` and roll `roll`.
    pub(crate) fn highest_corner(&self, p: f32, roll: f32) -> f32 {
        let pose = FeatherPose::new(p.atan(), roll);
        let [_, _, left, right] = self.shape.kite_corners().map(|c| pose.apply_local(c));
        left.z.max(right.z)
    }

    /// The lateral slope `q` that balances the free volume under the two
    /// vanes of the unrolled feather at slope `p` (free height per covered
    /// cell, capped at half the width). The +y vane's volume grows with `q`
    /// and the −y vane's shrinks, so the balance is linear in `q`.
    pub(crate) fn balancing_lateral_slope(&self, p: f32) -> f32 {
        let sec = (1.0 + p * p).sqrt();
        let cap = FREE_HEIGHT_CAP_PER_WIDTH * self.shape.width;
        let (mut free_pos, mut free_neg, mut arm_pos, mut arm_neg) = (0.0f32, 0.0f32, 0.0f32, 0.0f32);
        for j in 0..self.v {
            let y = self.row_y[j];
            let [xa, xb] = self.kite_interval(y.abs());
            let Some(run) = self.covered_columns(xa, xb, sec, 0) else { continue };
            let cells = j * self.u + run.start..j * self.u + run.end;
            let mut free = 0.0f32;
            for ((&x, &b), &o) in
                self.col_x[run.clone()].iter().zip(&self.body[cells.clone()]).zip(&self.obstacle[cells])
            {
                let top = if b > o { b } else { o };
                let f = x * p - top;
                free += if f < 0.0 {
                    0.0
                } else if f > cap {
                    cap
                } else {
                    f
                };
            }
            let arm = y.abs() * run.len() as f32;
            if y > 0.0 {
                free_pos += free;
                arm_pos += arm;
            } else {
                free_neg += free;
                arm_neg += arm;
            }
        }
        let arm = arm_pos + arm_neg;
        if arm <= 0.0 || arm.is_nan() {
            return 0.0;
        }
        (free_neg - free_pos) / arm
    }

    /// The columns (from `first` on) whose centres' shaft coordinate
    /// `x·sec` lies in `[xa, xb]`, or `None`.
    #[inline]
    fn covered_columns(&self, xa: f32, xb: f32, sec: f32, first: usize) -> Option<std::ops::Range<usize>> {
        if xa > xb {
            return None;
        }
        let inv = 1.0 / (sec * self.dx);
        let lo = ceil_i32(xa * inv - 0.5).max(first as i32);
        let hi = floor_i32(xb * inv - 0.5).min(self.u as i32 - 1);
        (lo <= hi).then(|| lo as usize..hi as usize + 1)
    }

    /// Step 2. Rolling tips one vane up and the other down. The roll is
    /// chosen to balance the free volume under the two vanes, but only as
    /// far as the rolled feather, re-pitched, lies nowhere above the
    /// unrolled one: the feather pivots down onto its free side and never
    /// lifts a vane corner above where step 1 put it.
    ///
    /// Why: a raised corner is a step every later neighbour on that side
    /// must climb (followers lie over a feather's root region and corners),
    /// and the coat's pitch escalates (BENCHMARKS.md, "Measurements behind
    /// the code's constants"). The vane corner has the largest
    /// lateral-to-shaft ratio of any covered point, so rolls stay small
    /// (tenths of a degree on flat skin, more on saddles and at vane edges
    /// where cell rounding binds) and the step mostly refines.
    ///
    /// The rolled feather needs pitch slope `f(q)` at lateral slope `q`
    /// (the upper envelope of one constraint per covered cell, each linear
    /// in `q` on either side of 0); its kite lies under the unrolled one iff
    /// its corners do: `s·L·f(q) + W/2·|q| ≤ s·L·p1`. On the side of 0
    /// where the volume-balancing roll lies every constraint is linear, so
    /// the allowed rolls there form an interval `[0, q_max]` found in one
    /// pass, and the balancing roll is clamped into it.
    ///
    /// Returns `(q, p, bound)`: the lateral slope, the pitch slope it needs
    /// (an upper estimate from the step-1 coverage, used only to turn `q`
    /// into an angle) and whether `|q|` reached `q_lim`.
    pub(crate) fn settling_lateral_slope(&mut self, p1: f32, binding: Option<Binding>, q_lim: f32) -> (f32, f32, bool) {
        let corner = 0.5 * self.shape.width / (self.shape.vane_split * self.shape.length);
        let q_bal = self.balancing_lateral_slope(p1).clamp(-q_lim, q_lim);
        if q_bal.abs() < MIN_LATERAL_SLOPE {
            return (0.0, p1, false);
        }
        // The cell that set p1 decides whether rolling towards q_bal can
        // lower the feather without lifting a corner: it must lower that
        // cell's requirement faster than it lifts the corner.
        let positive = q_bal > 0.0;
        if let Some(b) = binding.filter(|b| b.clears) {
            let (j, i) = (b.cell as usize / self.u, b.cell as usize % self.u);
            if let Some(line) = self.roll_line(i, j, p1) {
                let slope = if positive { line.c_pos + corner } else { -(line.c_neg - corner) };
                if slope >= 0.0 {
                    return (0.0, p1, false);
                }
            }
        }
        let q = q_bal.signum() * self.roll_limit(p1, positive, corner).min(q_bal.abs());
        let q = if q.abs() < MIN_LATERAL_SLOPE { 0.0 } else { q };
        // Within the limit, f(q) ≤ p1 − corner·|q|: the pitch estimate.
        let p = p1 - corner * q.abs();
        (q, p, q.abs() >= q_lim * (1.0 - 1e-6))
    }

    /// The largest `|q|` on the side of 0 given by `positive` at which the
    /// rolled feather, re-pitched, still lies nowhere above the unrolled
    /// one at slope `p`: each covered cell's constraint `a + c·q` plus the
    /// corner term must stay within `p`. (A cell already above `p` at
    /// `q = 0`, which step 1 should rule out up to rounding, forbids any
    /// roll.)
    fn roll_limit(&self, p: f32, positive: bool, corner: f32) -> f32 {
        let (half_dx, half_dy) = (0.5 * self.dx, 0.5 * self.dy);
        let half_width = 0.5 * self.shape.width;
        let rise = half_width / (self.shape.vane_split * self.shape.length);
        let sec = (1.0 + p * p).sqrt();
        let mx = half_dx * sec;
        let slack = 1e-6 * (1.0 + p.abs());
        let mut limit = f32::INFINITY;
        for j in 0..self.v {
            let y = self.row_y[j];
            let [xa, xb] = self.kite_interval(y.abs() - half_dy);
            let Some(run) = self.covered_columns(xa - mx, xb + mx, sec, self.first_col) else { continue };
            let y_out = y.abs() + half_dy;
            for i in run {
                let h = self.need[j * self.u + i];
                if h == EMPTY {
                    continue;
                }
                let reach = min_f(self.col_far[i] * sec * rise, half_width);
                let (y_lo, y_hi) = (max_f(y - half_dy, -reach), min_f(y + half_dy, reach));
                if reach < y_out && y_lo > y_hi {
                    continue;
                }
                let inv = if h > 0.0 { self.inv_near[i] } else { self.inv_far[i] };
                let a = h * inv;
                if a > p + slack {
                    return 0.0;
                }
                // Growth of this cell's constraint per unit |q|.
                let d = if positive { corner - y_lo * inv } else { corner + y_hi * inv };
                if d > 0.0 {
                    let q = max_f(p - a, 0.0) / d;
                    limit = if q < limit { q } else { limit };
                }
            }
        }
        limit
    }

    /// The pitch constraint of cell (i, j) as a function of the lateral
    /// slope, if the unrolled feather at slope `p` covers it and it holds
    /// something.
    #[inline]
    fn roll_line(&self, i: usize, j: usize, p: f32) -> Option<RollLine> {
        let h = self.need[j * self.u + i];
        if h == EMPTY || i < self.first_col {
            return None;
        }
        let (half_dx, half_dy) = (0.5 * self.dx, 0.5 * self.dy);
        let half_width = 0.5 * self.shape.width;
        let rise = half_width / (self.shape.vane_split * self.shape.length);
        let sec = (1.0 + p * p).sqrt();
        let mx = half_dx * sec;
        let y = self.row_y[j];
        let [xa, xb] = self.kite_interval(y.abs() - half_dy);
        let x0 = self.col_x[i] * sec;
        if xa > xb || x0 < xa - mx || x0 > xb + mx {
            return None;
        }
        let reach = min_f(self.col_far[i] * sec * rise, half_width);
        let (y_lo, y_hi) = (max_f(y - half_dy, -reach), min_f(y + half_dy, reach));
        if y_lo > y_hi {
            return None;
        }
        let inv = if h > 0.0 { self.inv_near[i] } else { self.inv_far[i] };
        Some(RollLine { a: h * inv, c_pos: -y_lo * inv, c_neg: -y_hi * inv })
    }
}

/// `need` of a cell with nothing in it: no pitch violates it.
pub(crate) const EMPTY: f32 = f32::NEG_INFINITY;

/// What the cells of one row share during one pass of the pitch search.
struct CellContext {
    p: f32,
    q: f32,
    k: f32,
    xb: f32,
    y: f32,
    half_dy: f32,
    sec: f32,
    rise_cb: f32,
    shear_rise: f32,
    half_width_cb: f32,
}

/// The largest `(h − lateral)/edge` over a run of cells (edge: near edge
/// when positive, far edge otherwise); empty cells give −∞. Plain
/// comparisons so that it vectorises.
#[inline]
fn max_requirement(need: &[f32], inv_near: &[f32], inv_far: &[f32], lateral: f32) -> f32 {
    let mut best = f32::NEG_INFINITY;
    for ((&h, &a), &b) in need.iter().zip(inv_near).zip(inv_far) {
        let n = h - lateral;
        let r = n * if n > 0.0 { a } else { b };
        if r > best {
            best = r;
        }
    }
    best
}

/// The pitch a covered cell demands as a function of the lateral slope `q`
/// of the rolled feather: `p ≥ a + c·q`, with `c = c_pos` for `q ≥ 0` and
/// `c_neg` for `q < 0` (the cell's lowest corner under the feather changes
/// side with the sign of the roll).
#[derive(Clone, Copy, Debug, PartialEq)]
struct RollLine {
    a: f32,
    c_pos: f32,
    c_neg: f32,
}

/// The result of a minimal-pitch search.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct MinPitch {
    /// The pitch slope `tan α`.
    pub(crate) p: f32,
    /// Whether a pitch limit bound.
    pub(crate) bound: bool,
    /// Whether no pitch up to the highest one is clear.
    pub(crate) steep: bool,
    /// The cell that set the final pitch, if one did.
    pub(crate) binding: Option<Binding>,
}

/// The cell that set a minimal pitch.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct Binding {
    /// Its index `j·u + i`.
    pub(crate) cell: u32,
    /// Whether the feather clears it (rather than its tip leaving it).
    pub(crate) clears: bool,
}

/// The slope at which a violated cell stops being violated: `p_req` (the
/// slope that clears it), or earlier if the tip stops covering it first
/// (shaft coordinate `x·sec α + k·tan α` passing `xb`). Never below `p`.
#[inline]
fn cell_threshold(p: f32, p_req: f32, x: f32, k: f32, xb: f32) -> f32 {
    if p_req <= p {
        return p_req;
    }
    let x0_at_req = x * (1.0 + p_req * p_req).sqrt() + k * p_req;
    if x0_at_req <= xb || x * x <= k * k {
        return p_req;
    }
    // Larger root of (x² − k²) p² + 2 xb k p + (x² − xb²) = 0.
    let disc = xb * xb + k * k - x * x;
    if disc < 0.0 {
        return p_req;
    }
    let exit = (-xb * k + x * disc.sqrt()) / (x * x - k * k);
    exit.clamp(p, p_req)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn threshold_of_a_cell_leaving_the_tip() {
        // x = 3, kite ends at xb = 3.2: the tip leaves when 3·sec α = 3.2.
        let exit = cell_threshold(0.0, 10.0, 3.0, 0.0, 3.2);
        assert!((3.0 * (1.0 + exit * exit).sqrt() - 3.2).abs() < 1e-4);
        assert_eq!(cell_threshold(0.0, 0.1, 3.0, 0.0, 3.2), 0.1);
    }
}
