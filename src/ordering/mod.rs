//! Who lies on whom: growth priority and the feather order (paper §2.1–2.2,
//! §3.2–3.3; DESIGN §4, §5).
//!
//! * [`Neighbourhoods`]: k-nearest roots, the symmetric pair set and obstacle
//!   candidates at the current pose.
//! * [`Priorities`]: the priority difference `ΔP_AB` (Eq. 3, or Eq. 2 for the
//!   legacy mode).
//! * [`PriorityOrder`]: the priority DAG and its topological order, built once
//!   by [`PriorityOrder::build_static`] and kept up to date frame by frame by
//!   [`PriorityOrder::update_frame`] (dynamic topological order with the
//!   paper's cycle rule).
//!
//! [`Neighbourhoods`] and [`PriorityOrder`] also save their state into a
//! system's state blob and read it back, checked (`write_state` /
//! `read_state`; the order's in `order_blob`).
//!
//! A frame loop (incremental mode) does, per frame:
//! 1. re-pose the roots; if neighbourhoods are recomputed,
//!    [`Neighbourhoods::rebuild`];
//! 2. find `R_k` (roots whose neighbours deformed differently);
//! 3. [`PriorityOrder::update_frame`]`(Some(neighbourhoods.pairs()), &r_k, &priorities)`
//!    (or, step by step: `begin_frame`, `sync_pairs`, `update_pairs`,
//!    `retry_suppressed`);
//! 4. readjust `R_k ∪` [`PriorityOrder::became_prior`] in [`PriorityOrder::order`].
//!
//! The first frame (and every frame of the `rebuild` mode) instead calls
//! [`Neighbourhoods::rebuild`], [`Priorities::deltas_of_pairs`] and
//! [`PriorityOrder::build_static`]. The `legacy` mode builds the static order
//! once with [`Priorities::legacy`] (Eq. 2) and never updates it.
//!
//! Nothing here uses threads: every result is the same on any pool.

mod dynamic_order;
mod kd_tree;
pub(crate) use kd_tree::KdTree;
mod neighbours;
mod order_blob;
mod order_graph;
mod pearce_kelly;
mod priority;
mod static_order;
mod suppressed;

pub use neighbours::{NeighbourParams, Neighbourhoods};
pub use order_graph::{PriorityOrder, ReorderStats};
pub use priority::{Priorities, PriorityRule, directed_priority_eq2, directed_priority_eq3};
pub use static_order::StaticReport;
