//! The poses and geometry a verifying walk gives the feathers it adjusts,
//! kept aside until the walk ends: the checks made ahead on other threads
//! meanwhile read the coat as it was before the walk, which then never
//! changes under them (see [`super::Adjuster::walk_checking_ahead`]).

use super::super::checks::SetAside;
use super::super::obstacle::ObstacleBoxes;
use super::visit::{FeatherGeometry, Posed};
use crate::feather::{FeatherPose, FeatherTriangles};
use glam::Vec3;

/// No entry for a feather.
const NONE: u32 = u32::MAX;

/// Per feather, its entry if the walk adjusted it; the entries (pose and
/// geometry) in the order they were made.
#[derive(Clone, Debug, Default)]
pub(super) struct Aside {
    slot: Vec<u32>,
    feathers: Vec<u32>,
    poses: Vec<FeatherPose>,
    geometry: Posed,
}

impl Aside {
    /// No entries, for `n` feathers. The entry lists keep their capacity
    /// (the most feathers a walk adjusted so far).
    pub(super) fn reset(&mut self, n: usize) {
        self.slot.clear();
        self.slot.resize(n, NONE);
        self.feathers.clear();
        self.poses.clear();
        self.geometry.clear();
    }

    /// Feather `i`'s entry, if it has one.
    #[inline]
    fn entry_of(&self, i: usize) -> Option<usize> {
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
        self.entry_of(i).map_or(base[i], |s| self.geometry.spheres[s])
    }

    /// Feather `i`'s triangles: its entry's, else `base`'s.
    #[inline]
    pub(super) fn triangles<'a>(&'a self, i: usize, base: &'a [FeatherTriangles]) -> &'a FeatherTriangles {
        self.entry_of(i).map_or(&base[i], |s| &self.geometry.triangles[s])
    }

    /// Feather `i`'s obstacle boxes: its entry's, else `base`'s.
    #[inline]
    pub(super) fn boxes<'a>(&'a self, i: usize, base: &'a [ObstacleBoxes]) -> &'a ObstacleBoxes {
        self.entry_of(i).map_or(&base[i], |s| &self.geometry.boxes[s])
    }

    /// Gives feather `i` this pose and geometry (replacing an entry it had).
    pub(super) fn set(&mut self, i: usize, pose: FeatherPose, g: &FeatherGeometry) {
        if let Some(s) = self.entry_of(i) {
            self.poses[s] = pose;
            self.geometry.set(s, g);
            return;
        }
        self.slot[i] = self.feathers.len() as u32;
        self.feathers.push(i as u32);
        self.poses.push(pose);
        self.geometry.push(g);
    }

    /// Writes every entry into `poses` and `base` and drops them.
    pub(super) fn merge_into(&mut self, poses: &mut [FeatherPose], base: &mut Posed) {
        for (s, &i) in self.feathers.iter().enumerate() {
            poses[i as usize] = self.poses[s];
            base.set(i as usize, &self.geometry.get(s));
        }
        let n = self.slot.len();
        self.reset(n);
    }

    /// The entries' slots and boxes, for [`BoxesOf`](super::super::checks::BoxesOf).
    pub(super) fn set_aside_boxes(&self) -> SetAside<'_> {
        SetAside { slot: &self.slot, boxes: &self.geometry.boxes, bounds: &self.geometry.bounds }
    }
}

crate::memory::heap_size_of_fields!(Aside { slot, feathers, poses, geometry });
