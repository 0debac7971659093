//! The coat: every feather at one pose, and the from-scratch solve that
//! builds it (neighbourhoods → priorities → static order → adjustment of
//! every feather). Creation, `evaluate`, and every frame of the `rebuild`
//! mode use it; the incremental and legacy frame updates live in
//! `animation::step` and change a coat in place.

use crate::adjustment::{AdjustParams, AdjustSteps, Adjuster, CandidateLists, Selection};
use crate::body::BodyIndex;
use crate::error::Result;
use crate::error::{Error, ErrorKind};
use crate::feather::{FeatherPose, FeatherShape, feather_triangles, shaft_direction};
use crate::geometry::RootFrame;
use crate::mesh::WeldedMesh;
use crate::ordering::{NeighbourParams, Neighbourhoods, Priorities, PriorityOrder};
use crate::progress::{Phase, Progress};
use crate::roots::{RootBinding, RootNormal, pose_roots};
use crate::snapshot::{Reader, Writer};
use crate::stats::{FeatherRecord, FrameReport, OrderingReport};
use crate::surface::Surface;
use crate::{Config, Mode};
use glam::Vec3;
use std::time::Instant;

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
    /// The mode and priority weights.
    pub mode: Mode,
    /// γ of Eq. 3 / Eq. 2.
    pub gamma: f32,
    /// λ of Eq. 3.
    pub lambda: f32,
    /// θs, the propagation threshold.
    pub theta_s: f32,
    /// The incremental mode's drift tolerance (`Config::drift_tolerance`).
    pub drift_tolerance: f32,
    /// Recompute neighbourhoods at the current pose every frame.
    pub recompute_neighbourhoods: bool,
    /// The incremental mode's settle rate (`Config::settle_rate`).
    pub settle_rate: f32,
    /// The connected part of the surface each triangle belongs to, and the
    /// number of parts ([`Surface::face_components`]): skin of another
    /// part near a feather is watched each frame (see
    /// `animation::step`).
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
            reach: shapes.iter().map(|s| s.length).collect(),
            shapes,
            roots,
            neighbour_params: NeighbourParams { k: config.k_neighbours, ..NeighbourParams::default() },
            adjust_params: config.adjust_params(),
            mode: config.mode,
            gamma: config.gamma,
            lambda: config.lambda,
            theta_s: config.theta_s,
            drift_tolerance: config.drift_tolerance,
            recompute_neighbourhoods: config.recompute_neighbourhoods,
            settle_rate: config.settle_rate,
            face_part,
            parts,
        }
    }

    /// Shapes from the configuration and each root's local spacing and
    /// per-vertex multipliers: the global overrides of `config` when set,
    /// otherwise the spacing rules of [`FeatherShape::for_spacing`]; length
    /// and width then scale by the root's multipliers.
    pub fn shapes_for(roots: &[RootBinding], config: &Config) -> Vec<FeatherShape> {
        roots
            .iter()
            .map(|r| {
                let mut s = FeatherShape::proportioned(r.spacing, config.length_per_spacing, config.width_per_spacing)
                    .overridden(config.feather_length, config.feather_width, config.feather_thickness);
                s.length *= r.length_scale;
                s.width *= r.width_scale;
                if config.feather_thickness <= 0.0 {
                    s.thickness *= r.width_scale;
                }
                s.with_segments(config.shaft_segments)
            })
            .collect()
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
#[derive(Clone, Debug, Default)]
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
    /// 0 after creation, then one more per step.
    pub frame_index: u64,
    /// Figures of the last static order.
    pub ordering_report: OrderingReport,
    /// Figures of the last create, step or evaluate.
    pub frame_report: FrameReport,
}

/// Buffers reused from call to call; never part of the state.
#[derive(Debug, Default)]
pub struct Workspace {
    /// The adjuster's own scratch.
    pub adjuster: Adjuster,
    /// ΔP of each pair.
    pub deltas: Vec<f32>,
    /// Shaft directions (the legacy rule's `o_i`).
    pub orientations: Vec<Vec3>,
}

impl Coat {
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

    /// Solves the coat from scratch at `positions`: neighbourhoods, the
    /// static order (Eq. 3, or Eq. 2 for the legacy mode) and the full
    /// three-step adjustment of every feather from a flat start.
    pub fn solve(
        &mut self,
        dressing: &Dressing,
        positions: &[Vec3],
        work: &mut Workspace,
        progress: &Progress,
    ) -> Result<()> {
        let start = Instant::now();
        self.pose(dressing, positions);
        progress.check(Phase::Ordering, 0.0)?;
        let order_start = Instant::now();
        self.neighbourhoods.rebuild(&self.frames, &dressing.reach, &dressing.neighbour_params);
        let neighbourhood_seconds = order_start.elapsed().as_secs_f64();
        progress.check(Phase::Ordering, 0.5)?;
        self.poses.clear();
        self.poses.resize(dressing.len(), FeatherPose::default());
        let pairs = self.neighbourhoods.pairs();
        match dressing.mode {
            Mode::Legacy => {
                // Eq. 2 with the feathers' own orientations (flat: o = õ).
                work.orientations.clear();
                work.orientations.extend(self.frames.iter().zip(&self.poses).map(|(f, p)| shaft_direction(f, *p)));
                Priorities::legacy(&self.frames, &work.orientations, dressing.gamma)
                    .deltas_of_pairs(pairs, &mut work.deltas)
            }
            Mode::Incremental | Mode::Rebuild => Priorities::improved(&self.frames, dressing.gamma, dressing.lambda)
                .deltas_of_pairs(pairs, &mut work.deltas),
        }
        let report = self.order.build_static(dressing.len(), pairs, &work.deltas);
        self.ordering_report = OrderingReport {
            pairs: report.pairs,
            edges: report.edges,
            dropped_edges: report.dropped,
            violations: report.violations,
            seconds: order_start.elapsed().as_secs_f64(),
        };
        progress.check(Phase::Adjusting, 0.0)?;
        self.body.rebuild(&self.positions, &dressing.triangles);
        let (offsets, indices) = self.neighbourhoods.obstacle_csr();
        let stats = work.adjuster.adjust_in_order_until(
            &self.frames,
            &dressing.shapes,
            &mut self.poses,
            self.order.order(),
            self.order.ranks(),
            CandidateLists::new(offsets, indices),
            &self.body,
            &dressing.adjust_params,
            AdjustSteps::Full,
            Selection::All,
            &|done| progress.check(Phase::Adjusting, done).is_ok(),
        );
        // A stopped adjustment (None) has set the progress's stop flag.
        progress.check(Phase::Adjusting, 1.0)?;
        let stats = stats.unwrap_or_default();
        self.staleness.reset(dressing.len());
        self.settling.clear();
        self.frame_report = FrameReport {
            frame_index: self.frame_index,
            adjusted: stats.adjusted,
            deformed: 0,
            seeds: dressing.len(),
            verified: 0,
            collision_tests: stats.collision_tests,
            priority_changes: 0,
            reversals: 0,
            reversals_refused: 0,
            cycles_broken: 0,
            clamped: stats.clamped,
            reorder_seconds: self.ordering_report.seconds,
            adjust_seconds: stats.seconds,
            step_seconds: start.elapsed().as_secs_f64(),
            neighbourhood_seconds,
            levels: stats.levels,
        };
        Ok(())
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

/// Saved state (see [`crate::snapshot`]): what determines every later
/// frame. Root frames, vertex normals and the body index are functions of
/// the positions, so they are recomputed on load rather than stored.
///
/// The blob is byte-reproducible: two identical runs save identical bytes,
/// so the report timings (run-dependent) are not stored; a loaded coat's
/// timings are 0 (loading adjusted nothing).
///
/// Layout: frame index (u64); welded positions (u64 count, then xyz f32
/// each); poses (u64 count of floats, then [`write_pose`] each: pitch,
/// roll, scale and the S − 1 joint bends); the ordering report (four u64
/// counts); the frame report (frame index and ten counts as u64, then the
/// level count u64); the neighbourhoods
/// ([`Neighbourhoods::write_state`]); the order ([`PriorityOrder::write_state`]);
/// the staleness ([`Staleness::write_state`]); the settling flags (u64
/// count, 0 or one per feather, then a byte 0 or 1 each).
impl Coat {
    /// Appends the coat's state to a state blob.
    pub fn write_state(&self, w: &mut Writer, joints: usize) {
        w.u64(self.frame_index);
        w.u64(3 * self.positions.len() as u64);
        for p in &self.positions {
            p.to_array().iter().for_each(|&x| w.f32(x));
        }
        w.u64(((POSE_FLOATS + joints) * self.poses.len()) as u64);
        self.poses.iter().for_each(|pose| write_pose(w, pose, joints));
        // Destructured in full (as in `read_state`) so that a new report
        // field cannot be forgotten here.
        // Timings are left out: they differ between identical runs.
        let OrderingReport { pairs, edges, dropped_edges, violations, seconds: _ } = self.ordering_report;
        [pairs, edges, dropped_edges, violations].iter().for_each(|&c| w.u64(c as u64));
        let FrameReport {
            frame_index,
            adjusted,
            deformed,
            seeds,
            verified,
            collision_tests,
            priority_changes,
            reversals,
            reversals_refused,
            cycles_broken,
            clamped,
            reorder_seconds: _,
            adjust_seconds: _,
            step_seconds: _,
            neighbourhood_seconds: _,
            levels,
        } = self.frame_report;
        w.u64(frame_index);
        [adjusted, deformed, seeds, verified].iter().for_each(|&c| w.u64(c as u64));
        w.u64(collision_tests);
        [priority_changes, reversals, reversals_refused, cycles_broken, clamped].iter().for_each(|&c| w.u64(c as u64));
        w.u64(levels as u64);
        self.neighbourhoods.write_state(w);
        self.order.write_state(w);
        self.staleness.write_state(w);
        w.u64(self.settling.len() as u64);
        self.settling.iter().for_each(|&s| w.u8(u8::from(s)));
    }

    /// Reads a coat written by [`write_state`](Self::write_state) for
    /// `dressing`, then recomputes the root frames, normals and body index
    /// from the positions (runs on the current rayon pool). Refuses with
    /// `InvalidState` a coat of another size, non-finite positions, poses
    /// outside the adjustment's limits, counts that do not fit, invalid
    /// neighbourhoods or order (see their `read_state`), or an order whose
    /// pair set is not the neighbourhoods'.
    pub fn read_state(r: &mut Reader<'_>, dressing: &Dressing) -> Result<Self> {
        let n = dressing.len();
        let frame_index = r.u64()?;
        r.len(4, Some(3 * dressing.surface.vertex_count()))?;
        let mut positions = Vec::with_capacity(dressing.surface.vertex_count());
        for _ in 0..dressing.surface.vertex_count() {
            let p = Vec3::new(r.f32()?, r.f32()?, r.f32()?);
            if !p.is_finite() {
                return Err(invalid_state("saved positions are not finite"));
            }
            positions.push(p);
        }
        let joints = dressing.shaft_joints();
        r.len(4, Some((POSE_FLOATS + joints) * n))?;
        let mut poses = Vec::with_capacity(n);
        for _ in 0..n {
            poses.push(read_pose(r, dressing, joints)?);
        }
        let ordering_report = OrderingReport {
            pairs: count(r)?,
            edges: count(r)?,
            dropped_edges: count(r)?,
            violations: count(r)?,
            seconds: 0.0,
        };
        let frame_report = FrameReport {
            frame_index: r.u64()?,
            adjusted: count(r)?,
            deformed: count(r)?,
            seeds: count(r)?,
            verified: count(r)?,
            collision_tests: r.u64()?,
            priority_changes: count(r)?,
            reversals: count(r)?,
            reversals_refused: count(r)?,
            cycles_broken: count(r)?,
            clamped: count(r)?,
            reorder_seconds: 0.0,
            adjust_seconds: 0.0,
            step_seconds: 0.0,
            neighbourhood_seconds: 0.0,
            levels: count(r)?,
        };
        let neighbourhoods = Neighbourhoods::read_state(r, n)?;
        let order = PriorityOrder::read_state(r, n)?;
        let staleness = Staleness::read_state(r, n)?;
        let settling_count = r.len(1, None)?;
        if settling_count != 0 && settling_count != n {
            return Err(invalid_state("the saved settling flags are not one per feather"));
        }
        let mut settling = Vec::with_capacity(settling_count);
        for _ in 0..settling_count {
            match r.u8()? {
                0 => settling.push(false),
                1 => settling.push(true),
                _ => return Err(invalid_state("a saved settling flag is not 0 or 1")),
            }
        }
        if order.pairs() != neighbourhoods.pairs() {
            return Err(invalid_state("the saved order's pairs are not the saved neighbourhoods' pairs"));
        }
        let mut coat = Coat {
            poses,
            neighbourhoods,
            order,
            staleness,
            settling,
            frame_index,
            ordering_report,
            frame_report,
            ..Coat::default()
        };
        coat.pose(dressing, &positions);
        coat.body.rebuild(&coat.positions, &dressing.triangles);
        Ok(coat)
    }
}

/// Floats of a pose before its bends.
const POSE_FLOATS: usize = 3;

/// One feather's pose in a state blob: pitch, roll, scale and the bends of
/// its `joints` joints (f32 each). The one place the pose's encoding lives,
/// with [`read_pose`].
fn write_pose(w: &mut Writer, pose: &FeatherPose, joints: usize) {
    w.f32(pose.pitch);
    w.f32(pose.roll);
    w.f32(pose.scale);
    pose.bends[..joints].iter().for_each(|&b| w.f32(b));
}

/// Reads a pose of [`write_pose`], refusing one outside the adjustment's limits.
fn read_pose(r: &mut Reader<'_>, dressing: &Dressing, joints: usize) -> Result<FeatherPose> {
    let limits = &dressing.adjust_params;
    let mut pose = FeatherPose::new(r.f32()?, r.f32()?).with_scale(r.f32()?);
    for b in &mut pose.bends[..joints] {
        *b = r.f32()?;
    }
    let (bend_low, bend_high) = limits.bend_range();
    let bent_within = pose.bends.iter().all(|b| (bend_low..=bend_high).contains(b));
    if !(bent_within
        && pose.pitch >= limits.min_pitch
        && pose.pitch <= limits.max_pitch
        && pose.roll.abs() <= limits.max_roll
        && (pose.scale >= limits.min_scale || pose.scale == 0.0)
        && pose.scale <= 1.0)
    {
        return Err(invalid_state("a saved feather pose lies outside the pitch, roll, size and bend limits"));
    }
    Ok(pose)
}

/// A count stored as u64 that must fit a `usize`.
fn count(r: &mut Reader<'_>) -> Result<usize> {
    usize::try_from(r.u64()?).map_err(|_| invalid_state("a saved count does not fit this platform"))
}

fn invalid_state(message: &str) -> Error {
    Error::new(ErrorKind::InvalidState, message)
}
