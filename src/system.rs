//! `System`: the safe Rust face of Plumage. It owns the welded mesh, the
//! feathers' rest binding (the dressing) and their state at the current pose
//! (the coat), and is what the FFI handle wraps.

use crate::animation::coherence::{PoseChanges, pose_changes};
use crate::coat::{Coat, Dressing};
use crate::config::SamplerKind;
use crate::config::{Config, Mode};
use crate::error::Result;
use crate::error::{Error, ErrorKind};
use crate::feather::pose_change;
use crate::feather::{FeatherMesh, FeatherPose, FeatherTriangles, MAX_TRIANGLES, triangles_per_feather};
use crate::field::Fields;
use crate::frame::{StepWorkspace, Workspace};
use crate::mesh::{MeshInput, WeldedMesh, check_frame_positions, weld};
use crate::pool::WorkerPool;
use crate::progress::{Phase, Progress};
use crate::rng::hash64;
use crate::sampling::sample_roots_with_progress;
use crate::snapshot::{Reader, Writer};
use crate::stats::{FeatherRecord, FrameReport, OrderingReport, PartReport, SamplingReport, ValidationReport};
use crate::surface::Surface;
use crate::validation::{ProbeSkin, Validation, ValidationInput, validate_part, validate_with_progress};
use glam::Vec3;
use std::collections::BTreeMap;

/// Probes per feather for the coverage figure of [`System::validate`].
const COVERAGE_PROBES_PER_FEATHER: usize = 4;
/// Bounds on the number of coverage probes.
const COVERAGE_PROBES_MIN: usize = 2_000;
const COVERAGE_PROBES_MAX: usize = 200_000;

/// A feathered surface: created at the rest pose, then stepped frame by frame.
#[derive(Debug)]
pub struct System {
    pool: WorkerPool,
    mesh: WeldedMesh,
    dressing: Dressing,
    sampling: SamplingReport,
    coat: Coat,
    records: Vec<FeatherRecord>,
    triangles: Vec<[f32; 3]>,
    work: Workspace,
    step_work: StepWorkspace,
    frame_positions: Vec<Vec3>,
    /// The poses before the last step or evaluate, and how they changed.
    previous_poses: Vec<FeatherPose>,
    pose_changes: PoseChanges,
    /// State blobs by frame count (see [`System::seek`]).
    checkpoints: BTreeMap<u64, Vec<u8>>,
    /// Whether the coat is what stepping from create gives (no evaluate or
    /// load since create or the last seek): only then are checkpoints kept.
    on_playback: bool,
    #[cfg(feature = "test-hooks")]
    test_panic: std::sync::atomic::AtomicBool,
}

impl System {
    /// Checks the configuration and the mesh, plants the roots, orders and
    /// adjusts the feathers at the rest pose.
    pub fn new(config: &Config, mesh: &MeshInput<'_>) -> Result<Self> {
        Self::new_with_progress(config, mesh, &Progress::none())
    }

    /// As [`System::new`], reporting to `progress`, which may stop it (then
    /// nothing is created).
    pub fn new_with_progress(config: &Config, mesh: &MeshInput<'_>, progress: &Progress) -> Result<Self> {
        Self::new_with_parallel_for(config, mesh, progress, None)
    }

    /// As [`System::new_with_progress`]; with `parallel_for`, every parallel
    /// section of this system runs through the host's parallel-for,
    /// `config.threads` tasks at a time (see [`crate::pool`]).
    pub fn new_with_parallel_for(
        config: &Config,
        mesh: &MeshInput<'_>,
        progress: &Progress,
        parallel_for: Option<std::sync::Arc<dyn crate::pool::ParallelFor>>,
    ) -> Result<Self> {
        config.validate()?;
        progress.check(Phase::Preparing, 0.0)?;
        mesh.check()?;
        let welded = weld(mesh)?;
        progress.check(Phase::Preparing, 0.3)?;
        let pool = match parallel_for {
            Some(host) => WorkerPool::with_parallel_for(config.threads, host)?,
            None => WorkerPool::new(config.threads)?,
        };
        let surface = Surface::new(&welded);
        progress.check(Phase::Preparing, 0.6)?;
        let attribute = |a: Option<&[f32]>, stride| a.map(|v| welded.weld_attribute(v, stride));
        let fields = Fields::new(
            &welded,
            &surface,
            attribute(mesh.orientations, 3).as_deref(),
            attribute(mesh.spacing_scale, 1).as_deref(),
            attribute(mesh.length_scale, 1).as_deref(),
            attribute(mesh.width_scale, 1).as_deref(),
            config,
        )?;
        progress.check(Phase::Sampling, 0.0)?;
        let sampling = pool.install(|| sample_roots_with_progress(&welded, &surface, &fields, config, progress))?;
        progress.check(Phase::Sampling, 1.0)?;
        let mut dressing = Dressing::new(surface, &welded, sampling.roots, config);
        if fields.vertex_spacing_scales().iter().any(|&s| s <= 0.0) {
            dressing.feathered = fields.vertex_spacing_scales().iter().map(|&s| s > 0.0).collect();
        }
        let sampling_report = SamplingReport {
            roots: dressing.len(),
            spacing: sampling.spacing,
            relative_radius: sampling.metrics.relative_radius,
            coverage_gap: sampling.metrics.coverage_gap,
            alignment: sampling.metrics.alignment,
            seconds: sampling.seconds,
        };
        let mut system = Self {
            pool,
            mesh: welded,
            dressing,
            sampling: sampling_report,
            coat: Coat::default(),
            records: Vec::new(),
            triangles: Vec::new(),
            work: Workspace::default(),
            step_work: StepWorkspace::default(),
            frame_positions: Vec::new(),
            previous_poses: Vec::new(),
            pose_changes: PoseChanges::default(),
            checkpoints: BTreeMap::new(),
            on_playback: true,
            #[cfg(feature = "test-hooks")]
            test_panic: Default::default(),
        };
        let rest = system.mesh.positions.clone();
        let Self { pool, dressing, coat, work, .. } = &mut system;
        pool.install(|| crate::frame::solve(coat, dressing, &rest, work, progress))?;
        system.export();
        system.keep_checkpoint();
        Ok(system)
    }

    /// Test builds only: the next step, evaluate or validate panics.
    #[cfg(feature = "test-hooks")]
    pub fn arm_test_panic(&mut self) {
        self.test_panic.store(true, std::sync::atomic::Ordering::SeqCst);
    }

    fn maybe_test_panic(&self) {
        #[cfg(feature = "test-hooks")]
        if self.test_panic.swap(false, std::sync::atomic::Ordering::SeqCst) {
            panic!("forced by plumage_testing_panic_on_next_call");
        }
    }

    /// The configuration the system was created with.
    pub fn config(&self) -> &Config {
        &self.dressing.config
    }

    /// The welded mesh (rest pose).
    pub fn mesh(&self) -> &WeldedMesh {
        &self.mesh
    }

    /// Welded vertex positions of the current pose.
    pub fn current_positions(&self) -> &[Vec3] {
        &self.coat.positions
    }

    /// Number of vertices every frame must provide (the caller's numbering).
    pub fn vertex_count(&self) -> usize {
        self.mesh.caller_vertex_count()
    }

    /// Frames stepped since creation (evaluate does not count).
    pub fn frames_stepped(&self) -> u64 {
        self.coat.frame_index
    }

    /// Number of worker threads of the system's pool.
    pub fn threads(&self) -> usize {
        self.pool.threads()
    }

    /// Number of triangles of the caller's rest mesh (degenerate and
    /// duplicate ones included).
    pub fn caller_triangle_count(&self) -> usize {
        self.mesh.triangles.len() + self.mesh.degenerate_triangles + self.mesh.duplicate_triangles
    }

    /// Number of feathers.
    pub fn feather_count(&self) -> usize {
        self.records.len()
    }

    /// The feathers at the current pose, in a stable order (by root).
    pub fn feathers(&self) -> &[FeatherRecord] {
        &self.records
    }

    /// Each feather's triangles (see [`crate::feather::FeatherTriangles`]:
    /// two, one per vane, for the kite) as their corners, world space,
    /// feather after feather in the order of [`System::feathers`].
    pub fn feather_triangles(&self) -> &[[f32; 3]] {
        &self.triangles
    }

    /// Every feather as a mesh (vertices, normals, UVs, triangles, the
    /// feather of each vertex), in the order of [`System::feathers`].
    pub fn feather_mesh(&self) -> FeatherMesh {
        FeatherMesh::build(&self.coat.frames, &self.dressing.shapes, &self.coat.poses)
    }

    /// Which feathers the last create, step or evaluate readjusted (one flag
    /// per feather, in the order of [`System::feathers`]).
    pub fn readjusted(&self) -> &[bool] {
        self.work.adjuster.adjusted()
    }

    /// Sampling figures of the roots.
    pub fn sampling_report(&self) -> Option<SamplingReport> {
        Some(self.sampling)
    }

    /// Figures of the static order built by create, evaluate or a rebuild frame.
    pub fn ordering_report(&self) -> Option<OrderingReport> {
        Some(self.coat.ordering_report)
    }

    /// What the last create, step or evaluate did.
    pub fn frame_report(&self) -> Option<FrameReport> {
        Some(self.coat.frame_report)
    }

    /// How the feathers' poses relative to their roots changed in the last
    /// step or evaluate (none after create or a load): the pops figure.
    pub fn pose_changes(&self) -> PoseChanges {
        self.pose_changes
    }

    /// Exact validation of the current feathers (DESIGN.md §6).
    pub fn validate(&self) -> Option<ValidationReport> {
        self.validate_with_progress(&Progress::none()).expect("validation without a progress sink is never interrupted")
    }

    /// As [`System::validate`], reporting to `progress`, which may stop it
    /// (`Interrupted`; validation never changes the system).
    pub fn validate_with_progress(&self, progress: &Progress) -> Result<Option<ValidationReport>> {
        self.maybe_test_panic();
        let n = self.dressing.len();
        let tris = self.feather_triangle_sets();
        let skin = ProbeSkin {
            positions: &self.coat.positions,
            triangles: &self.dressing.triangles,
            feathered: &self.dressing.feathered,
        };
        let input = self.validation_input(&tris, &skin, coverage_probes(n));
        let v = self.pool.install(|| validate_with_progress(&input, progress))?;
        Ok(Some(validation_report(&v)))
    }

    /// [`System::validate`] restricted to the part of the mesh made of the
    /// caller's triangles `triangles` (e.g. one of several meshes dressed as
    /// one system): the pairs with at least one of its feathers (every other
    /// feather counts as an obstacle), its feathers' body penetrations, pitch
    /// and tip heights, and coverage probes drawn on its skin (covered by
    /// any feather), as many per feather as the whole validation draws.
    pub fn validate_part(&self, triangles: std::ops::Range<u32>) -> Option<ValidationReport> {
        self.maybe_test_panic();
        let member: Vec<bool> = self.records.iter().map(|r| triangles.contains(&r.triangle)).collect();
        let members = member.iter().filter(|&&m| m).count();
        let skin: Vec<[u32; 3]> = (self.dressing.triangles.iter().zip(&self.dressing.source_triangle))
            .filter(|&(_, s)| triangles.contains(s))
            .map(|(&t, _)| t)
            .collect();
        let tris = self.feather_triangle_sets();
        let skin = ProbeSkin { positions: &self.coat.positions, triangles: &skin, feathered: &self.dressing.feathered };
        let input = self.validation_input(&tris, &skin, coverage_probes(members));
        let v = self.pool.install(|| validate_part(&input, &member));
        Some(validation_report(&v))
    }

    /// What a validation of the current coat looks at, with the coverage
    /// probes drawn on `skin`.
    fn validation_input<'a>(
        &'a self,
        feather_triangles: &'a [FeatherTriangles],
        skin: &'a ProbeSkin<'a>,
        probes: usize,
    ) -> ValidationInput<'a> {
        let c = &self.coat;
        ValidationInput {
            feather_triangles,
            frames: &c.frames,
            shapes: &self.dressing.shapes,
            poses: &c.poses,
            body: &c.body,
            skin,
            probes,
            seed: self.dressing.config.seed,
        }
    }

    /// The last create, step or evaluate's figures restricted to the
    /// feathers rooted on the caller's triangles `triangles`.
    pub fn part_report(&self, triangles: std::ops::Range<u32>) -> PartReport {
        let readjusted = self.readjusted();
        let mut r = PartReport::default();
        for (i, record) in self.records.iter().enumerate() {
            if !triangles.contains(&record.triangle) {
                continue;
            }
            r.feathers += 1;
            r.placed += usize::from(record.length > 0.0);
            r.adjusted += usize::from(readjusted.get(i).copied().unwrap_or(false));
            if let (Some(before), Some(after)) = (self.previous_poses.get(i), self.coat.poses.get(i)) {
                let change = pose_change(before, after);
                r.pops += usize::from(change > self.dressing.config.pop_threshold);
                r.largest_pose_change = r.largest_pose_change.max(change);
            }
        }
        r
    }

    /// Each feather's triangles at the current pose, as the validation takes them.
    fn feather_triangle_sets(&self) -> Vec<FeatherTriangles> {
        let mut corners = self.triangles.iter().map(|&p| Vec3::from_array(p));
        self.dressing
            .shapes
            .iter()
            .map(|shape| {
                let mut t = [[Vec3::ZERO; 3]; MAX_TRIANGLES];
                let n = triangles_per_feather(shape);
                for triangle in &mut t[..n] {
                    *triangle = std::array::from_fn(|_| corners.next().unwrap_or(Vec3::NAN));
                }
                FeatherTriangles::from_slice(&t[..n])
            })
            .collect()
    }

    /// Advances to the next animation frame by the system's mode. On error
    /// nothing changes.
    pub fn step(&mut self, positions: &[f32]) -> Result<()> {
        self.step_with_progress(positions, &Progress::none())
    }

    /// As [`System::step`], reporting to `progress`, which may stop it.
    pub fn step_with_progress(&mut self, positions: &[f32], progress: &Progress) -> Result<()> {
        self.maybe_test_panic();
        check_frame_positions(positions, self.vertex_count())?;
        self.transaction(positions, progress, |s, p| {
            let Self { pool, dressing, coat, work, step_work, frame_positions, .. } = s;
            pool.install(|| crate::frame::advance(coat, dressing, frame_positions, work, step_work, p))
        })?;
        self.keep_checkpoint();
        Ok(())
    }

    /// Solves the pose from scratch, independent of history (the frame count
    /// is kept). On error nothing changes.
    pub fn evaluate(&mut self, positions: &[f32]) -> Result<()> {
        self.evaluate_with_progress(positions, &Progress::none())
    }

    /// As [`System::evaluate`], reporting to `progress`, which may stop it.
    pub fn evaluate_with_progress(&mut self, positions: &[f32], progress: &Progress) -> Result<()> {
        self.maybe_test_panic();
        check_frame_positions(positions, self.vertex_count())?;
        self.transaction(positions, progress, |s, p| {
            let Self { pool, dressing, coat, work, frame_positions, .. } = s;
            pool.install(|| crate::frame::solve(coat, dressing, frame_positions, work, p))
        })?;
        // Later steps no longer continue the playback: keep no checkpoint
        // of them until a seek.
        self.on_playback = false;
        Ok(())
    }

    /// Runs `update` on the welded `positions`; when it fails (it can only
    /// be interrupted) the coat is restored to what it was.
    fn transaction(
        &mut self,
        positions: &[f32],
        progress: &Progress,
        update: impl FnOnce(&mut Self, &Progress) -> Result<()>,
    ) -> Result<()> {
        self.mesh.welded_positions_into(positions, &mut self.frame_positions);
        let older_poses = std::mem::replace(&mut self.previous_poses, self.coat.poses.clone());
        let backup = progress.is_interruptible().then(|| (self.coat.clone(), self.work.adjuster.adjusted().to_vec()));
        let result = update(self, progress);
        match result {
            Ok(()) => {
                self.pose_changes =
                    pose_changes(&self.previous_poses, &self.coat.poses, self.dressing.config.pop_threshold);
                self.export()
            }
            Err(_) => {
                self.previous_poses = older_poses;
                if let Some((coat, readjusted)) = backup {
                    self.coat = coat;
                    self.work.adjuster.set_adjusted(&readjusted);
                }
            }
        }
        result
    }

    fn export(&mut self) {
        let Self { coat, dressing, records, triangles, .. } = self;
        coat.export(dressing, records, triangles);
    }
}

/// Saved state: save a frame, resume from it (see [`crate::snapshot`] for
/// the blob's header and checksum). The payload is the coat
/// ([`Coat::write_state`]), then the flags of [`System::readjusted`] (u64
/// count, one byte 0 or 1 per feather): a per-frame report the adjuster's
/// workspace keeps.
impl System {
    /// The state of the current frame as a self-contained blob: resuming
    /// from it with [`System::load_state`] gives byte-identical later frames.
    /// Only the per-frame state is stored; what never changes after
    /// creation is identified by the blob's fingerprint.
    pub fn save_state(&self) -> Vec<u8> {
        let mut w = Writer::new(self.state_fingerprint());
        self.coat.write_state(&mut w, self.dressing.shaft_joints());
        let readjusted = self.readjusted();
        w.u64(readjusted.len() as u64);
        readjusted.iter().for_each(|&f| w.u8(u8::from(f)));
        w.finish()
    }

    /// Resumes from a blob of [`System::save_state`]: the feathers, reports
    /// and frame count become those of the saved frame. A truncated,
    /// corrupt or foreign blob (another mesh, roots or configuration) is
    /// refused with `InvalidState` and nothing changes: the blob is parsed
    /// and checked in full before it replaces the current frame.
    pub fn load_state(&mut self, blob: &[u8]) -> Result<()> {
        let mut reader = Reader::open(blob, self.state_fingerprint())?;
        let dressing = &self.dressing;
        let coat = self.pool.install(|| Coat::read_state(&mut reader, dressing))?;
        let n = reader.len(1, Some(dressing.len()))?;
        let mut readjusted = Vec::with_capacity(n);
        for _ in 0..n {
            match reader.u8()? {
                0 => readjusted.push(false),
                1 => readjusted.push(true),
                _ => return Err(Error::new(ErrorKind::InvalidState, "a saved readjustment flag is not 0 or 1")),
            }
        }
        reader.finish()?;
        self.coat = coat;
        self.work.adjuster.set_adjusted(&readjusted);
        self.pose_changes = PoseChanges::default();
        self.previous_poses.clear();
        self.export();
        self.on_playback = false;
        Ok(())
    }

    /// Keyframed checkpoints (`Config::checkpoint_interval` K > 0): after
    /// create and every K-th step of the playback, the system keeps its
    /// state blob. `seek(frame)` prepares the system to reach the state
    /// after `frame` steps and returns the frame count it now stands at:
    /// the caller steps it with the positions of the frames from there up
    /// to `frame`, and gets the bytes playback gave. Seeking forward from
    /// the current frame of the playback keeps it (the caller replays
    /// from there); otherwise the nearest checkpoint at or before `frame`
    /// is loaded. Refused with `InvalidArgument` when checkpoints are off;
    /// nothing changes on error.
    pub fn seek(&mut self, frame: u64) -> Result<u64> {
        if self.dressing.config.checkpoint_interval == 0 {
            return Err(Error::new(
                ErrorKind::InvalidArgument,
                "config.checkpoint_interval is 0: no checkpoints are kept to seek with",
            ));
        }
        let (&at, blob) =
            self.checkpoints.range(..=frame).next_back().expect("the checkpoint after create is always kept");
        let here = self.coat.frame_index;
        if self.on_playback && here <= frame && here >= at {
            return Ok(here);
        }
        let blob = blob.clone();
        self.load_state(&blob)?;
        self.on_playback = true;
        Ok(at)
    }

    /// The frame counts of the checkpoints kept, oldest first.
    pub fn checkpoint_frames(&self) -> Vec<u64> {
        self.checkpoints.keys().copied().collect()
    }

    /// Keeps the current state as a checkpoint when it is one (see
    /// [`System::seek`]), dropping the oldest past the cap (never the one
    /// after create).
    fn keep_checkpoint(&mut self) {
        let every = u64::from(self.dressing.config.checkpoint_interval);
        let frame = self.coat.frame_index;
        if every == 0 || !self.on_playback || frame % every != 0 {
            return;
        }
        let blob = self.save_state();
        self.checkpoints.insert(frame, blob);
        while self.checkpoints.len() > self.dressing.config.checkpoint_cap as usize + 1 {
            let oldest = self.checkpoints.keys().copied().find(|&k| k != 0).expect("more than one checkpoint");
            self.checkpoints.remove(&oldest);
        }
    }

    /// What a blob must match to be loaded: a hash of every configuration
    /// field that can change a result (all but the thread count, which
    /// never does), the welded rest mesh (positions bit for bit, triangles,
    /// caller vertex count) and every root's binding and shape.
    fn state_fingerprint(&self) -> u64 {
        // Destructured in full so that a new field cannot be forgotten here.
        let Config {
            seed,
            threads: _,
            sampler,
            mode,
            spacing,
            target_feathers,
            theta,
            randomness,
            pool_factor,
            feather_length,
            feather_width,
            feather_thickness,
            gamma,
            lambda,
            k_neighbours,
            height_field_u,
            height_field_v,
            fluffiness,
            collision_allowance,
            theta_s,
            drift_tolerance,
            flow_axis,
            flow_source,
            recompute_neighbourhoods,
            curvature_min_scale,
            shaft_segments,
            bend_limit,
            length_per_spacing,
            width_per_spacing,
            pop_threshold: _,
            settle_rate,
            checkpoint_interval: _,
            checkpoint_cap: _,
        } = &self.dressing.config;
        let bits = |x: f32| u64::from(x.to_bits());
        let mut words = vec![
            *seed,
            match sampler {
                SamplerKind::Guided => 0,
                SamplerKind::Random => 1,
            },
            match mode {
                Mode::Incremental => 0,
                Mode::Legacy => 1,
                Mode::Rebuild => 2,
            },
            *target_feathers as u64,
            *k_neighbours as u64,
            *height_field_u as u64,
            *height_field_v as u64,
            u64::from(*recompute_neighbourhoods),
            u64::from(flow_source.is_some()),
            u64::from(*shaft_segments),
        ];
        words.extend(
            [
                *spacing,
                *theta,
                *randomness,
                *pool_factor,
                *feather_length,
                *feather_width,
                *feather_thickness,
                *gamma,
                *lambda,
                *fluffiness,
                *collision_allowance,
                *theta_s,
                *drift_tolerance,
                *settle_rate,
                *curvature_min_scale,
                *bend_limit,
                *length_per_spacing,
                *width_per_spacing,
                flow_axis.x,
                flow_axis.y,
                flow_axis.z,
            ]
            .map(bits),
        );
        words.extend(flow_source.unwrap_or(Vec3::ZERO).to_array().map(bits));
        let mesh = &self.mesh;
        words.push(mesh.caller_vertex_count() as u64);
        words.push(mesh.positions.len() as u64);
        words.extend(mesh.positions.iter().flat_map(|p| p.to_array().map(bits)));
        words.push(mesh.triangles.len() as u64);
        words.extend(mesh.triangles.iter().flat_map(|t| t.map(u64::from)));
        let dressing = &self.dressing;
        words.push(dressing.len() as u64);
        for (root, shape) in dressing.roots.iter().zip(&dressing.shapes) {
            words.extend([root.id, u64::from(root.point.face)]);
            words.extend(root.point.bary.map(bits));
            words.extend(root.rest_direction.map(bits));
            words.extend([root.spacing, root.length_scale, root.width_scale].map(bits));
            words.extend([shape.length, shape.width, shape.thickness, shape.vane_split].map(bits));
            words.push(u64::from(shape.segments));
        }
        hash64(&words)
    }
}

/// Coverage probes for a validation of `feathers` feathers.
fn coverage_probes(feathers: usize) -> usize {
    (COVERAGE_PROBES_PER_FEATHER * feathers).clamp(COVERAGE_PROBES_MIN, COVERAGE_PROBES_MAX)
}

fn validation_report(v: &Validation) -> ValidationReport {
    ValidationReport {
        intersecting_pairs: v.intersecting_pairs.len(),
        body_penetrations: v.body_penetrations.len(),
        coverage: v.coverage,
        probes: v.probes,
        buried_probes: v.buried_probes,
        mean_pitch_deg: v.mean_pitch_deg,
        tip_height_median: v.tip_heights.median,
        tip_height_p90: v.tip_heights.p90,
        bristle_percent: v.tip_heights.bristle_percent,
    }
}
