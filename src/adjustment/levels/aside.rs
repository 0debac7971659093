//! The poses and geometry a verifying walk gives the feathers it adjusts,
//! kept aside until the walk ends: the checks made ahead on other threads
//! meanwhile read the coat as it was before the walk, which then never
//! changes under them (see [`super::Adjuster::walk_checking_ahead`]).

use super::super::obstacle::{ObstacleBounds, ObstacleBoxes};
use crate::feather::{FeatherPose, FeatherTriangles};
use glam::Vec3;

/// No entry for a feather.
const NONE: u32 = u32::MAX;

/// Per feather, its entry if the walk adjusted it; the entries in the order
/// they were first made.
#[derive(Clone, Debug, Default)]
pub(super) struct Aside {
    slot: Vec<u32>,
    feathers: Vec<u32>,
    poses: Vec<FeatherPose>,
    triangles: Vec<FeatherTriangles>,
    spheres: Vec<(Vec3, f32)>,
    boxes: Vec<ObstacleBoxes>,
    bounds: Vec<ObstacleBounds>,
}

/// The base arrays an [`Aside`] is laid over: every feather's pose and its
/// posed geometry as the walk began.
pub(super) struct Base<'a> {
    pub(super) poses: &'a mut [FeatherPose],
    pub(super) triangles: &'a mut [FeatherTriangles],
    pub(super) spheres: &'a mut [(Vec3, f32)],
    pub(super) boxes: &'a mut [ObstacleBoxes],
    pub(super) bounds: &'a mut [ObstacleBounds],
}

/// One feather's new pose and geometry.
pub(super) struct Entry {
    pub(super) pose: FeatherPose,
    pub(super) triangles: FeatherTriangles,
    pub(super) sphere: (Vec3, f32),
    pub(super) boxes: ObstacleBoxes,
    pub(super) bounds: ObstacleBounds,
}

impl Aside {
    /// No entries, for `n` feathers. The entry lists keep their capacity
    /// (the most feathers a walk adjusted so far).
    pub(super) fn reset(&mut self, n: usize) {
        self.slot.clear();
        self.slot.resize(n, NONE);
        self.feathers.clear();
        self.poses.clear();
        self.triangles.clear();
        self.spheres.clear();
        self.boxes.clear();
        self.bounds.clear();
    }

    /// Feather `i`'s entry, if it has one.
    #[inline]
    pub(super) fn entry_of(&self, i: usize) -> Option<usize> {
        self.slot.get(i).copied().filter(|&s| s != NONE).map(|s| s as usize)
    }

    /// Feather `i`'s pose: its entry's, else `base`'s.
    #[inline]
    pub(super) fn pose(&self, i: usize, base: &[FeatherPose]) -> FeatherPose {
        self.entry_of(i).map_or(base[i], |s| self.poses[s])
    }

    /// Feather `i`'s sphere: its entry's, else `base`'s.
    #[inline]
    pub(super) fn sphere(&self, i: usize, base: &[(Vec3, f32)]) -> (Vec3, f32) {
        self.entry_of(i).map_or(base[i], |s| self.spheres[s])
    }

    /// Feather `i`'s triangles: its entry's, else `base`'s.
    #[inline]
    pub(super) fn triangles<'a>(&'a self, i: usize, base: &'a [FeatherTriangles]) -> &'a FeatherTriangles {
        self.entry_of(i).map_or(&base[i], |s| &self.triangles[s])
    }

    /// Feather `i`'s obstacle boxes: its entry's, else `base`'s.
    #[inline]
    pub(super) fn boxes<'a>(&'a self, i: usize, base: &'a [ObstacleBoxes]) -> &'a ObstacleBoxes {
        self.entry_of(i).map_or(&base[i], |s| &self.boxes[s])
    }

    /// Gives feather `i` this entry (replacing one it had).
    pub(super) fn set(&mut self, i: usize, e: Entry) {
        if let Some(s) = self.entry_of(i) {
            (self.poses[s], self.triangles[s], self.spheres[s]) = (e.pose, e.triangles, e.sphere);
            (self.boxes[s], self.bounds[s]) = (e.boxes, e.bounds);
            return;
        }
        self.slot[i] = self.feathers.len() as u32;
        self.feathers.push(i as u32);
        self.poses.push(e.pose);
        self.triangles.push(e.triangles);
        self.spheres.push(e.sphere);
        self.boxes.push(e.boxes);
        self.bounds.push(e.bounds);
    }

    /// Writes every entry into `base` and drops them.
    pub(super) fn merge_into(&mut self, base: Base<'_>) {
        for (s, &i) in self.feathers.iter().enumerate() {
            let i = i as usize;
            base.poses[i] = self.poses[s];
            base.triangles[i] = self.triangles[s];
            base.spheres[i] = self.spheres[s];
            base.boxes[i] = self.boxes[s];
            base.bounds[i] = self.bounds[s];
            self.slot[i] = NONE;
        }
        let n = self.slot.len();
        self.reset(n);
    }

    /// The entries' slots and boxes, for [`BoxesOf`](super::super::checks::BoxesOf).
    pub(super) fn set_aside_boxes(&self) -> super::super::checks::SetAside<'_> {
        super::super::checks::SetAside { slot: &self.slot, boxes: &self.boxes, bounds: &self.bounds }
    }
}

crate::memory::heap_size_of_fields!(Aside { slot, feathers, poses, triangles, spheres, boxes, bounds });
