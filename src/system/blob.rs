//! A system's saved state and scrubbing: the state blob of one frame,
//! loading it back, and the checkpoints `seek` goes back to.

use super::System;
use crate::animation::coherence::PoseChanges;
use crate::coat::Coat;
use crate::config::{Config, Mode, SamplerKind};
use crate::error::{Error, ErrorKind, Result};
use crate::rng::hash64;
use crate::snapshot::{Reader, Writer};
use glam::Vec3;

/// Saved state: save a frame, resume from it (see [`crate::snapshot`] for
/// the blob's header and checksum). The payload is the coat
/// ([`Coat::write_state`]), then the flags of [`System::readjusted`] (u64
/// count, one byte 0 or 1 per feather, `Coat::readjusted`).
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
        let mut coat = self.pool.install(|| Coat::read_state(&mut reader, dressing))?;
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
        coat.readjusted = readjusted;
        self.coat = coat;
        self.pose_changes = PoseChanges::default();
        self.previous_poses.clear();
        self.export();
        self.all_changed_now();
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
    pub(super) fn keep_checkpoint(&mut self) {
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
        let mut words = config_words(&self.dressing.config);
        let bits = |x: f32| u64::from(x.to_bits());
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
        // Painted layers change the order; without any, the words are as before.
        if !dressing.layers.is_empty() {
            words.push(dressing.layers.len() as u64);
            words.extend(dressing.layers.iter().map(|&l| bits(l)));
        }
        hash64(&words)
    }
}

/// The words of the fingerprint that come from the configuration: every
/// field that can change a result (all but the thread count and the
/// figures-only and memory fields).
fn config_words(config: &Config) -> Vec<u64> {
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
        memory_limit: _,
    } = config;
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
    words
}
