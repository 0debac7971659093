//! Which obstacle candidates a feather can actually rest on this frame.
//!
//! The obstacle candidates of feather i are every root within reach
//! (`|r_i − r_j| ≤ L_i + L_j`, about a hundred on a closed coat), but only
//! the few whose feathers lie over i's height-field footprint matter: the
//! adjustment rasterises an obstacle only when its triangles' box meets the
//! footprint's rectangle `[0, L + dx] × [−(W/2 + dy), W/2 + dy]` in i's
//! frame (any height). Feather j lies within a sphere (centre, radius)
//! around its current triangles; when the sphere's shadow on i's tangent
//! plane misses a slightly larger rectangle, j's triangles cannot touch the
//! footprint.
//!
//! A frame passes the adjustment only the candidates that touch or come
//! within a pose margin of touching ([`Contacts::obstacle_rows`]): the
//! margin covers a pitch or roll change of up to `POSE_MARGIN` radians of
//! the candidate during the frame. That list serves the adjustment both as
//! obstacles and for propagation (a feather that moved past θs pulls in the
//! feathers it lies on, not every feather within reach). A candidate that
//! was readjusted by more than the margin may end up over a footprint it
//! was not listed for; [`Contacts::missed`] finds those afterwards so that
//! the frame can readjust the feathers concerned with their full lists.

use crate::adjustment::AdjustParams;
use crate::csr::CsrView;
use crate::feather::{FeatherPose, FeatherShape, feather_triangles};
use crate::geometry::RootFrame;
use crate::progress::{Phase, Progress};
use glam::Vec3;
use rayon::prelude::*;

/// Pitch or roll change (radians) of a candidate during a frame that its
/// listing covers in advance.
const POSE_MARGIN: f32 = 0.2;
/// Relative slack of the footprint rectangle over the height field's.
const FOOTPRINT_SLACK: f32 = 0.1;
/// Candidate entries per parallel work item.
const ENTRY_CHUNK: usize = 4096;
/// Blocks of rows [`Contacts::obstacle_rows`] fills in parallel.
const ROW_BLOCKS: usize = 64;

/// A conservative rectangle around a feather's height-field footprint, in
/// its frame (x along the shaft, y across).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Footprint {
    x_lo: f32,
    x_hi: f32,
    y_half: f32,
}

impl Footprint {
    /// The rectangle of a feather of `shape` at the resolution of `params`:
    /// the field's `[0, L + dx] × ±(W/2 + dy)` grown by a tenth of the
    /// length and width on every side.
    pub fn of(shape: &FeatherShape, params: &AdjustParams) -> Self {
        let (l, w) = (shape.length.max(0.0), shape.width.max(0.0));
        let dx = l / (params.height_field_u.max(2) - 1) as f32;
        let dy = if params.height_field_v > 2 { w / (params.height_field_v - 2) as f32 } else { f32::INFINITY };
        Self {
            x_lo: -FOOTPRINT_SLACK * l,
            x_hi: l + dx + FOOTPRINT_SLACK * l,
            y_half: 0.5 * w + dy + FOOTPRINT_SLACK * w,
        }
    }

    /// Squared distance, in `frame`'s tangent plane, from the shadow of
    /// `point` to the rectangle (0 inside).
    #[inline]
    pub fn distance2(&self, frame: &RootFrame, point: Vec3) -> f32 {
        Shadow::of(self, frame).distance2(point)
    }

    /// Whether a sphere may reach over the rectangle.
    #[inline]
    pub fn reached_by(&self, frame: &RootFrame, sphere: Sphere) -> bool {
        self.distance2(frame, sphere.centre) <= sphere.radius * sphere.radius
    }
}

/// A footprint rectangle placed in world space at a frame: the tangent
/// and binormal of the frame with the rectangle's centre and half sizes
/// folded in, so that a point's distance to it costs two dot products.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
struct Shadow {
    tangent: Vec3,
    binormal: Vec3,
    x_centre: f32,
    y_centre: f32,
    x_half: f32,
    y_half: f32,
}

impl Shadow {
    fn of(footprint: &Footprint, frame: &RootFrame) -> Self {
        let x_mid = 0.5 * (footprint.x_lo + footprint.x_hi);
        Self {
            tangent: frame.tangent,
            binormal: frame.binormal,
            x_centre: frame.tangent.dot(frame.position) + x_mid,
            y_centre: frame.binormal.dot(frame.position),
            x_half: 0.5 * (footprint.x_hi - footprint.x_lo),
            y_half: footprint.y_half,
        }
    }

    /// As [`Footprint::distance2`].
    #[inline]
    fn distance2(&self, point: Vec3) -> f32 {
        let dx = ((self.tangent.dot(point) - self.x_centre).abs() - self.x_half).max(0.0);
        let dy = ((self.binormal.dot(point) - self.y_centre).abs() - self.y_half).max(0.0);
        dx * dx + dy * dy
    }
}

/// Every feather at one pose: its root frame, shape and pose.
#[derive(Clone, Copy, Debug)]
pub struct Posed<'a> {
    /// Each feather's root frame.
    pub frames: &'a [RootFrame],
    /// Each feather's dimensions.
    pub shapes: &'a [FeatherShape],
    /// Each feather's pose.
    pub poses: &'a [FeatherPose],
}

/// A feather's sphere centre and squared radii without and with the pose
/// margin, packed for the candidate loop.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
struct Reach2 {
    centre: Vec3,
    touch: f32,
    near: f32,
}

/// A sphere around a feather's triangles.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Sphere {
    /// Midpoint of the shaft.
    pub centre: Vec3,
    /// Distance to the farthest corner.
    pub radius: f32,
}

impl Sphere {
    /// The sphere of the feather at `pose`.
    pub fn of(frame: &RootFrame, shape: &FeatherShape, pose: FeatherPose) -> Self {
        let t = feather_triangles(frame, shape, pose);
        let centre = (t[0][0] + t[0][1]) * 0.5;
        let radius = t.iter().flatten().map(|p| p.distance(centre)).fold(0.0f32, f32::max);
        Self { centre, radius }
    }

    /// The sphere grown to cover a pitch or roll change of [`POSE_MARGIN`]:
    /// no point of the feather is farther than `L + W/2` from its root.
    fn with_pose_margin(self, shape: &FeatherShape) -> Self {
        Self { centre: self.centre, radius: self.radius + POSE_MARGIN * (shape.length + 0.5 * shape.width) }
    }
}

/// Per-frame contact data over the obstacle candidates (CSR rows, one entry
/// per candidate pair `(i, j)`). Scratch of the frame update.
#[derive(Clone, Debug, Default)]
pub struct Contacts {
    footprints: Vec<Footprint>,
    shadows: Vec<Shadow>,
    spheres: Vec<Sphere>,
    reach2: Vec<Reach2>,
    touch: Vec<u8>,
    offsets: Vec<u32>,
    indices: Vec<u32>,
    missed: Vec<bool>,
}

/// `touch` values of an entry `(i, j)`: j's sphere misses i's footprint
/// even with the pose margin (0), reaches it only with the margin (1), or
/// reaches it (2); or not worked out yet (3), as for a candidate that came
/// later than i in the order [`Contacts::update`] was given.
const APART: u8 = 0;
const TOUCHING: u8 = 2;
const UNKNOWN: u8 = 3;

impl Contacts {
    /// Room for frames of up to `entries` candidate entries (the
    /// candidate rows' capacity), so that a frame whose rows hold more than
    /// any before allocates nothing here.
    pub fn reserve_entries(&mut self, entries: usize) {
        self.touch.reserve(entries.saturating_sub(self.touch.len()));
        self.indices.reserve(entries.saturating_sub(self.indices.len()));
    }

    /// Every feather's footprint and sphere at its current pose, and for
    /// every candidate entry `(i, j)` with j earlier than i by `rank`
    /// whether j's sphere reaches i's footprint, with or without the pose
    /// margin. Only an earlier candidate can be an obstacle, so the other
    /// half of the entries waits until an order makes them earlier
    /// ([`obstacle_rows`](Self::obstacle_rows)).
    /// Polls `progress` as it goes: once it says stop, the rest is left
    /// as it was (the caller's next check fails and the frame is dropped).
    pub fn update(
        &mut self,
        feathers: Posed<'_>,
        params: &AdjustParams,
        candidates: CsrView<'_, u32>,
        rank: &[u32],
        progress: &Progress,
    ) {
        let Posed { frames, shapes, poses } = feathers;
        let (offsets, indices) = (candidates.offsets(), candidates.items());
        let n = frames.len();
        if self.footprints.len() != n {
            self.footprints.clear();
            self.footprints.extend(shapes.iter().map(|s| Footprint::of(s, params)));
        }
        self.spheres.resize(n, Sphere::default());
        self.reach2.resize(n, Reach2::default());
        self.shadows.resize(n, Shadow::default());
        let footprints = &self.footprints;
        self.spheres
            .par_iter_mut()
            .zip(self.reach2.par_iter_mut().zip(self.shadows.par_iter_mut()))
            .enumerate()
            .with_min_len(256)
            .for_each(|(i, (s, (r2, shadow)))| {
                if !progress.poll(Phase::Ordering, 0.25, i) {
                    return;
                }
                *s = Sphere::of(&frames[i], &shapes[i], poses[i]);
                let grown = s.with_pose_margin(&shapes[i]).radius;
                *r2 = Reach2 { centre: s.centre, touch: s.radius * s.radius, near: grown * grown };
                *shadow = Shadow::of(&footprints[i], &frames[i]);
            });
        let (shadows, reach2) = (&self.shadows, &self.reach2);
        self.touch.resize(indices.len(), APART);
        self.touch.par_chunks_mut(ENTRY_CHUNK).enumerate().for_each(|(chunk, out)| {
            if progress.check(Phase::Ordering, 0.28).is_err() {
                return;
            }
            let base = chunk * ENTRY_CHUNK;
            for_each_row_part(offsets, base..base + out.len(), |i, part| {
                let rank_i = rank[i];
                for (t, &j) in out[part.start - base..part.end - base].iter_mut().zip(&indices[part]) {
                    *t = if rank[j as usize] < rank_i { touch(shadows, reach2, i as u32, j) } else { UNKNOWN };
                }
            });
        });
    }

    /// Feather `i`'s footprint.
    pub fn footprint(&self, i: usize) -> &Footprint {
        &self.footprints[i]
    }

    /// Feather `j`'s sphere at the pose it had when [`update`](Self::update) ran.
    pub fn sphere(&self, j: usize) -> Sphere {
        self.spheres[j]
    }

    /// Whether candidate entry `e` (j in row i) touches i's footprint;
    /// answered for a j earlier than i in the order given to
    /// [`update`](Self::update) (false otherwise).
    #[inline]
    pub fn touching(&self, e: usize) -> bool {
        self.touch[e] == TOUCHING
    }

    /// Fills the rows handed to the adjustment: the candidates of each
    /// feather that come earlier in the order (`rank`) and touch its
    /// footprint or come within the pose margin of it.
    pub fn obstacle_rows(&mut self, candidates: CsrView<'_, u32>, rank: &[u32]) -> CsrView<'_, u32> {
        let (offsets, indices) = (candidates.offsets(), candidates.items());
        let n = candidates.rows();
        self.offsets.clear();
        self.offsets.resize(n + 1, 0);
        if n == 0 {
            return CsrView::new(&self.offsets, &[]);
        }
        // Sized for every candidate, so the buffer never creeps up with the
        // poses.
        self.indices.resize(indices.len(), 0);
        let (shadows, reach2) = (&self.shadows, &self.reach2);
        // Blocks of rows in parallel, each with its entries' states, its
        // rows' lengths and, to write its kept candidates into, the place
        // its candidates hold; then the blocks close up, in order.
        let (mut states, mut out, mut lengths) =
            (&mut self.touch[..indices.len()], &mut self.indices[..], &mut self.offsets[1..]);
        let blocks: [_; ROW_BLOCKS] = std::array::from_fn(|b| {
            let rows = n * b / ROW_BLOCKS..n * (b + 1) / ROW_BLOCKS;
            let size = (offsets[rows.end] - offsets[rows.start]) as usize;
            let (s, s_rest) = std::mem::take(&mut states).split_at_mut(size);
            let (o, o_rest) = std::mem::take(&mut out).split_at_mut(size);
            let (l, l_rest) = std::mem::take(&mut lengths).split_at_mut(rows.len());
            (states, out, lengths) = (s_rest, o_rest, l_rest);
            (rows, s, o, l)
        });
        blocks.into_par_iter().for_each(|(rows, states, out, lengths)| {
            let base = offsets[rows.start] as usize;
            let mut len = 0;
            for (i, length) in rows.zip(lengths.iter_mut()) {
                let rank_i = rank[i];
                let row = candidates.span(i);
                let before = len;
                for (&j, t) in indices[row.clone()].iter().zip(&mut states[row.start - base..row.end - base]) {
                    let earlier = rank[j as usize] < rank_i;
                    if (*t == UNKNOWN) & earlier {
                        // Earlier now, later when the contacts were worked
                        // out: a reversal or a new pair of this frame (rare).
                        *t = touch(shadows, reach2, i as u32, j);
                    }
                    // Written without branching on the (unpredictable) tests.
                    out[len] = j;
                    len += usize::from((*t != APART) & earlier);
                }
                *length = (len - before) as u32;
            }
        });
        for i in 0..n {
            self.offsets[i + 1] += self.offsets[i];
        }
        for b in 0..ROW_BLOCKS {
            let rows = n * b / ROW_BLOCKS..n * (b + 1) / ROW_BLOCKS;
            let (from, to) = (offsets[rows.start] as usize, self.offsets[rows.start] as usize);
            let len = (self.offsets[rows.end] as usize) - to;
            // Never past the candidates of a block yet to close up.
            self.indices.copy_within(from..from + len, to);
        }
        let len = self.offsets[n] as usize;
        CsrView::new(&self.offsets, &self.indices[..len])
    }

    /// After an adjustment with [`obstacle_rows`](Self::obstacle_rows):
    /// marks the feathers i over whose footprint an earlier, readjusted
    /// candidate j now lies although the rows did not list j for i. Only a
    /// feather that left its sphere grown by the pose margin can do that
    /// (it turned by more than the margin). Returns how many were marked;
    /// [`missed_flags`](Self::missed_flags) holds them.
    pub fn missed(
        &mut self,
        feathers: Posed<'_>,
        candidates: CsrView<'_, u32>,
        rank: &[u32],
        adjusted: &[bool],
    ) -> usize {
        let Posed { frames, shapes, poses } = feathers;
        let n = frames.len();
        self.missed.clear();
        self.missed.resize(n, false);
        let mut count = 0;
        for j in (0..n).filter(|&j| adjusted[j]) {
            let now = Sphere::of(&frames[j], &shapes[j], poses[j]);
            let before = self.spheres[j].with_pose_margin(&shapes[j]);
            if now.centre.distance(before.centre) + now.radius <= before.radius {
                continue;
            }
            // The relation is symmetric: i is a candidate of j exactly when
            // j is one of i, so the entries (i, j) are found from row j.
            for &i in candidates.row(j) {
                let i = i as usize;
                if rank[i] <= rank[j] || self.missed[i] {
                    continue;
                }
                let row = candidates.span(i);
                let listed =
                    candidates.row(i).binary_search(&(j as u32)).is_ok_and(|k| self.touch[row.start + k] != APART);
                if !listed && self.footprints[i].reached_by(&frames[i], now) {
                    self.missed[i] = true;
                    count += 1;
                }
            }
        }
        count
    }

    /// The flags of the last [`missed`](Self::missed).
    pub fn missed_flags(&self) -> &[bool] {
        &self.missed
    }
}

/// Calls `f(i, part)` for every row `i` (of the CSR `offsets`) holding
/// entries of `entries`, in order, with `part` the entries of the row
/// that lie in `entries`.
fn for_each_row_part(
    offsets: &[u32],
    entries: std::ops::Range<usize>,
    mut f: impl FnMut(usize, std::ops::Range<usize>),
) {
    if entries.is_empty() {
        return;
    }
    // The last row starting at or before the first entry (rows before it
    // may be empty and start there too).
    let mut i = offsets.partition_point(|&o| o as usize <= entries.start) - 1;
    let mut at = entries.start;
    while at < entries.end {
        let end = (offsets[i + 1] as usize).min(entries.end);
        if end > at {
            f(i, at..end);
            at = end;
        }
        i += 1;
    }
}

/// The `touch` value of entry `(i, j)`: how j's sphere lies to i's footprint.
#[inline]
fn touch(shadows: &[Shadow], reach2: &[Reach2], i: u32, j: u32) -> u8 {
    let r = &reach2[j as usize];
    let d2 = shadows[i as usize].distance2(r.centre);
    u8::from(d2 <= r.touch) + u8::from(d2 <= r.near)
}

crate::memory::heap_size_of_fields!(Contacts { footprints, shadows, spheres, reach2, touch, offsets, indices, missed });

#[cfg(test)]
mod tests {
    use super::*;
    use crate::adjustment::HeightField;
    use crate::rng::Rng;

    /// Whatever the resolution, an obstacle whose sphere misses the
    /// footprint rectangle touches no cell of the adjustment's height field.
    #[test]
    fn a_sphere_off_the_footprint_leaves_the_height_field_alone() {
        let mut rng = Rng::new(3);
        let frame = RootFrame::from_normal_and_direction(Vec3::new(0.5, -0.2, 0.1), Vec3::Z, Vec3::X).unwrap();
        for (u, v) in [(32, 16), (2, 3), (8, 40), (64, 4)] {
            let params = AdjustParams { height_field_u: u, height_field_v: v, ..AdjustParams::default() };
            let shape = FeatherShape::for_spacing(1.0);
            let footprint = Footprint::of(&shape, &params);
            let mut field = HeightField::new(u, v);
            let mut checked = 0;
            for _ in 0..4000 {
                let at =
                    Vec3::new(rng.next_f32() * 16.0 - 6.0, rng.next_f32() * 12.0 - 6.0, rng.next_f32() * 4.0 - 2.0);
                let normal = Vec3::new(rng.next_f32() - 0.5, rng.next_f32() - 0.5, 1.0);
                let direction = Vec3::new(rng.next_f32() - 0.5, rng.next_f32() - 0.5, rng.next_f32() - 0.5);
                let Some(other) = RootFrame::from_normal_and_direction(at, normal, direction) else { continue };
                let pose = FeatherPose::new(rng.next_f32() * 1.4 - 0.3, rng.next_f32() * 1.2 - 0.6);
                let sphere = Sphere::of(&other, &shape, pose);
                if footprint.reached_by(&frame, sphere) {
                    continue;
                }
                field.reset(&shape, params.min_pitch);
                let touched = field.add_obstacle(&frame, &feather_triangles(&other, &shape, pose), shape.thickness);
                assert!(!touched, "an obstacle off the footprint touched the field at {u}×{v}");
                checked += 1;
            }
            assert!(checked > 1000);
        }
    }

    /// Entries worked out late (their candidate was later in the order
    /// `update` saw) give the rows an `update` with the final order gives.
    #[test]
    fn rows_do_not_depend_on_the_order_the_contacts_were_worked_out_in() {
        use crate::ordering::{NeighbourParams, Neighbourhoods};
        let mut rng = Rng::new(11);
        let (w, h) = (12, 9);
        let frames: Vec<RootFrame> = (0..w * h)
            .map(|k| {
                let at = Vec3::new((k % w) as f32 + 0.4 * rng.next_f32(), (k / w) as f32 + 0.4 * rng.next_f32(), 0.0);
                let normal = Vec3::new(0.2 * rng.next_f32(), 0.2 * rng.next_f32(), 1.0);
                RootFrame::from_normal_and_direction(at, normal, Vec3::new(1.0, 0.3 * rng.next_f32(), 0.0)).unwrap()
            })
            .collect();
        let n = frames.len();
        let shapes = vec![FeatherShape::for_spacing(1.0); n];
        let poses: Vec<FeatherPose> =
            (0..n).map(|_| FeatherPose::new(0.5 * rng.next_f32(), 0.2 * rng.next_f32() - 0.1)).collect();
        let reach: Vec<f32> = shapes.iter().map(|s| s.length).collect();
        let mut nb = Neighbourhoods::new();
        nb.rebuild(&frames, &reach, &NeighbourParams::default());
        let candidates = nb.obstacle_csr();
        let params = AdjustParams::default();
        // Two orders: by x, and by x with every other pair of neighbours swapped.
        let by_x: Vec<u32> = (0..n as u32).map(|i| (i % w as u32) * h as u32 + i / w as u32).collect();
        let swapped: Vec<u32> = by_x.iter().map(|&r| r ^ 1).collect();
        let rows = |first: &[u32], last: &[u32]| {
            let mut c = Contacts::default();
            let posed = Posed { frames: &frames, shapes: &shapes, poses: &poses };
            c.update(posed, &params, candidates, first, &Progress::none());
            let rows = c.obstacle_rows(candidates, last);
            (rows.offsets().to_vec(), rows.items().to_vec())
        };
        let late = rows(&by_x, &swapped);
        assert_eq!(late, rows(&swapped, &swapped));
        assert!(late.1.len() > n, "feathers have obstacles");
        assert_ne!(late, rows(&by_x, &by_x), "the orders differ in the rows they give");
    }

    #[test]
    fn the_pose_margin_covers_a_turn_of_the_candidate() {
        let shape = FeatherShape::for_spacing(1.0);
        let frame = RootFrame::from_normal_and_direction(Vec3::new(0.3, 0.4, 0.0), Vec3::Z, Vec3::X).unwrap();
        let grown = Sphere::of(&frame, &shape, FeatherPose::new(0.1, 0.0)).with_pose_margin(&shape);
        for (pitch, roll) in [(0.3, 0.0), (-0.1, 0.2), (0.28, -0.2)] {
            let turned = feather_triangles(&frame, &shape, FeatherPose::new(pitch, roll));
            assert!(turned.iter().flatten().all(|p| p.distance(grown.centre) <= grown.radius + 1e-5));
        }
    }
}
