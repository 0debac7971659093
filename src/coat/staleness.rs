//! How far each feather's surroundings have moved relative to it since it
//! was last adjusted: part of the coat's state, measured with the bound of
//! [`crate::animation::motion`] (the miss of one root's map at another root
//! plus the turn between their frames times a radius).
//!
//! [`Staleness`] measures, for each feather, how far what it rests on has
//! moved relative to it since the feather was last adjusted, by one of two
//! rules:
//! - summed (the paper's rule and legacy): the largest per-frame
//!   displacement over its current surroundings, summed frame by frame. By
//!   the triangle inequality the sum bounds how far anything it rests on
//!   moved relative to it, however slowly the motion crept in;
//! - net (incremental with exact checks): when the feather is adjusted, the
//!   placement of each of its surroundings j in its own frame is recorded
//!   (`F_iᵀ (r_j − r_i)` and `F_iᵀ F_j`); each frame, the same bound as
//!   above is taken between the recorded and the current placement (their
//!   map is the composition of every frame's `A` since, seen from i), so a
//!   back-and-forth cancels instead of counting twice. Surroundings that
//!   joined since (new nearest roots, obstacles that came over the
//!   footprint) are left to the exact checks, which test every feather
//!   whose surroundings moved at all.

use crate::error::{Error, ErrorKind, Result};
use crate::geometry::RootFrame;
use crate::snapshot::{Reader, Writer};
use glam::{Quat, Vec3};

/// Recorded placements per feather (the k nearest first, then obstacles in
/// index order; the rest are left to the exact checks like surroundings
/// that joined later). A footprint has the k = 10 nearest roots (the
/// default) and typically 30 to 60 earlier candidates over it: 32 slots
/// watch the nearest roots and most of those. Fewer watch less, so less
/// drift is seen (BENCHMARKS.md, "Measurements behind the code's
/// constants").
const PLACEMENT_SLOTS: usize = 32;
/// `counts` value of a feather adjusted since its placements were recorded.
const PENDING: u8 = u8::MAX;

/// Where one root (and its frame) lay in a feather's frame when the
/// feather was last adjusted, and at which distance from it its motion is
/// measured. 36 bytes: the turn is a quaternion kept as four floats (a
/// `Quat` would be aligned to 16 and take 48).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Placement {
    /// The other root, j.
    pub other: u32,
    /// `ρ`: the distance at which a turn of j is measured (module notes).
    pub radius: f32,
    /// `F_iᵀ (r_j − r_i)`.
    pub offset: Vec3,
    /// `F_iᵀ F_j` as a unit quaternion (x, y, z, w).
    pub turn: [f32; 4],
}

/// A root frame with its axes as a unit quaternion ([`orientation`]),
/// computed once per frame for every root.
#[derive(Clone, Copy, Debug)]
pub struct Oriented<'a> {
    /// The frame.
    pub frame: &'a RootFrame,
    /// Its axes `(õ, b, n)` as a rotation.
    pub orientation: Quat,
}

/// The rotation taking the world axes to a frame's `(õ, b, n)`.
pub fn orientation(frame: &RootFrame) -> Quat {
    Quat::from_mat3(&frame.axes())
}

impl Placement {
    /// Root j's (`there`) placement in frame i (`here`).
    #[inline]
    pub fn of(here: Oriented<'_>, other: u32, there: Oriented<'_>, radius: f32) -> Self {
        let (offset, turn) = relative_placement(here, there);
        Self { other, radius, offset, turn: turn.to_array() }
    }

    /// How far j moved relative to i since the placement was recorded
    /// (`miss + turn·ρ` of the module notes; the turn `2 sin(θ/2)` of the
    /// angle θ between the two rotations, from the quaternions' distance
    /// `d = 2 sin(θ/4)` as `d √(4 − d²)`, which keeps small turns exact).
    #[inline]
    pub fn moved(&self, here: Oriented<'_>, there: Oriented<'_>) -> f32 {
        let (offset, turn) = relative_placement(here, there);
        let recorded = Quat::from_array(self.turn);
        // q and −q are the same rotation: take the nearer.
        let d = if turn.dot(recorded) >= 0.0 { turn - recorded } else { turn + recorded }.length();
        let chord = d * (4.0 - d * d).max(0.0).sqrt();
        offset.distance(self.offset) + chord * self.radius
    }
}

/// `(F_iᵀ (r_j − r_i), F_iᵀ F_j)`, the second as a quaternion.
#[inline]
fn relative_placement(here: Oriented<'_>, there: Oriented<'_>) -> (Vec3, Quat) {
    let (f, d) = (here.frame, there.frame.position - here.frame.position);
    let offset = Vec3::new(f.tangent.dot(d), f.binormal.dot(d), f.normal.dot(d));
    (offset, here.orientation.conjugate() * there.orientation)
}

/// Per feather, how far its surroundings moved relative to it since it was
/// last adjusted (module notes). Part of the saved state: it decides which
/// feathers later frames readjust.
#[derive(Debug, Default, PartialEq)]
pub struct Staleness {
    /// This frame's motion by the rule in use.
    moved: Vec<f32>,
    /// The summed rule's sums.
    summed: Vec<f32>,
    /// Recorded placements per feather, or [`PENDING`].
    counts: Vec<u8>,
    /// `PLACEMENT_SLOTS` per feather.
    placements: Vec<Placement>,
}

impl Staleness {
    /// `n` freshly adjusted feathers, their placements still to record.
    pub fn reset(&mut self, n: usize) {
        self.moved.clear();
        self.moved.resize(n, 0.0);
        self.summed.clear();
        self.summed.resize(n, 0.0);
        self.counts.clear();
        self.counts.resize(n, PENDING);
        // The slots are filled by the first record: the modes that never
        // record (rebuild, which resets every frame, legacy, the paper's
        // rule) hold none.
        self.placements.clear();
    }

    /// Number of feathers.
    pub fn len(&self) -> usize {
        self.moved.len()
    }

    /// True when there are no feathers.
    pub fn is_empty(&self) -> bool {
        self.moved.is_empty()
    }

    /// How far each feather's surroundings moved since it was last adjusted.
    pub fn moved(&self) -> &[f32] {
        &self.moved
    }

    /// Whether feather i's placements are still to be recorded.
    pub fn pending(&self, i: usize) -> bool {
        self.counts[i] == PENDING
    }

    /// Records feather i's placements (at most `PLACEMENT_SLOTS`; the rest
    /// count as unrecorded).
    pub fn record(&mut self, i: usize, placements: impl Iterator<Item = Placement>) {
        let n = self.counts.len();
        if self.placements.len() != n * PLACEMENT_SLOTS {
            self.placements.resize(n * PLACEMENT_SLOTS, Placement::default());
        }
        let slots = &mut self.placements[i * PLACEMENT_SLOTS..(i + 1) * PLACEMENT_SLOTS];
        let mut count = 0;
        for (slot, p) in slots.iter_mut().zip(placements) {
            *slot = p;
            count += 1;
        }
        self.counts[i] = count as u8;
    }

    /// Feather i's recorded placements (none while pending).
    #[inline]
    pub fn placements(&self, i: usize) -> &[Placement] {
        if self.pending(i) {
            return &[];
        }
        let start = i * PLACEMENT_SLOTS;
        &self.placements[start..start + self.counts[i] as usize]
    }

    /// Summed rule: adds this frame's displacement of each feather's
    /// surroundings and marks in `over` the feathers whose sum now exceeds
    /// their `limit`.
    pub fn add(&mut self, displacement: &[f32], limit: impl Fn(usize) -> f32, over: &mut [bool]) {
        let n = self.moved.len();
        assert!(displacement.len() == n && over.len() == n, "one entry per feather");
        for (i, ((m, sum), (&d, o))) in
            self.moved.iter_mut().zip(&mut self.summed).zip(displacement.iter().zip(over.iter_mut())).enumerate()
        {
            *sum += d;
            *m = *sum;
            *o = *m > limit(i);
        }
    }

    /// Net rule: takes this frame's net motion of each feather's recorded
    /// surroundings and marks in `over` the feathers whose motion exceeds
    /// their `limit`.
    pub fn set_net(&mut self, net: &[f32], limit: impl Fn(usize) -> f32, over: &mut [bool]) {
        let n = self.moved.len();
        assert!(net.len() == n && over.len() == n, "one entry per feather");
        for (i, ((m, &d), o)) in self.moved.iter_mut().zip(net).zip(over.iter_mut()).enumerate() {
            *m = d;
            *o = d > limit(i);
        }
    }

    /// Feathers just adjusted start afresh; their placements are recorded
    /// at the start of the next frame.
    pub fn clear_adjusted(&mut self, adjusted: &[bool]) {
        for (i, _) in adjusted.iter().enumerate().filter(|(_, a)| **a) {
            self.moved[i] = 0.0;
            self.summed[i] = 0.0;
            self.counts[i] = PENDING;
        }
    }

    /// Appends the state to a blob: the last frame's motions and the summed
    /// rule's sums (two length-prefixed f32 slices), then per feather its count (u8, 255 = pending) and each
    /// recorded placement (other root u32, radius, offset xyz and the turn's
    /// quaternion xyzw, f32).
    pub fn write_state(&self, w: &mut Writer) {
        w.f32s(&self.moved);
        w.f32s(&self.summed);
        for i in 0..self.len() {
            w.u8(self.counts[i]);
            for p in self.placements(i) {
                w.u32(p.other);
                w.f32(p.radius);
                p.offset.to_array().iter().for_each(|&x| w.f32(x));
                p.turn.iter().for_each(|&x| w.f32(x));
            }
        }
    }

    /// Reads the state of `n` feathers written by
    /// [`write_state`](Self::write_state); refuses another count, a sum or
    /// value that is negative or not finite, or a placement naming no
    /// other root with `InvalidState`.
    pub fn read_state(r: &mut Reader<'_>, n: usize) -> Result<Self> {
        let (mut moved, mut summed) = (Vec::new(), Vec::new());
        r.f32s_into(&mut moved, Some(n))?;
        r.f32s_into(&mut summed, Some(n))?;
        if moved.iter().chain(&summed).any(|m| !(m.is_finite() && *m >= 0.0)) {
            return Err(invalid("a saved staleness is negative or not finite"));
        }
        let mut s = Self::default();
        s.reset(n);
        s.moved = moved;
        s.summed = summed;
        for i in 0..n {
            let count = r.u8()?;
            s.counts[i] = count;
            if count == PENDING {
                continue;
            }
            if count as usize > PLACEMENT_SLOTS {
                return Err(invalid("a saved feather has more placements than are kept"));
            }
            if s.placements.len() != n * PLACEMENT_SLOTS {
                s.placements.resize(n * PLACEMENT_SLOTS, Placement::default());
            }
            for slot in 0..count as usize {
                let other = r.u32()?;
                let radius = r.f32()?;
                let offset = Vec3::new(r.f32()?, r.f32()?, r.f32()?);
                let turn = [r.f32()?, r.f32()?, r.f32()?, r.f32()?];
                if other as usize >= n || other as usize == i {
                    return Err(invalid("a saved placement names an invalid root"));
                }
                if !(radius.is_finite() && radius >= 0.0 && offset.is_finite() && turn.iter().all(|t| t.is_finite())) {
                    return Err(invalid("a saved placement is negative or not finite"));
                }
                s.placements[i * PLACEMENT_SLOTS + slot] = Placement { other, radius, offset, turn };
            }
        }
        Ok(s)
    }
}

fn invalid(message: &str) -> Error {
    Error::new(ErrorKind::InvalidState, message)
}

crate::memory::clone_by_fields!(Staleness { moved, summed, counts, placements });
crate::memory::heap_size_of_fields!(Staleness { moved, summed, counts, placements });

#[cfg(test)]
mod tests {
    use super::*;
    use glam::Quat;

    fn frame(p: Vec3, n: Vec3, d: Vec3) -> RootFrame {
        RootFrame::from_normal_and_direction(p, n, d).unwrap()
    }

    #[test]
    fn staleness_sums_until_adjusted_and_round_trips() {
        let mut s = Staleness::default();
        s.reset(3);
        let mut over = vec![false; 3];
        s.add(&[0.4, 0.0, 1.5], |_| 1.0, &mut over);
        assert_eq!(over, [false, false, true]);
        s.add(&[0.7, 0.1, 0.0], |_| 1.0, &mut over);
        assert_eq!(over, [true, false, true]);
        s.clear_adjusted(&[true, false, true]);
        assert_eq!(s.moved(), &[0.0, 0.1, 0.0]);
        let mut w = Writer::new(5);
        s.write_state(&mut w);
        let blob = w.finish();
        let mut r = Reader::open(&blob, 5).unwrap();
        assert_eq!(Staleness::read_state(&mut r, 3).unwrap(), s);
        let mut r = Reader::open(&blob, 5).unwrap();
        assert_eq!(Staleness::read_state(&mut r, 4).unwrap_err().kind(), ErrorKind::InvalidState);
        let mut w = Writer::new(5);
        w.f32s(&[0.0, 0.0]);
        w.f32s(&[0.0, -1.0]);
        let bad = w.finish();
        let mut r = Reader::open(&bad, 5).unwrap();
        assert_eq!(Staleness::read_state(&mut r, 2).unwrap_err().kind(), ErrorKind::InvalidState);
    }

    #[test]
    fn net_motion_cancels_a_back_and_forth_and_round_trips() {
        let a = frame(Vec3::ZERO, Vec3::Z, Vec3::X);
        let b = frame(Vec3::X, Vec3::Z, Vec3::X);
        let mut s = Staleness::default();
        s.reset(2);
        assert!(s.pending(0) && s.placements(0).is_empty());
        fn o(f: &RootFrame) -> Oriented<'_> {
            Oriented { frame: f, orientation: orientation(f) }
        }
        s.record(0, std::iter::once(Placement::of(o(&a), 1, o(&b), 2.0)));
        assert!(!s.pending(0) && s.pending(1));
        // b slides by 0.3 and turns by 0.1 rad, then comes back.
        let away = frame(Vec3::new(1.3, 0.0, 0.0), Vec3::Z, Quat::from_rotation_z(0.1) * Vec3::X);
        let chord = 2.0 * (0.05f32).sin();
        let p = s.placements(0)[0];
        let moved_away = p.moved(o(&a), o(&away));
        assert!((moved_away - (0.3 + 2.0 * chord)).abs() < 1e-4, "{moved_away}");
        assert!(p.moved(o(&a), o(&b)) < 1e-6);
        // A rigid motion of both moves nothing.
        let q = Quat::from_axis_angle(Vec3::new(1.0, 2.0, 3.0).normalize(), 0.7);
        let rigid = |f: &RootFrame| frame(q * f.position + Vec3::ONE, q * f.normal, q * f.tangent);
        let (ra, rb) = (rigid(&a), rigid(&b));
        assert!(p.moved(o(&ra), o(&rb)) < 1e-5, "{}", p.moved(o(&ra), o(&rb)));
        let mut over = vec![false; 2];
        s.set_net(&[moved_away, 0.0], |_| 0.4, &mut over);
        assert_eq!(over, [true, false]);
        let mut w = Writer::new(5);
        s.write_state(&mut w);
        let blob = w.finish();
        let mut r = Reader::open(&blob, 5).unwrap();
        let back = Staleness::read_state(&mut r, 2).unwrap();
        r.finish().unwrap();
        assert_eq!(back, s);
        s.clear_adjusted(&[true, false]);
        assert!(s.pending(0) && s.moved() == [0.0, 0.0]);
        // A placement naming the feather itself is refused.
        let mut bad = Staleness::default();
        bad.reset(2);
        bad.record(0, std::iter::once(Placement::of(o(&a), 0, o(&b), 2.0)));
        let mut w = Writer::new(5);
        bad.write_state(&mut w);
        let blob = w.finish();
        let mut r = Reader::open(&blob, 5).unwrap();
        assert_eq!(Staleness::read_state(&mut r, 2).unwrap_err().kind(), ErrorKind::InvalidState);
    }
}
