//! The coat: what never changes after creation ([`Dressing`]: the roots,
//! their shapes, the parameters) and every feather at one pose ([`Coat`]:
//! root frames, poses, neighbourhoods, order, body, staleness), with the
//! coat's saved state. The phases of a frame that change a coat live in
//! [`crate::frame`].

use crate::Config;
use crate::adjustment::AdjustParams;
use crate::body::BodyIndex;
use crate::csr::CsrView;
use crate::feather::{FeatherPose, FeatherShape, FeatherType, feather_triangles, shaft_direction};
use crate::geometry::RootFrame;
use crate::mesh::WeldedMesh;
use crate::ordering::{NeighbourParams, Neighbourhoods, PriorityOrder};
use crate::roots::{RootBinding, RootNormal, pose_roots};
use crate::stats::{FeatherRecord, FrameReport, OrderingReport};
use crate::surface::Surface;
use glam::Vec3;

mod blob;
mod staleness;

pub use staleness::{Oriented, Placement, Staleness, orientation};

/// What never changes after creation: the rest binding of every feather and
/// the parameters derived from the configuration.
#[derive(Clone, Debug)]
pub struct Dressing {
    /// Surface topology of the welded mesh.
    pub surface: Surface,
    /// Welded triangles.
    pub triangles: Vec<[u32; 3]>,
    /// For each welded triangle, the caller's triangle index.
    pub source_triangle: Vec<u32>,
    /// For each welded vertex, whether it carries feathers (its spacing
    /// multiplier is positive); empty when every vertex does.
    pub feathered: Vec<bool>,
    /// Each feather's painted layer (the layer map at its root); empty when
    /// no layer map was given. See [`crate::ordering::Priorities::with_layers`].
    pub layers: Vec<f32>,
    /// Where each feather is planted.
    pub roots: Vec<RootBinding>,
    /// Each feather's dimensions.
    pub shapes: Vec<FeatherShape>,
    /// Each feather's reach for obstacle search (its length).
    pub reach: Vec<f32>,
    /// Neighbourhood parameters.
    pub neighbour_params: NeighbourParams,
    /// Adjustment parameters.
    pub adjust_params: AdjustParams,
    /// The configuration the system was created with: the mode, the
    /// priority weights γ and λ (Eq. 3 / Eq. 2), θs, the drift tolerance,
    /// the settle rate, whether neighbourhoods follow the pose, ... (read
    /// in place, never copied field by field).
    pub config: Config,
    /// The connected part of the surface each triangle belongs to, and the
    /// number of parts ([`Surface::face_components`]): skin of another
    /// part near a feather is watched each frame (see
    /// [`crate::frame::step_coat`]).
    pub face_part: Vec<u32>,
    pub parts: usize,
}

impl Dressing {
    /// Everything fixed at creation: the welded mesh's surface and
    /// triangles, the sampled roots with their shapes, and the parameters
    /// of `config`.
    pub fn new(surface: Surface, mesh: &WeldedMesh, roots: Vec<RootBinding>, config: &Config) -> Self {
        let shapes = Self::shapes_for(&roots, config);
        let (face_part, parts) = surface.face_components();
        Self {
            surface,
            triangles: mesh.triangles.clone(),
            source_triangle: mesh.source_triangle.clone(),
            feathered: Vec::new(),
            layers: Vec::new(),
            reach: shapes.iter().map(|s| s.length).collect(),
            shapes,
            roots,
            neighbour_params: NeighbourParams { k: config.k_neighbours, ..NeighbourParams::default() },
            adjust_params: config.adjust_params(),
            config: config.clone(),
            face_part,
            parts,
        }
    }

    /// Shapes from the configuration and each root's local spacing and
    /// per-vertex multipliers: the global overrides of `config` when set,
    /// otherwise the spacing rules of [`FeatherShape::for_spacing`]; length
    /// and width then scale by the root's multipliers.
    pub fn shapes_for(roots: &[RootBinding], config: &Config) -> Vec<FeatherShape> {
        let plain = FeatherType { length_per_spacing: 0.0, width_per_spacing: 0.0, thickness_scale: 1.0 };
        roots.iter().map(|r| Self::shape_of(r, &plain, config)).collect()
    }

    /// Gives each feather the shape of its type (`kinds[i]` indexes
    /// `types`), with its root's spacing and multipliers.
    pub fn retype(&mut self, types: &[FeatherType], kinds: &[u8]) {
        self.shapes =
            self.roots.iter().zip(kinds).map(|(r, &k)| Self::shape_of(r, &types[k as usize], &self.config)).collect();
        self.reach = self.shapes.iter().map(|s| s.length).collect();
    }

    fn shape_of(r: &RootBinding, kind: &FeatherType, config: &Config) -> FeatherShape {
        let mut s = kind.shape(r.spacing, (config.length_per_spacing, config.width_per_spacing)).overridden(
            config.feather_length,
            config.feather_width,
            config.feather_thickness,
        );
        s.length *= r.length_scale;
        s.width *= r.width_scale;
        if config.feather_thickness <= 0.0 {
            s.thickness *= r.width_scale;
        }
        s.with_segments(config.shaft_segments)
    }

    /// Number of feathers.
    pub fn len(&self) -> usize {
        self.roots.len()
    }

    /// Joints of the feathers' shafts (every feather has as many: the
    /// configuration's segments less one).
    pub fn shaft_joints(&self) -> usize {
        self.shapes.first().map_or(0, |s| s.segment_count() - 1)
    }

    /// Whether there are no feathers.
    pub fn is_empty(&self) -> bool {
        self.roots.is_empty()
    }
}

/// Every feather at the current pose, plus the order and neighbourhoods
/// that produced it. This is the state a frame changes, and what a saved
/// state holds.
#[derive(Debug, Default)]
pub struct Coat {
    /// Welded vertex positions of the current pose.
    pub positions: Vec<Vec3>,
    /// Area-weighted vertex normals of the current pose.
    pub normals: Vec<Vec3>,
    /// Each root's frame at the current pose.
    pub frames: Vec<RootFrame>,
    /// Each feather's pitch and roll relative to its frame.
    pub poses: Vec<FeatherPose>,
    /// Neighbourhoods (k nearest, pairs, obstacle candidates).
    pub neighbourhoods: Neighbourhoods,
    /// The priority DAG and its order.
    pub order: PriorityOrder,
    /// The body's triangles at the current pose, indexed.
    pub body: BodyIndex,
    /// How far each feather's surroundings moved since it was last adjusted.
    pub staleness: Staleness,
    /// Feathers held back from their solved pose by the settle rate: the
    /// incremental mode readjusts them again next frame (empty or all
    /// false after a solve).
    pub settling: Vec<bool>,
    /// Which feathers the last create, step or evaluate readjusted (one
    /// flag per feather; saved with the state).
    pub readjusted: Vec<bool>,
    /// 0 after creation, then one more per step.
    pub frame_index: u64,
    /// Figures of the last static order.
    pub ordering_report: OrderingReport,
    /// Figures of the last create, step or evaluate.
    pub frame_report: FrameReport,
}

crate::memory::clone_by_fields!(Coat {
    positions,
    normals,
    frames,
    poses,
    neighbourhoods,
    order,
    body,
    staleness,
    settling,
    readjusted,
    frame_index,
    ordering_report,
    frame_report
});
crate::memory::heap_size_of_fields!(Coat {
    positions, normals, frames, poses, neighbourhoods, order, body, staleness, settling, readjusted
} plain { frame_index, ordering_report, frame_report });

impl Coat {
    /// The obstacle candidates of every feather (`Coat::neighbourhoods`):
    /// row i lists, sorted, the roots within reach of root i.
    pub fn obstacle_candidates(&self) -> CsrView<'_, u32> {
        self.neighbourhoods.obstacle_csr()
    }

    /// Moves the coat to `positions` (welded) and re-poses every root.
    pub fn pose(&mut self, dressing: &Dressing, positions: &[Vec3]) {
        self.positions.clear();
        self.positions.extend_from_slice(positions);
        dressing.surface.vertex_normals(&self.positions, &mut self.normals);
        pose_roots(
            &dressing.roots,
            &self.positions,
            &dressing.triangles,
            &self.normals,
            RootNormal::FaceLimited,
            &mut self.frames,
        );
    }

    /// Fills the host-facing records and triangles of every feather.
    pub fn export(&self, dressing: &Dressing, records: &mut Vec<FeatherRecord>, triangles: &mut Vec<[f32; 3]>) {
        records.clear();
        triangles.clear();
        for (i, ((root, frame), (pose, shape))) in
            dressing.roots.iter().zip(&self.frames).zip(self.poses.iter().zip(&dressing.shapes)).enumerate()
        {
            let tris = feather_triangles(frame, shape, *pose);
            triangles.extend(tris.iter().flatten().map(|p| p.to_array()));
            records.push(FeatherRecord {
                id: root.id,
                order_index: self.order.rank_of(i as u32),
                triangle: dressing.source_triangle[root.point.face as usize],
                barycentric: root.point.bary,
                root: frame.position.to_array(),
                normal: frame.normal.to_array(),
                direction: shaft_direction(frame, *pose).to_array(),
                pitch: pose.pitch,
                roll: pose.roll,
                length: shape.length * pose.scale,
                width: shape.width * pose.scale,
                thickness: shape.thickness,
            });
        }
    }
}

crate::memory::heap_size_of_fields!(Dressing { surface, triangles, source_triangle, feathered, layers, roots, shapes, reach, face_part } plain {
    neighbour_params, adjust_params, config, parts
});
