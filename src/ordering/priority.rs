//! Growth priority between neighbouring roots (paper §2.1 and §3.2).
//!
//! The directed priority `P_AB` measures how much root B lies "ahead" of root
//! A; the priority difference `ΔP_AB = P_AB − P_BA` decides who lies on whom:
//! `ΔP_AB > 0` means B is prior to A (B is placed first, A rests on it), the
//! DAG edge A→B.
//!
//! * Eq. 3 (the 2017 paper, default): `P_AB = õ_A·d_AB − γ (n_A·d_AB) − λ |b_A·d_AB|`
//!   with `d_AB = r_B − r_A`. It only uses the tangential orientation `õ_A`
//!   and the binormal `b_A`, which pitch and roll never change, so adjusting
//!   feathers never changes the order.
//! * Eq. 2 (the 2015 paper, legacy mode): `P_AB = o_A·(r_B − r_A) + γ n_A·(r_A − r_B)`
//!   with the feather's actual orientation `o_A`.
//!
//! Painted layers ([`Priorities::with_layers`]) come first: where two
//! roots' layers differ, the root on the higher layer lies on top whatever
//! Eq. 3 says, with a priority difference of [`LAYER_PRIORITY`], stronger
//! than any geometric one (so a cycle is always broken on a geometric
//! edge); equal layers leave Eq. 3 (or Eq. 2) alone.
//!
//! Exact antisymmetry: `ΔP_AB` is always evaluated as `P(lo, hi) − P(hi, lo)`
//! for the ordered pair `lo < hi` and negated when asked the other way round,
//! so `ΔP_AB == −ΔP_BA` holds bitwise (Rust never contracts `a*b + c` into a
//! fused multiply-add, so each `P` is one fixed sequence of roundings).

use crate::geometry::RootFrame;
use glam::Vec3;

/// The magnitude of a priority difference between two roots on different
/// layers: beyond any geometric `ΔP` (coordinates are bounded by
/// [`crate::limits::MAX_COORDINATE`]) and finite, as the order stores it.
pub(crate) const LAYER_PRIORITY: f32 = 1e30;

/// Which definition of the directed priority is used.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum PriorityRule {
    /// Eq. 3 of the 2017 paper (tangential orientation, binormal term λ).
    Improved,
    /// Eq. 2 of the 2015 paper (actual orientation, no λ), for the legacy mode.
    Legacy,
}

/// Evaluates priority differences for one pose.
#[derive(Clone, Copy, Debug)]
pub struct Priorities<'a> {
    frames: &'a [RootFrame],
    orientations: &'a [Vec3],
    rule: PriorityRule,
    gamma: f32,
    lambda: f32,
    /// Per root, its painted layer; empty when none was painted.
    layers: &'a [f32],
}

impl<'a> Priorities<'a> {
    /// Eq. 3 priorities over the root frames (γ = 0.6, λ = 0.3 by default in
    /// the config; `0 ≤ λ < γ < 1`).
    pub fn improved(frames: &'a [RootFrame], gamma: f32, lambda: f32) -> Self {
        Self { frames, orientations: &[], rule: PriorityRule::Improved, gamma, lambda, layers: &[] }
    }

    /// Eq. 2 priorities with the feathers' actual orientations `o_i`
    /// (one per root).
    ///
    /// # Panics
    /// If `orientations` and `frames` differ in length.
    pub fn legacy(frames: &'a [RootFrame], orientations: &'a [Vec3], gamma: f32) -> Self {
        assert_eq!(frames.len(), orientations.len(), "one orientation per root");
        Self { frames, orientations, rule: PriorityRule::Legacy, gamma, lambda: 0.0, layers: &[] }
    }

    /// The same priorities with painted layers (one per root, or empty for
    /// none): see the module doc.
    ///
    /// # Panics
    /// If `layers` is neither empty nor one per root.
    pub fn with_layers(self, layers: &'a [f32]) -> Self {
        assert!(layers.is_empty() || layers.len() == self.frames.len(), "one layer per root");
        Self { layers, ..self }
    }

    /// The rule in use.
    pub fn rule(&self) -> PriorityRule {
        self.rule
    }

    /// Number of roots.
    pub fn len(&self) -> usize {
        self.frames.len()
    }

    /// True when there are no roots.
    pub fn is_empty(&self) -> bool {
        self.frames.is_empty()
    }

    /// The directed priority `P_AB` (Eq. 3 or Eq. 2).
    pub fn directed(&self, a: u32, b: u32) -> f32 {
        let (fa, fb) = (&self.frames[a as usize], &self.frames[b as usize]);
        match self.rule {
            PriorityRule::Improved => directed_priority_eq3(fa, fb.position, self.gamma, self.lambda),
            PriorityRule::Legacy => {
                directed_priority_eq2(fa.position, fa.normal, self.orientations[a as usize], fb.position, self.gamma)
            }
        }
    }

    /// The priority difference `ΔP_AB = P_AB − P_BA` (paper Eq. 1); positive
    /// means B is prior to A. Exactly antisymmetric; 0 when `a == b`.
    pub fn delta(&self, a: u32, b: u32) -> f32 {
        if let (Some(&la), Some(&lb)) = (self.layers.get(a as usize), self.layers.get(b as usize)) {
            if la != lb {
                return if la > lb { LAYER_PRIORITY } else { -LAYER_PRIORITY };
            }
        }
        match a.cmp(&b) {
            std::cmp::Ordering::Less => self.directed(a, b) - self.directed(b, a),
            std::cmp::Ordering::Greater => -(self.directed(b, a) - self.directed(a, b)),
            std::cmp::Ordering::Equal => 0.0,
        }
    }

    /// `ΔP_ab` for every pair `(a, b)`, written to `out` (cleared first).
    pub fn deltas_of_pairs(&self, pairs: &[(u32, u32)], out: &mut Vec<f32>) {
        out.clear();
        out.extend(pairs.iter().map(|&(a, b)| self.delta(a, b)));
    }
}

/// Eq. 3 (2017 paper): `P_AB = õ_A·d − γ (n_A·d) − λ |b_A·d|`, `d = r_B − r_A`.
#[inline]
pub fn directed_priority_eq3(a: &RootFrame, r_b: Vec3, gamma: f32, lambda: f32) -> f32 {
    let d = r_b - a.position;
    a.tangent.dot(d) - gamma * a.normal.dot(d) - lambda * a.binormal.dot(d).abs()
}

/// Eq. 2 (2015 paper): `P_AB = o_A·(r_B − r_A) + γ n_A·(r_A − r_B)`.
#[inline]
pub fn directed_priority_eq2(r_a: Vec3, n_a: Vec3, o_a: Vec3, r_b: Vec3, gamma: f32) -> f32 {
    o_a.dot(r_b - r_a) + gamma * n_a.dot(r_a - r_b)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn flat(x: f32, y: f32, z: f32) -> RootFrame {
        RootFrame::from_normal_and_direction(Vec3::new(x, y, z), Vec3::Z, Vec3::X).unwrap()
    }

    #[test]
    fn tip_side_root_is_prior_on_a_flat_plate() {
        let frames = [flat(0.0, 0.0, 0.0), flat(1.0, 0.2, 0.0)];
        let p = Priorities::improved(&frames, 0.6, 0.3);
        // ΔP_01 = 2 Δx > 0: root 1 (further along +x) is prior to root 0.
        assert!((p.delta(0, 1) - 2.0).abs() < 1e-6);
        assert_eq!(p.delta(1, 0).to_bits(), (-p.delta(0, 1)).to_bits());
    }

    #[test]
    fn the_higher_layer_lies_on_top_and_equal_layers_keep_eq3() {
        let frames = [flat(0.0, 0.0, 0.0), flat(1.0, 0.2, 0.0), flat(2.0, 0.0, 0.0)];
        let plain = Priorities::improved(&frames, 0.6, 0.3);
        let layers = [1.0, 0.0, 1.0];
        let p = plain.with_layers(&layers);
        // Eq. 3 puts 1 before 0 (0 on top); the layers agree on who is on top.
        assert_eq!(p.delta(0, 1), LAYER_PRIORITY);
        assert_eq!(p.delta(1, 0), -LAYER_PRIORITY);
        // Root 1 lies ahead of 2 by Eq. 3 in reverse: the layer wins.
        assert!(plain.delta(1, 2) > 0.0 && p.delta(1, 2) < 0.0);
        // Equal layers: Eq. 3 bit for bit.
        assert_eq!(p.delta(0, 2).to_bits(), plain.delta(0, 2).to_bits());
    }

    #[test]
    fn lower_root_is_prior() {
        let frames = [flat(0.0, 0.0, 0.0), flat(0.0, 0.0, 0.1)];
        let p = Priorities::improved(&frames, 0.6, 0.3);
        // B = 1 is higher along the normal: ΔP_01 = −2γ·0.1 < 0, so 0 is prior.
        assert!(p.delta(0, 1) < 0.0);
        let o = [Vec3::X, Vec3::X];
        let legacy = Priorities::legacy(&frames, &o, 0.6);
        assert!(legacy.delta(0, 1) < 0.0);
    }

    #[test]
    fn lambda_term_is_symmetric_on_a_flat_plate() {
        let frames = [flat(0.0, 0.0, 0.0), flat(0.0, 1.0, 0.0)];
        let p = Priorities::improved(&frames, 0.6, 0.3);
        assert!((p.directed(0, 1) + 0.3).abs() < 1e-6);
        assert_eq!(p.delta(0, 1), 0.0);
    }
}
