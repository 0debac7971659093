//! The feather's dimensions and outline (DESIGN.md §4): length, width,
//! thickness and where the vanes are widest.

use glam::Vec3;

/// Length of a feather as a multiple of the local spacing `d`. A feather
/// then reaches over three to four rows of neighbours, so every point of the
/// skin is covered two to three times, as on a real bird; a shorter
/// feather leaves skin bare where feathers pitch up or are shortened
/// (BENCHMARKS.md, "Measurements behind the code's constants").
pub(crate) const LENGTH_PER_SPACING: f32 = 4.0;
/// Width as a multiple of `d`: the vanes reach a little past the lateral
/// neighbours, so neighbouring feathers overlap sideways too.
pub(crate) const WIDTH_PER_SPACING: f32 = 1.75;
/// Thickness as a fraction of the width (a contour feather's vane is thin;
/// this sets how steeply stacked feathers climb).
pub(crate) const THICKNESS_PER_WIDTH: f32 = 0.04;
/// Where the vane corners sit along the shaft, as a fraction of the length.
pub(crate) const DEFAULT_VANE_SPLIT: f32 = 0.4;
/// Most shaft segments a feather may have.
pub const MAX_SEGMENTS: usize = 4;
/// Most joints between shaft segments.
pub const MAX_JOINTS: usize = MAX_SEGMENTS - 1;

/// Dimensions of one feather, in model units.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct FeatherShape {
    /// Shaft length `L` (root to tip).
    pub length: f32,
    /// Vane width `W` (corner to corner).
    pub width: f32,
    /// Thickness `t`: how far above its own triangles a feather's top is.
    pub thickness: f32,
    /// `s_w`: where the vane corners sit along the shaft, as a fraction of
    /// the length (0 < s_w < 1).
    pub vane_split: f32,
    /// Shaft segments `S` (1 to [`MAX_SEGMENTS`]): 1 is the rigid kite;
    /// with more, joints sit evenly along the shaft and each may bend (see
    /// [`FeatherPose::bends`](super::FeatherPose::bends) and
    /// [`ShaftPlan`]).
    pub segments: u32,
}

impl FeatherShape {
    /// The default shape for local spacing `d` (Poisson-disk radius):
    /// length 4 d, width 1.75 d, thickness 4 % of the width (0.07 d), vane
    /// corners at 40 % of the length. With roots about d apart a feather
    /// covers its neighbours ahead over three to four rows and half of each lateral
    /// neighbour, so the coat is closed, and the small thickness keeps
    /// stacked feathers nearly flat (a few degrees of pitch).
    pub fn for_spacing(d: f32) -> Self {
        let width = WIDTH_PER_SPACING * d;
        Self {
            length: LENGTH_PER_SPACING * d,
            width,
            thickness: THICKNESS_PER_WIDTH * width,
            vane_split: DEFAULT_VANE_SPLIT,
            segments: 1,
        }
    }

    /// The shape for spacing `d` with a length and a width proportional to
    /// it (as a multiple of `d`; the defaults are 4 and 1.75), thickness
    /// 4 % of the width.
    pub fn proportioned(d: f32, length_per_spacing: f32, width_per_spacing: f32) -> Self {
        let width = width_per_spacing * d;
        Self { length: length_per_spacing * d, width, thickness: THICKNESS_PER_WIDTH * width, ..Self::for_spacing(d) }
    }

    /// The default shape for spacing `d` with global overrides: any of
    /// `length`, `width`, `thickness` that is > 0 replaces the rule (a given
    /// width also sets the default thickness, 4 % of it).
    pub fn with_overrides(d: f32, length: f32, width: f32, thickness: f32) -> Self {
        Self::for_spacing(d).overridden(length, width, thickness)
    }

    /// This shape with global overrides (see [`FeatherShape::with_overrides`]).
    pub fn overridden(self, length: f32, width: f32, thickness: f32) -> Self {
        let mut s = self;
        if length > 0.0 {
            s.length = length;
        }
        if width > 0.0 {
            s.width = width;
            s.thickness = THICKNESS_PER_WIDTH * width;
        }
        if thickness > 0.0 {
            s.thickness = thickness;
        }
        s
    }

    /// Half the vane width at distance `x` along the flat shaft: 0 at the
    /// root and the tip, `W/2` at the vane corners, linear in between;
    /// negative outside `[0, L]`.
    #[inline]
    pub fn half_width_at(&self, x: f32) -> f32 {
        let corner = self.vane_split * self.length;
        let half = 0.5 * self.width;
        if x < 0.0 || x > self.length {
            -1.0
        } else if x <= corner {
            half * x / corner
        } else {
            half * (self.length - x) / (self.length - corner)
        }
    }

    /// This shape shrunk by `scale` about the root: length and width scale,
    /// the thickness (and so the clearance over it) stays. The shrunk kite
    /// lies inside the full one, since the kite is convex and holds its root.
    #[inline]
    pub fn scaled(&self, scale: f32) -> Self {
        Self { length: self.length * scale, width: self.width * scale, ..*self }
    }

    /// The same shape with `segments` shaft segments (clamped to
    /// 1..=[`MAX_SEGMENTS`]).
    pub fn with_segments(self, segments: u32) -> Self {
        Self { segments: segments.clamp(1, MAX_SEGMENTS as u32), ..self }
    }

    /// Shaft segments, clamped to 1..=[`MAX_SEGMENTS`].
    #[inline]
    pub fn segment_count(&self) -> usize {
        (self.segments as usize).clamp(1, MAX_SEGMENTS)
    }

    /// How the shaft is jointed and the vanes sampled (see [`ShaftPlan`]).
    pub fn shaft_plan(&self) -> ShaftPlan {
        ShaftPlan::of(self)
    }

    /// The flat kite in local coordinates: root, tip, +y corner, −y corner.
    pub fn kite_corners(&self) -> [Vec3; 4] {
        let cx = self.vane_split * self.length;
        let hw = 0.5 * self.width;
        [Vec3::ZERO, Vec3::new(self.length, 0.0, 0.0), Vec3::new(cx, hw, 0.0), Vec3::new(cx, -hw, 0.0)]
    }
}

/// Most vane-edge stations: the interior joints and the vane corners.
pub const MAX_STATIONS: usize = MAX_SEGMENTS;

/// How a segmented feather is cut up (one home for the layout that the
/// posed triangles, the copy-out mesh and the drape all follow).
///
/// Joints sit evenly along the unbent shaft, at `k/S` of the length. The
/// vane's outline stays the kite's (so the height field, which models the
/// kite, stays exact for the unbent feather): its edge is sampled at
/// *stations*, every interior joint and the vane corners (`s_w`), with the
/// kite's half-width there. Within a segment the vane between the shaft
/// and the stations of that segment (both ends included) is one flat
/// polygon, cut into a fan of triangles from the segment's first joint:
/// per vane, segment `k` has as many triangles as stations in
/// `[k/S, (k+1)/S]`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ShaftPlan {
    /// Segments `S`.
    pub segments: usize,
    /// Interior stations along the unbent shaft, as fractions of the
    /// length, increasing.
    pub stations: [f32; MAX_STATIONS],
    /// How many of `stations` are used.
    pub station_count: usize,
}

impl ShaftPlan {
    fn of(shape: &FeatherShape) -> Self {
        let segments = shape.segment_count();
        let mut stations = [0.0; MAX_STATIONS];
        let mut n = 0;
        let split = shape.vane_split;
        let mut corner_placed = false;
        for k in 1..=segments {
            let joint = k as f32 / segments as f32;
            if !corner_placed && split <= joint {
                if split < joint {
                    stations[n] = split;
                    n += 1;
                }
                corner_placed = true;
            }
            if k < segments {
                stations[n] = joint;
                n += 1;
            }
        }
        Self { segments, stations, station_count: n }
    }

    /// Joint `k` (0 the root, `S` the tip) as a fraction of the length.
    #[inline]
    pub fn joint(&self, k: usize) -> f32 {
        k as f32 / self.segments as f32
    }

    /// The used stations.
    #[inline]
    pub fn stations(&self) -> &[f32] {
        &self.stations[..self.station_count]
    }

    /// The stations of segment `k` (both ends included), farthest first:
    /// the order of its fan of triangles.
    pub fn segment_stations(&self, k: usize) -> impl Iterator<Item = (usize, f32)> + '_ {
        let (near, far) = (self.joint(k), self.joint(k + 1));
        self.stations().iter().copied().enumerate().rev().filter(move |&(_, f)| f >= near && f <= far)
    }

    /// Triangles of one vane.
    pub fn triangles_per_vane(&self) -> usize {
        (0..self.segments).map(|k| self.segment_stations(k).count()).sum()
    }

    /// Triangles of one vane on segments `0..=k`.
    pub fn triangles_per_vane_up_to(&self, k: usize) -> usize {
        (0..=k.min(self.segments - 1)).map(|j| self.segment_stations(j).count()).sum()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn half_width_is_a_kite() {
        let s = FeatherShape { length: 10.0, width: 4.0, thickness: 0.1, vane_split: 0.4, segments: 1 };
        assert_eq!(s.half_width_at(0.0), 0.0);
        assert!((s.half_width_at(4.0) - 2.0).abs() < 1e-6);
        assert!((s.half_width_at(7.0) - 1.0).abs() < 1e-6);
        assert!(s.half_width_at(10.5) < 0.0 && s.half_width_at(-0.1) < 0.0);
    }

    #[test]
    fn shaft_plans_keep_the_kite_outline() {
        let kite = FeatherShape::for_spacing(1.0);
        let plan = kite.shaft_plan();
        assert_eq!(plan.stations(), &[0.4]);
        assert_eq!(plan.triangles_per_vane(), 1);
        let four = kite.with_segments(4).shaft_plan();
        assert_eq!(four.stations(), &[0.25, 0.4, 0.5, 0.75]);
        // Segment 1 (0.25..0.5) holds three stations: its fan has three triangles.
        assert_eq!(four.segment_stations(1).map(|(_, f)| f).collect::<Vec<_>>(), vec![0.5, 0.4, 0.25]);
        assert_eq!(four.triangles_per_vane(), 7);
        assert_eq!(four.triangles_per_vane_up_to(1), 4);
        // A corner on a joint is not repeated.
        let even = FeatherShape { vane_split: 0.5, ..kite }.with_segments(4).shaft_plan();
        assert_eq!(even.stations(), &[0.25, 0.5, 0.75]);
        assert_eq!(even.triangles_per_vane(), 6);
    }

    #[test]
    fn overrides_replace_the_rules() {
        let s = FeatherShape::with_overrides(1.0, 0.0, 3.0, 0.0);
        assert_eq!(s.length, 4.0);
        assert_eq!(s.width, 3.0);
        assert!((s.thickness - 0.12).abs() < 1e-6);
        assert_eq!(FeatherShape::with_overrides(1.0, 2.0, 0.0, 0.5).thickness, 0.5);
    }
}
