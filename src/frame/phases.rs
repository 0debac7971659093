//! The phases a from-scratch solve and a frame-to-frame step share (see the
//! module notes of [`crate::frame`] for the whole sequence).

use crate::Mode;
use crate::adjustment::Adjuster;
use crate::animation::contact::{Contacts, Sphere};
use crate::animation::motion::RootMap;
use crate::coat::{Coat, Dressing};
use crate::csr::Csr;
use crate::error::Result;
use crate::feather::shaft_direction;
use crate::geometry::RootFrame;
use crate::ordering::Priorities;
use crate::progress::{Phase, Progress};
use crate::stats::OrderingReport;
use glam::Vec3;
use std::time::Instant;

/// Buffers reused from call to call by every phase; never part of the state.
#[derive(Debug, Default)]
pub struct Workspace {
    /// The adjuster's own scratch.
    pub adjuster: Adjuster,
    /// ΔP of each pair.
    pub deltas: Vec<f32>,
    /// Shaft directions (the legacy rule's `o_i`).
    pub orientations: Vec<Vec3>,
}

/// Buffers of the frame-to-frame step ([`super::step_coat`]), reused
/// every frame; never part of the state.
#[derive(Debug, Default)]
pub struct StepWorkspace {
    pub(super) previous_frames: Vec<RootFrame>,
    pub(super) previous_ranks: Vec<u32>,
    pub(super) previous_candidates: Csr<u32>,
    pub(super) maps: Vec<RootMap>,
    pub(super) displacement: Vec<f32>,
    pub(super) net: Vec<f32>,
    pub(super) orientations: Vec<glam::Quat>,
    pub(super) spheres: Vec<Sphere>,
    pub(super) seeds: Vec<bool>,
    pub(super) suspects: Vec<bool>,
    pub(super) no_suspects: Vec<bool>,
    pub(super) verified: Vec<bool>,
    pub(super) r_k: Vec<u32>,
    pub(super) body_ids: Vec<u32>,
    pub(super) contacts: Contacts,
}

crate::memory::heap_size_of_fields!(StepWorkspace {
    previous_frames,
    previous_ranks,
    previous_candidates,
    maps,
    displacement,
    net,
    orientations,
    spheres,
    seeds,
    suspects,
    no_suspects,
    verified,
    r_k,
    body_ids,
    contacts
});

/// Phase 3 from scratch, the static order: the priority difference of
/// every pair (Eq. 3, or Eq. 2 with the feathers' current shaft directions
/// for the legacy mode), then the priority DAG made acyclic and its
/// topological order. `started` is when the ordering began (the report's
/// seconds count from there, neighbourhoods included).
pub(super) fn static_order(coat: &mut Coat, dressing: &Dressing, work: &mut Workspace, started: Instant) {
    let pairs = coat.neighbourhoods.pairs();
    match dressing.config.mode {
        Mode::Legacy => {
            // Eq. 2 with the feathers' own orientations (flat: o = õ).
            work.orientations.clear();
            work.orientations.extend(coat.frames.iter().zip(&coat.poses).map(|(f, p)| shaft_direction(f, *p)));
            Priorities::legacy(&coat.frames, &work.orientations, dressing.config.gamma)
                .with_layers(&dressing.layers)
                .deltas_of_pairs(pairs, &mut work.deltas)
        }
        Mode::Incremental | Mode::Rebuild => {
            Priorities::improved(&coat.frames, dressing.config.gamma, dressing.config.lambda)
                .with_layers(&dressing.layers)
                .deltas_of_pairs(pairs, &mut work.deltas)
        }
    }
    let report = coat.order.build_static(dressing.len(), pairs, &work.deltas);
    coat.ordering_report = OrderingReport {
        pairs: report.pairs,
        edges: report.edges,
        dropped_edges: report.dropped,
        violations: report.violations,
        seconds: started.elapsed().as_secs_f64(),
    };
}

/// Phases 2 and 4 side by side (they read and write different parts of
/// the coat): the neighbourhoods (the k nearest roots, the pair set and
/// the obstacle candidates at the coat's current root frames) on the pool,
/// the body index at the coat's positions beside them. Returns the seconds
/// the neighbourhoods took.
pub(super) fn neighbourhoods_and_body(coat: &mut Coat, dressing: &Dressing, progress: &Progress) -> Result<f64> {
    let Coat { neighbourhoods, frames, body, positions, .. } = coat;
    let keep_going = || progress.check(Phase::Ordering, 0.1).is_ok();
    let (seconds, ()) = rayon::join(
        || {
            let start = Instant::now();
            neighbourhoods.rebuild_until(frames, &dressing.reach, &dressing.neighbour_params, &keep_going);
            start.elapsed().as_secs_f64()
        },
        || body.rebuild(positions, &dressing.triangles),
    );
    // Stopped: the rows are half built; the caller restores the coat.
    progress.check(Phase::Ordering, 0.2)?;
    Ok(seconds)
}

/// Phase 4, body: the body's triangles at the coat's positions, indexed.
pub(super) fn body(coat: &mut Coat, dressing: &Dressing) {
    coat.body.rebuild(&coat.positions, &dressing.triangles);
}

crate::memory::heap_size_of_fields!(Workspace { adjuster, deltas, orientations });
