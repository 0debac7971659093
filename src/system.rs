//! `System`: the safe Rust face of Plumage. It owns the welded mesh and
//! everything computed on it, and is what the FFI handle wraps.

use crate::config::Config;
use crate::error::Result;
use crate::mesh::{MeshInput, WeldedMesh, check_frame_positions, weld};

/// A feathered surface: created at the rest pose, then stepped frame by frame.
#[derive(Clone, Debug)]
pub struct System {
    config: Config,
    mesh: WeldedMesh,
    frames_stepped: u64,
}

impl System {
    /// Checks the configuration and the mesh, and welds the mesh.
    pub fn new(config: &Config, mesh: &MeshInput<'_>) -> Result<Self> {
        config.validate()?;
        mesh.check()?;
        let welded = weld(mesh)?;
        Ok(Self { config: config.clone(), mesh: welded, frames_stepped: 0 })
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
        0
    }

    /// Advances to the next animation frame. On error nothing changes.
    pub fn step(&mut self, positions: &[f32]) -> Result<()> {
        check_frame_positions(positions, self.vertex_count())?;
        self.mesh.set_caller_positions(positions);
        self.frames_stepped += 1;
        Ok(())
    }

    /// Solves the pose from scratch, independent of history. On error nothing changes.
    pub fn evaluate(&mut self, positions: &[f32]) -> Result<()> {
        check_frame_positions(positions, self.vertex_count())?;
        self.mesh.set_caller_positions(positions);
        Ok(())
    }
}
