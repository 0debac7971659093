//! Candidate lists kept from frame to frame, and the certificate that says
//! when they still hold.
//!
//! A leaf's lists are made at one pose, its *reference*: the union of its
//! near leaves (found with the reach widened by a margin `m`), and per root
//! `i` of the leaf
//! * `S_i`: every root `j` of the union with `|r_i − r_j| ≤ L_i + L_j + m`
//!   (a superset of the row: the row is `S_i` filtered at the current pose
//!   by the very test, in the very `f32` operations, of the exhaustive
//!   search, so it comes out the same bitwise);
//! * `K_i`: every root of the union within `ρ_i = d_k + m`, with `d_k` the
//!   distance of `i`'s k-th nearest at the reference (the k nearest now are
//!   ranked among `K_i` when the certificate below says no other root can
//!   come nearer).
//!
//! **The certificate.** Let `M(x) = R (x − a) + a'` be the rigid map of the
//! leaf's root nearest the middle of its box (its *anchor*) from the reference to now (`R` its
//! frame's rotation, `a`, `a'` its positions), and for every root `x` of the
//! union `e_x = r_x' − M(r_x)` (primes: now). Then, exactly,
//! `r_i' − r_j' = R (r_i − r_j) + e_i − e_j`, so with `E ≥ max |e_x|` over
//! the union, `E_self ≥ max |e_i|` over the leaf's own roots (near the
//! anchor, so usually much smaller) and `σ` the smallest singular value of
//! `R`, for `i` in the leaf and `j` in the union
//!
//! ```text
//!     |r_i' − r_j'| ≥ σ |r_i − r_j| − (E_self + E).                      (1)
//! ```
//!
//! `R` is a product of two frames, orthonormal up to rounding: with
//! `δ ≥ ‖RᵀR − I‖_F` (computed, plus 1e-6), `σ² ≥ 1 − δ`, so `σ ≥ 1 − δ`.
//!
//! *Rows.* Every root that can be within reach now lies in one of the leaf's
//! near leaves *now* (the box test is exact), and these are checked to be
//! among the reference's, so it lies in the union. A root `j` of the union
//! not in `S_i` was farther than `L + m` (`L = L_i + L_j ≤ L_max`, the
//! leaf's longest reach plus the union's longest); by (1) it is now farther
//! than `(1 − δ)(L + m) − (E_self + E)`, which is at least `L` (with room
//! for rounding) when
//!
//! ```text
//!     (1 − δ − ε) m − (E_self + E) ≥ (2ε + δ) L_max.                     (2)
//! ```
//!
//! *Within the rows.* For `j` in `S_i`, with `d = |r_i − r_j|` and
//! `L = L_i + L_j` at the reference, the slack `s = d − L` is stored. By
//! (1) and `σ_max ≤ 1 + δ`, `d' ∈ [(1 − δ) d − e, (1 + δ) d + e]` with
//! `e = E_self + E`. With `B = e + (2δ + 2ε)(L_max + m)` (`d ≤ L + m`):
//! if `s ≤ −B`, `(1 + δ) d + e ≤ L − (δ + 2ε)(L_max + m) ≤ L (1 − ε)`, so
//! `j` is in the row now; if `s ≥ B`, `(1 − δ) d − e ≥ L (1 + ε)`, so it is
//! not. Only the entries with `|s| < B` are tested (exactly).         (3)
//!
//! *k nearest.* When the k-th nearest of `K_i` now lies at `d ≤ L_i + min L`
//! (so every root nearer than it is in the union, as for the rows) and
//! `d (1 + 3ε) ≤ (1 − δ − ε) ρ_i − (E_self + E)`, a root of the union
//! outside `K_i` (farther than `ρ_i` at the reference) is now strictly
//! farther than `d` by (1), so it cannot rank: the k nearest of `K_i` are
//! the k nearest.
//!
//! *Rounding.* `ε = 1e-5` covers every `f32` rounding above with a wide
//! margin: a computed squared distance or squared limit is within a few
//! units of `2⁻²⁴` (relative) of its exact value, so a root tested out at
//! the reference is farther than its limit times `(1 − ε)`, and a root
//! farther than its limit times `(1 + ε)` now is tested out now; the
//! residuals' own rounding (a few units of `2⁻²⁴` of the magnitudes
//! involved: the union's radius about the anchor, the anchor's position and
//! `E`) is added to `E` before the test ([`AnchorMap::widen`]). Anything not
//! finite fails the tests, and the leaf's lists are then made again at the
//! current pose.

use crate::geometry::RootFrame;
use glam::{Mat3, Vec3};

/// Relative room for rounding (see the module notes).
pub(super) const EPS: f32 = 1e-5;

/// The margin `m` of a leaf: this fraction of its longest reach plus the
/// shortest reach of all roots. Larger keeps the lists valid through more
/// motion, at the cost of longer lists to filter each frame.
pub(super) const MARGIN: f32 = 0.25;

/// The rigid map of a leaf's anchor from its reference frame to now.
#[derive(Clone, Copy, Debug)]
pub(super) struct AnchorMap {
    rotation: Mat3,
    from: Vec3,
    to: Vec3,
    /// `δ`: a bound on how far `R` is from orthogonal.
    pub(super) skew: f32,
}

impl AnchorMap {
    /// The map taking `before` onto `after` (as the step's root maps do).
    pub(super) fn between(before: &RootFrame, after: &RootFrame) -> Self {
        let rotation = after.axes() * before.axes().transpose();
        let g = rotation.transpose() * rotation - Mat3::IDENTITY;
        let skew = (g.x_axis.length_squared() + g.y_axis.length_squared() + g.z_axis.length_squared()).sqrt() + 1e-6;
        Self { rotation, from: before.position, to: after.position, skew }
    }

    /// `|now − M(reference)|²` as computed (`e_x` of the module notes).
    #[inline]
    pub(super) fn residual2(&self, reference: Vec3, now: Vec3) -> f32 {
        (now - (self.rotation * (reference - self.from) + self.to)).length_squared()
    }

    /// `E`: the largest computed residual `e`, widened by the rounding of
    /// its computation; `radius` bounds `|reference − a|` over the union.
    #[inline]
    pub(super) fn widen(&self, e: f32, radius: f32) -> f32 {
        e * (1.0 + EPS) + EPS * (radius + self.to.length() + self.from.length())
    }

    /// Condition (2): the leaf's `S_i` still hold every row (`e`:
    /// `E_self + E`, widened).
    #[inline]
    pub(super) fn rows_hold(&self, margin: f32, longest: f32, e: f32) -> bool {
        (1.0 - self.skew - EPS) * margin - e >= (2.0 * EPS + self.skew) * longest
    }

    /// The half-width `B` of the band of slacks that must be tested: an
    /// entry of `S_i` whose reference slack `s = |r_i − r_j| − (L_i + L_j)`
    /// is at most `−B` is within reach now, one with `s ≥ B` is not
    /// (module notes, (3)).
    #[inline]
    pub(super) fn band(&self, e: f32, longest: f32, margin: f32) -> f32 {
        e + (2.0 * self.skew + 2.0 * EPS) * (longest + margin)
    }

    /// The k-th nearest of `K_i` at squared distance `d2` now is the k-th
    /// nearest of all (given `d2 ≤ (L_i + min L)²`, checked by the caller).
    #[inline]
    pub(super) fn nearest_hold(&self, d2: f32, radius: f32, e: f32) -> bool {
        d2.sqrt() * (1.0 + 3.0 * EPS) <= (1.0 - self.skew - EPS) * radius - e
    }
}

/// Whether every element of `inner` is in `outer` (both increasing).
pub(super) fn is_subset(inner: &[u32], outer: &[u32]) -> bool {
    let mut rest = outer.iter();
    inner.iter().all(|x| rest.any(|y| y == x))
}

#[cfg(test)]
mod tests {
    use super::*;
    use glam::Quat;

    #[test]
    fn a_rigid_motion_leaves_no_residual_and_keeps_the_lists() {
        let q = Quat::from_axis_angle(Vec3::new(1.0, 2.0, 3.0).normalize(), 0.9);
        let t = Vec3::new(0.3, -0.2, 0.1);
        let a = RootFrame::from_normal_and_direction(Vec3::new(0.1, 0.2, 0.3), Vec3::Z, Vec3::X).unwrap();
        let moved = RootFrame::from_normal_and_direction(q * a.position + t, q * a.normal, q * a.tangent).unwrap();
        let map = AnchorMap::between(&a, &moved);
        let x = Vec3::new(1.0, -0.5, 0.25);
        assert!(map.residual2(x, q * x + t).sqrt() < 1e-5);
        assert!(map.skew < 1e-5);
        let e = 2.0 * map.widen(map.residual2(x, q * x + t).sqrt(), 2.0);
        assert!(map.rows_hold(0.1, 2.0, e));
        // Residuals adding up to the margin break the rows' certificate.
        assert!(!map.rows_hold(0.1, 2.0, map.widen(0.03, 2.0) + map.widen(0.07, 2.0)));
        assert!(!map.rows_hold(0.1, 2.0, f32::NAN));
        assert!(map.nearest_hold(0.25, 0.6, e) && !map.nearest_hold(0.25, 0.5, e));
    }

    #[test]
    fn subsets_of_increasing_lists() {
        assert!(is_subset(&[], &[]) && is_subset(&[2, 5], &[1, 2, 3, 5]));
        assert!(!is_subset(&[2, 4], &[1, 2, 3, 5]) && !is_subset(&[6], &[1, 2]));
    }
}
