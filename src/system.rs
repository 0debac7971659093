//! `System`: the safe Rust face of Plumage. It owns the welded mesh and
//! everything computed on it, and is what the FFI handle wraps.

use crate::config::Config;
use crate::error::Result;
use crate::mesh::{MeshInput, WeldedMesh, check_frame_positions, weld};
use crate::progress::{Phase, Progress};
use crate::stats::{FeatherRecord, FrameReport, OrderingReport, SamplingReport, ValidationReport};

/// A feathered surface: created at the rest pose, then stepped frame by frame.
#[derive(Clone, Debug)]
pub struct System {
    config: Config,
    mesh: WeldedMesh,
    frames_stepped: u64,
    #[cfg(feature = "test-hooks")]
    test_panic: std::sync::Arc<std::sync::atomic::AtomicBool>,
}

impl System {
    /// Checks the configuration and the mesh, and welds the mesh.
    pub fn new(config: &Config, mesh: &MeshInput<'_>) -> Result<Self> {
        Self::new_with_progress(config, mesh, &Progress::none())
    }

    /// As [`System::new`], reporting to `progress`, which may stop it.
    pub fn new_with_progress(config: &Config, mesh: &MeshInput<'_>, progress: &Progress) -> Result<Self> {
        config.validate()?;
        progress.check(Phase::Preparing, 0.0)?;
        mesh.check()?;
        let welded = weld(mesh)?;
        progress.check(Phase::Preparing, 1.0)?;
        Ok(Self {
            config: config.clone(),
            mesh: welded,
            frames_stepped: 0,
            #[cfg(feature = "test-hooks")]
            test_panic: Default::default(),
        })
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
        &self.config
    }

    /// The welded mesh at the current pose.
    pub fn mesh(&self) -> &WeldedMesh {
        &self.mesh
    }

    /// Number of vertices every frame must provide (the caller's numbering).
    pub fn vertex_count(&self) -> usize {
        self.mesh.caller_vertex_count()
    }

    /// Frames stepped since creation.
    pub fn frames_stepped(&self) -> u64 {
        self.frames_stepped
    }

    /// Number of feathers.
    pub fn feather_count(&self) -> usize {
        self.feathers().len()
    }

    /// The feathers at the current pose, in a stable order (by root).
    pub fn feathers(&self) -> &[FeatherRecord] {
        &[]
    }

    /// Each feather's two triangles (one per vane), world space, in the
    /// order of [`System::feathers`].
    pub fn feather_triangles(&self) -> &[[[f32; 3]; 6]] {
        &[]
    }

    /// Sampling figures, once roots have been planted.
    pub fn sampling_report(&self) -> Option<SamplingReport> {
        None
    }

    /// Ordering figures, once the static order exists.
    pub fn ordering_report(&self) -> Option<OrderingReport> {
        None
    }

    /// What the last create, step or evaluate did, once feathers are adjusted.
    pub fn frame_report(&self) -> Option<FrameReport> {
        None
    }

    /// Exact validation of the current feathers, once feathers exist.
    pub fn validate(&self) -> Option<ValidationReport> {
        self.maybe_test_panic();
        None
    }

    /// Advances to the next animation frame. On error nothing changes.
    pub fn step(&mut self, positions: &[f32]) -> Result<()> {
        self.step_with_progress(positions, &Progress::none())
    }

    /// As [`System::step`], reporting to `progress`, which may stop it.
    pub fn step_with_progress(&mut self, positions: &[f32], progress: &Progress) -> Result<()> {
        self.maybe_test_panic();
        check_frame_positions(positions, self.vertex_count())?;
        progress.check(Phase::Preparing, 0.0)?;
        self.mesh.set_caller_positions(positions);
        self.frames_stepped += 1;
        Ok(())
    }

    /// Solves the pose from scratch, independent of history. On error nothing changes.
    pub fn evaluate(&mut self, positions: &[f32]) -> Result<()> {
        self.evaluate_with_progress(positions, &Progress::none())
    }

    /// As [`System::evaluate`], reporting to `progress`, which may stop it.
    pub fn evaluate_with_progress(&mut self, positions: &[f32], progress: &Progress) -> Result<()> {
        self.maybe_test_panic();
        check_frame_positions(positions, self.vertex_count())?;
        progress.check(Phase::Preparing, 0.0)?;
        self.mesh.set_caller_positions(positions);
        Ok(())
    }
}
