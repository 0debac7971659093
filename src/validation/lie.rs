//! How a coat lies (DESIGN.md §6): how far each feather's tip stands off
//! the body surface, in feather lengths. A coat that lies down has its tips
//! a few thicknesses above the skin per layer beneath; a bristle stands
//! more than half a length off.

use crate::body::BodyIndex;
use crate::feather::{FeatherPose, FeatherShape, tip_position};
use crate::geometry::RootFrame;
use rayon::prelude::*;

/// A tip farther than this off the skin, in feather lengths, is a bristle.
pub const BRISTLE_TIP_HEIGHT: f64 = 0.5;

/// Tip heights of a coat, summarised.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct TipHeights {
    /// Median tip height, in feather lengths.
    pub median: f64,
    /// 90th percentile (nearest rank), in feather lengths.
    pub p90: f64,
    /// Percentage of feathers whose tip stands more than
    /// [`BRISTLE_TIP_HEIGHT`] lengths off the skin.
    pub bristle_percent: f64,
    /// Feathers measured: those placed (a feather left out has no tip).
    pub feathers: usize,
}

/// The distance from each placed feather's tip to the nearest point of the
/// body, divided by the feather's placed length and capped at 1 (a tip a
/// whole length or more off the skin counts as 1). Feathers left out are
/// skipped. In feather order.
pub fn tip_heights(frames: &[RootFrame], shapes: &[FeatherShape], poses: &[FeatherPose], body: &BodyIndex) -> Vec<f64> {
    frames
        .par_iter()
        .zip(shapes)
        .zip(poses)
        .map_init(Vec::new, |scratch, ((frame, shape), pose)| {
            let length = shape.length * pose.scale;
            if length.is_nan() || length <= 0.0 {
                return None;
            }
            let tip = tip_position(frame, shape, *pose);
            Some(body.closest_point(tip, length, scratch).map_or(1.0, |c| f64::from(c.distance / length).min(1.0)))
        })
        .collect::<Vec<_>>()
        .into_iter()
        .flatten()
        .collect()
}

/// The median, 90th percentile and bristle share of `heights`.
pub fn summarise_tip_heights(heights: &[f64]) -> TipHeights {
    if heights.is_empty() {
        return TipHeights::default();
    }
    let mut sorted = heights.to_vec();
    sorted.sort_by(f64::total_cmp);
    let rank = |q: f64| sorted[((q * sorted.len() as f64).ceil() as usize).clamp(1, sorted.len()) - 1];
    let bristles = sorted.iter().filter(|&&h| h > BRISTLE_TIP_HEIGHT).count();
    TipHeights {
        median: rank(0.5),
        p90: rank(0.9),
        bristle_percent: 100.0 * bristles as f64 / sorted.len() as f64,
        feathers: sorted.len(),
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use glam::Vec3;

    /// A flat floor z = 0 of two triangles.
    fn floor() -> BodyIndex {
        let p = [
            Vec3::new(-10.0, -10.0, 0.0),
            Vec3::new(10.0, -10.0, 0.0),
            Vec3::new(10.0, 10.0, 0.0),
            Vec3::new(-10.0, 10.0, 0.0),
        ];
        BodyIndex::from_mesh(&p, &[[0, 1, 2], [0, 2, 3]])
    }

    #[test]
    fn a_pitched_feather_stands_its_sine_off_a_floor() {
        let frame = RootFrame::from_normal_and_direction(Vec3::ZERO, Vec3::Z, Vec3::X).unwrap();
        let shape = FeatherShape::for_spacing(1.0);
        let poses = [
            FeatherPose::new(0.0, 0.0),
            FeatherPose::new(0.3, 0.1),
            FeatherPose::new(0.7, 0.0),
            FeatherPose::new(0.7, 0.0).with_scale(0.0),
        ];
        let h = tip_heights(&[frame; 4], &[shape; 4], &poses, &floor());
        assert_eq!(h.len(), 3, "the feather left out has no tip");
        assert!(h[0].abs() < 1e-6);
        assert!((h[1] - 0.3f64.sin()).abs() < 1e-5, "{}", h[1]);
        assert!((h[2] - 0.7f64.sin()).abs() < 1e-5);
        let s = summarise_tip_heights(&h);
        assert_eq!(s.feathers, 3);
        assert!((s.median - h[1]).abs() < 1e-12 && (s.p90 - h[2]).abs() < 1e-12);
        assert!((s.bristle_percent - 100.0 / 3.0).abs() < 1e-9);
    }

    #[test]
    fn a_tip_out_of_reach_counts_a_whole_length() {
        let frame = RootFrame::from_normal_and_direction(Vec3::new(0.0, 0.0, 50.0), Vec3::Z, Vec3::X).unwrap();
        let h = tip_heights(&[frame], &[FeatherShape::for_spacing(1.0)], &[FeatherPose::default()], &floor());
        assert_eq!(h, vec![1.0]);
        assert_eq!(summarise_tip_heights(&[]), TipHeights::default());
    }
}
