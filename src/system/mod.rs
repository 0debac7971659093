//! `System`: the safe Rust face of Plumage. It owns the welded mesh, the
//! feathers' rest binding (the dressing) and their state at the current pose
//! (the coat), and is what the FFI handle wraps.

use crate::animation::coherence::{PoseChanges, changed_feathers, pose_changes};
use crate::coat::{Coat, Dressing};
use crate::config::Config;
use crate::error::Result;
use crate::feather::{FeatherMesh, FeatherPose, FeatherTemplate, InstanceRecord};
use crate::field::{Fields, VertexMaps};
use crate::frame::{StepWorkspace, Workspace};
use crate::geometry::RootFrame;
use crate::memory::MemoryUse;
use crate::mesh::{MeshInput, WeldedMesh, check_frame_positions, weld};
use crate::progress::{Phase, Progress};
use crate::sampling::plant_roots_with_progress;
use crate::stats::{FeatherRecord, FrameReport, OrderingReport, SamplingReport};
use crate::surface::Surface;
use crate::workers::WorkerPool;
use glam::Vec3;
use std::collections::BTreeMap;

mod blob;
mod validate;

/// A feathered surface: created at the rest pose, then stepped frame by frame.
#[derive(Debug)]
pub struct System {
    pool: WorkerPool,
    mesh: WeldedMesh,
    dressing: Dressing,
    sampling: SamplingReport,
    coat: Coat,
    /// The coat as it was before the call under way, when that call may
    /// fail (it can be stopped, or a memory limit is set): restored if it
    /// does. Cloned into in place, so its buffers serve every frame; empty
    /// after a call that could not fail, or that failed.
    backup: Coat,
    records: Vec<FeatherRecord>,
    triangles: Vec<[f32; 3]>,
    work: Workspace,
    step_work: StepWorkspace,
    frame_positions: Vec<Vec3>,
    /// The poses before the last step or evaluate, and how they changed.
    previous_poses: Vec<FeatherPose>,
    /// The poses `previous_poses` held before the call under way, given
    /// back to it if that call fails (a spare buffer otherwise).
    older_poses: Vec<FeatherPose>,
    pose_changes: PoseChanges,
    /// The root frames before the last step or evaluate.
    previous_frames: Vec<RootFrame>,
    /// The feathers whose placement the last call changed (see
    /// [`System::changed_feathers`]), how many of them changed their pose,
    /// and whether the list holds every feather because the previous
    /// result is not comparable.
    changed: Vec<u32>,
    reposed: usize,
    all_changed: bool,
    /// State blobs by frame count (see [`System::seek`]).
    checkpoints: BTreeMap<u64, Vec<u8>>,
    /// Whether the coat is what stepping from create gives (no evaluate or
    /// load since create or the last seek): only then are checkpoints kept.
    on_playback: bool,
    #[cfg(feature = "test-hooks")]
    test_panic: std::sync::atomic::AtomicBool,
}

/// What the mesh's vertex maps give the dressing: which vertices are
/// feathered (a spacing scale above 0), the roots' layers and their
/// feather types.
fn dress_from_vertex_maps(dressing: &mut Dressing, welded: &WeldedMesh, mesh: &MeshInput<'_>, fields: &Fields) {
    if fields.vertex_spacing_scales().iter().any(|&s| s <= 0.0) {
        dressing.feathered = fields.vertex_spacing_scales().iter().map(|&s| s > 0.0).collect();
    }
    // One layer everywhere orders nothing: kept as no layers at all.
    if let Some(layer) = mesh.layer.map(|v| welded.weld_attribute(v, 1)).filter(|l| l.iter().any(|&v| v != l[0])) {
        dressing.layers =
            dressing.roots.iter().map(|r| crate::field::blend_at(&layer, &dressing.surface, r.point)).collect();
    }
    if let Some(map) = mesh.feather_types {
        // Indices below 256 are exact as floats, so they weld as floats.
        let per_vertex: Vec<f32> = map.per_vertex.iter().map(|&t| t as f32).collect();
        let welded_types = welded.weld_attribute(&per_vertex, 1);
        let triangles = dressing.surface.triangles();
        let kinds: Vec<u8> = (dressing.roots.iter())
            .map(|r| {
                let corner = (0..3).max_by(|&a, &b| r.point.bary[a].total_cmp(&r.point.bary[b])).unwrap_or(0);
                welded_types[triangles[r.point.face as usize][corner] as usize] as u8
            })
            .collect();
        dressing.retype(map.types, &kinds);
    }
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
    /// `config.threads` tasks at a time (see [`crate::workers`]).
    pub fn new_with_parallel_for(
        config: &Config,
        mesh: &MeshInput<'_>,
        progress: &Progress,
        parallel_for: Option<std::sync::Arc<dyn crate::workers::ParallelFor>>,
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
        let skeleton_flow = mesh.skeleton.map(|skeleton| {
            let hints = skeleton.flow_hints(mesh.positions, crate::skeleton::front(config.flow_axis));
            welded.weld_attribute(&hints.iter().flat_map(|h| h.to_array()).collect::<Vec<f32>>(), 3)
        });
        let welded_maps = [
            attribute(mesh.orientations, 3),
            attribute(mesh.spacing_scale, 1),
            attribute(mesh.length_scale, 1),
            attribute(mesh.width_scale, 1),
        ];
        let [orientations, spacing_scale, length_scale, width_scale] = welded_maps.each_ref().map(|m| m.as_deref());
        let maps = VertexMaps {
            orientations,
            skeleton_flow: skeleton_flow.as_deref(),
            spacing_scale,
            length_scale,
            width_scale,
        };
        let fields = Fields::new(&welded, &surface, &maps, config)?;
        if config.spacing <= 0.0 {
            check_feather_arrays(config, crate::sampling::target_feathers(config))?;
        }
        progress.check(Phase::Sampling, 0.0)?;
        let mut planted = pool.install(|| plant_roots_with_progress(&welded, &surface, &fields, config, progress))?;
        check_feather_arrays(config, planted.roots.len())?;
        progress.check(Phase::Sampling, 1.0)?;
        let mut dressing = Dressing::new(surface, &welded, std::mem::take(&mut planted.roots), config);
        dress_from_vertex_maps(&mut dressing, &welded, mesh, &fields);
        // The metrics are measured below, beside the static adjustment.
        let sampling_report = SamplingReport {
            roots: dressing.len(),
            spacing: planted.spacing,
            relative_radius: f32::NAN,
            coverage_gap: f32::NAN,
            alignment: f32::NAN,
            seconds: planted.seconds,
            field_singularities: singular_faces_on_feathers(&welded, &fields),
        };
        let mut system = Self::fresh(pool, welded, dressing, sampling_report);
        let rest = system.mesh.positions.clone();
        let Self { pool, dressing, coat, work, sampling, .. } = &mut system;
        let dressing = &*dressing;
        // The sampling metrics only report on the roots: they run beside the
        // static adjustment, which leaves a second thread mostly idle (its
        // levels hold a few feathers each). Neither reads what the other
        // writes, so the results are those of running them one after the
        // other.
        let metrics = pool.install(|| {
            crate::frame::solve_beside(coat, dressing, &rest, work, progress, || {
                planted.metrics(&dressing.surface, &rest, &fields, &dressing.roots, config.theta, progress)
            })
        })??;
        sampling.relative_radius = metrics.relative_radius;
        sampling.coverage_gap = metrics.coverage_gap;
        sampling.alignment = metrics.alignment;
        system.export();
        system.all_changed_now();
        system.keep_checkpoint();
        if config.memory_limit > 0 {
            let held = system.memory().total();
            if held > config.memory_limit {
                return Err(crate::memory::over_limit("the system would hold", held, config.memory_limit));
            }
        }
        Ok(system)
    }

    /// A system over `mesh` and `dressing` before its first adjustment.
    fn fresh(pool: WorkerPool, mesh: WeldedMesh, dressing: Dressing, sampling: SamplingReport) -> Self {
        Self {
            pool,
            mesh,
            dressing,
            sampling,
            coat: Coat::default(),
            backup: Coat::default(),
            records: Vec::new(),
            triangles: Vec::new(),
            work: Workspace::default(),
            step_work: StepWorkspace::default(),
            frame_positions: Vec::new(),
            previous_poses: Vec::new(),
            older_poses: Vec::new(),
            pose_changes: PoseChanges::default(),
            previous_frames: Vec::new(),
            changed: Vec::new(),
            reposed: 0,
            all_changed: true,
            checkpoints: BTreeMap::new(),
            on_playback: true,
            #[cfg(feature = "test-hooks")]
            test_panic: Default::default(),
        }
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

    /// The heap bytes the system holds, by part (see [`MemoryUse`]). Every
    /// field is named, so a new one must be given a part.
    pub fn memory(&self) -> MemoryUse {
        use crate::memory::HeapSize;
        let Self {
            pool: _,
            mesh,
            dressing,
            sampling: _,
            coat,
            backup,
            records,
            triangles,
            work,
            step_work,
            frame_positions,
            previous_poses,
            older_poses,
            previous_frames,
            changed,
            reposed: _,
            all_changed: _,
            pose_changes: _,
            checkpoints,
            on_playback: _,
            #[cfg(feature = "test-hooks")]
                test_panic: _,
        } = self;
        let Coat {
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
            frame_index: _,
            ordering_report: _,
            frame_report: _,
        } = coat;
        MemoryUse {
            mesh: std::mem::size_of::<Self>()
                + mesh.heap_bytes()
                + dressing.heap_bytes()
                + positions.heap_bytes()
                + normals.heap_bytes()
                + body.heap_bytes()
                + frame_positions.heap_bytes(),
            coat: frames.heap_bytes()
                + poses.heap_bytes()
                + staleness.heap_bytes()
                + settling.heap_bytes()
                + readjusted.heap_bytes()
                + records.heap_bytes()
                + triangles.heap_bytes()
                + previous_poses.heap_bytes()
                + older_poses.heap_bytes()
                + previous_frames.heap_bytes()
                + changed.heap_bytes(),
            neighbourhoods: neighbourhoods.heap_bytes() + order.heap_bytes(),
            history: checkpoints.heap_bytes(),
            scratch: work.heap_bytes() + step_work.heap_bytes() + backup.heap_bytes(),
        }
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
        &self.coat.readjusted
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

    /// Each feather packed for instancing, in the order of
    /// [`System::feathers`] (see [`InstanceRecord`] for the convention):
    /// placed from [`System::feather_template`] they give the vertices of
    /// [`System::feather_mesh`] within 1e-4 of a feather's length.
    pub fn feather_instances(&self) -> Vec<InstanceRecord> {
        let placements = self.coat.frames.iter().zip(&self.dressing.shapes).zip(&self.coat.poses);
        placements.map(|((frame, shape), pose)| InstanceRecord::pack(frame, shape, pose)).collect()
    }

    /// The template card of the system's feathers (every feather has the
    /// same segments and vane split; only length and width differ).
    pub fn feather_template(&self) -> FeatherTemplate {
        let shape = self.dressing.shapes.first().copied().unwrap_or_else(|| {
            crate::feather::FeatherShape::for_spacing(1.0).with_segments(self.dressing.config.shaft_segments)
        });
        FeatherTemplate::of(&shape)
    }

    /// The feathers whose record and triangles the last create, step,
    /// evaluate, load or seek may have changed: every feather not listed
    /// is, bit for bit, as the call before left it. A step or an evaluate
    /// lists the feathers whose root frame or pose differs in any bit; a
    /// create, a load and a seek that loads a checkpoint list every feather
    /// with `all` set (there is no previous result to compare with). A
    /// refused or interrupted call leaves the list as it was.
    pub fn changed_feathers(&self) -> ChangedFeathers<'_> {
        ChangedFeathers { indices: &self.changed, reposed: self.reposed, all: self.all_changed }
    }

    /// Marks every feather changed (after create or a load).
    fn all_changed_now(&mut self) {
        self.changed.clear();
        self.changed.extend(0..self.coat.poses.len() as u32);
        self.reposed = self.changed.len();
        self.all_changed = true;
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
        std::mem::swap(&mut self.previous_poses, &mut self.older_poses);
        self.previous_poses.clone_from(&self.coat.poses);
        self.previous_frames.clone_from(&self.coat.frames);
        let limit = self.dressing.config.memory_limit;
        let backed_up = progress.is_interruptible() || limit > 0;
        if backed_up {
            self.backup.clone_from(&self.coat);
        } else if self.backup.frames.capacity() > 0 {
            // A call nobody can stop keeps no copy: a host that once passed
            // a progress callback does not hold one from then on.
            self.backup = Coat::default();
        }
        let result = update(self, progress).and_then(|()| match limit {
            0 => Ok(()),
            _ => match self.memory().total() {
                held if held > limit => {
                    Err(crate::memory::over_limit("after this frame the system would hold", held, limit))
                }
                _ => Ok(()),
            },
        });
        match result {
            Ok(()) => {
                self.pose_changes =
                    pose_changes(&self.previous_poses, &self.coat.poses, self.dressing.config.pop_threshold);
                let (before, after) = (
                    (&self.previous_frames[..], &self.previous_poses[..]),
                    (&self.coat.frames[..], &self.coat.poses[..]),
                );
                self.reposed = changed_feathers(before, after, &mut self.changed);
                self.all_changed = false;
                self.export()
            }
            Err(_) => {
                std::mem::swap(&mut self.previous_poses, &mut self.older_poses);
                if backed_up {
                    std::mem::swap(&mut self.coat, &mut self.backup);
                    // The coat of the failed call goes: a call refused for
                    // its memory does not leave it held.
                    self.backup = Coat::default();
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

/// Refuses a create whose `feathers` feathers' own arrays would pass
/// `config.memory_limit`, before they are allocated.
fn check_feather_arrays(config: &Config, feathers: usize) -> Result<()> {
    let floor = feather_arrays_floor(feathers);
    if config.memory_limit > 0 && floor > config.memory_limit {
        return Err(crate::memory::over_limit(
            &format!("{feathers} feathers' own arrays alone would hold"),
            floor,
            config.memory_limit,
        ));
    }
    Ok(())
}

/// What the last call changed (see [`System::changed_feathers`]).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ChangedFeathers<'a> {
    /// Indices of the feathers whose record or triangles may differ,
    /// increasing.
    pub indices: &'a [u32],
    /// How many of them changed their pose relative to their root (pitch,
    /// roll, size, bends); the others only moved with the skin.
    pub reposed: usize,
    /// Whether `indices` holds every feather because there was no previous
    /// result to compare with (create, load, a seek that loads).
    pub all: bool,
}

/// The bytes the per-feather arrays of a system with `feathers` feathers
/// hold at the least: one element of each array every feather has (rest
/// binding, frame, pose, triangles, record, the adjuster's triangles and
/// obstacle boxes). A lower bound of what create will allocate, known
/// before it allocates: a limit below it is refused up front.
pub fn feather_arrays_floor(feathers: usize) -> usize {
    use crate::adjustment::obstacle::ObstacleBoxes;
    use crate::feather::{FeatherPose, FeatherTriangles};
    use std::mem::size_of;
    let per_feather = size_of::<crate::roots::RootBinding>()
        + size_of::<crate::geometry::RootFrame>()
        + size_of::<FeatherPose>()
        + size_of::<FeatherTriangles>() * 2
        + size_of::<ObstacleBoxes>()
        + size_of::<crate::stats::FeatherRecord>();
    feathers.saturating_mul(per_feather)
}

/// The faces with a feathered corner round which the rest orientation
/// field turns (see [`crate::validation::field_singularities`]).
fn singular_faces_on_feathers(mesh: &WeldedMesh, fields: &Fields) -> usize {
    let spacing = fields.vertex_spacing_scales();
    let singular = crate::validation::field_singularities(&mesh.positions, &mesh.triangles, fields.vertex_directions());
    singular.iter().filter(|&&(t, _)| mesh.triangles[t as usize].iter().any(|&v| spacing[v as usize] > 0.0)).count()
}
