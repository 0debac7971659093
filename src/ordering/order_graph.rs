//! The priority DAG's storage and the topological order it keeps (paper
//! §2.2; DESIGN §4): [`PriorityOrder`] with its pair states and per-root
//! incidence lists, the read-only accessors, and the graph primitives the
//! dynamic order (`dynamic_order`), Pearce–Kelly with the cycle rule
//! (`pearce_kelly`) and the suppressed pairs (`suppressed`) build on.
//!
//! # Graph
//! Edges only ever join the two roots of a neighbour pair, so the graph is
//! stored as one state per pair (no edge, `lo` prior, `hi` prior) plus a
//! per-root incidence list (CSR, sorted by the partner's index) built from
//! the pair set. Reversing, deleting or inserting an edge is a change of that
//! state; only a change of the pair set rebuilds the incidence lists.
//!
//! Internally an edge is read "prior → dependent": the prior root is
//! adjusted first, so every edge must go forward in [`PriorityOrder::order`].
//! (In the paper's notation that is the DAG edge dependent → prior, A→B when
//! `ΔP_AB > 0`.)

use crate::csr::Csr;
use std::cmp::Reverse;
use std::collections::BinaryHeap;
use std::ops::AddAssign;

/// The edge on one pair.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub(super) enum Edge {
    /// No edge: the roots are not ordered relative to each other.
    #[default]
    Absent,
    /// The lower-indexed root is prior (adjusted first).
    LoPrior,
    /// The higher-indexed root is prior.
    HiPrior,
}

impl Edge {
    /// The edge a pair wants given `ΔP_lo,hi`: positive ⇒ `hi` is prior.
    #[inline]
    pub(super) fn wanted(delta: f32) -> Self {
        if delta > 0.0 {
            Edge::HiPrior
        } else if delta < 0.0 {
            Edge::LoPrior
        } else {
            Edge::Absent
        }
    }
}

/// Whether `v` is the prior root of the edge `edge` on the pair `{v, u}`.
#[inline]
pub(super) fn is_prior_side(v: u32, u: u32, edge: Edge) -> bool {
    match edge {
        Edge::Absent => false,
        Edge::LoPrior => v < u,
        Edge::HiPrior => v > u,
    }
}

/// A priority difference as stored: non-finite values mean "no preference".
#[inline]
pub(super) fn sanitized_delta(delta: f32) -> f32 {
    if delta.is_finite() { delta } else { 0.0 }
}

/// One entry of a root's incidence list.
#[derive(Clone, Copy, Debug, Default)]
pub(super) struct Incidence {
    /// The partner root.
    pub(super) other: u32,
    /// Index of the pair in the sorted pair list.
    pub(super) pair: u32,
}

/// What one reordering call did (paper Table 1, "priority changes").
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct ReorderStats {
    /// Pairs whose `ΔP` was given (after dropping duplicates and unknowns).
    pub pairs_updated: usize,
    /// Pairs whose `ΔP` changed sign (including to or from exactly 0).
    pub priority_changes: usize,
    /// Edges reversed (sign changes realised, retries included).
    pub reversals_done: usize,
    /// Reversals refused by the cycle rule (the old edge was kept).
    pub reversals_refused: usize,
    /// Edges deleted because they were the weakest on a cycle.
    pub cycles_broken: usize,
    /// Edges inserted on pairs that had none (new pairs, retries, `ΔP` leaving 0).
    pub edges_inserted: usize,
    /// Such insertions refused by the cycle rule.
    pub insertions_refused: usize,
    /// Edges removed because their pair vanished or its `ΔP` became 0.
    pub edges_removed: usize,
    /// Pairs added by a pair-set change.
    pub pairs_added: usize,
    /// Pairs removed by a pair-set change.
    pub pairs_removed: usize,
    /// Changed entries naming a pair that is not in the pair set (ignored).
    pub unknown_pairs: usize,
    /// Suppressed pairs whose insertion was tried again.
    pub retried: usize,
    /// Of those, how many now have their wanted edge.
    pub retries_succeeded: usize,
    /// True when the retry passes hit their bound before a quiet pass.
    pub retry_passes_exhausted: bool,
    /// Wall time of the call(s), seconds.
    pub seconds: f64,
}

impl AddAssign for ReorderStats {
    fn add_assign(&mut self, o: Self) {
        self.pairs_updated += o.pairs_updated;
        self.priority_changes += o.priority_changes;
        self.reversals_done += o.reversals_done;
        self.reversals_refused += o.reversals_refused;
        self.cycles_broken += o.cycles_broken;
        self.edges_inserted += o.edges_inserted;
        self.insertions_refused += o.insertions_refused;
        self.edges_removed += o.edges_removed;
        self.pairs_added += o.pairs_added;
        self.pairs_removed += o.pairs_removed;
        self.unknown_pairs += o.unknown_pairs;
        self.retried += o.retried;
        self.retries_succeeded += o.retries_succeeded;
        self.retry_passes_exhausted |= o.retry_passes_exhausted;
        self.seconds += o.seconds;
    }
}

/// The priority DAG over neighbour pairs and a topological order of it,
/// maintained incrementally. Build it with
/// [`build_static`](PriorityOrder::build_static), then call
/// [`update_frame`](PriorityOrder::update_frame) (or its parts) once per
/// frame. All buffers are kept across calls.
#[derive(Debug, Default)]
pub struct PriorityOrder {
    // The graph.
    pub(super) pairs: Vec<(u32, u32)>,
    pub(super) delta: Vec<f32>,
    pub(super) state: Vec<Edge>,
    /// Per root, its pairs (partner and pair index), sorted by partner.
    pub(super) inc: Csr<Incidence>,
    pub(super) edge_count: usize,
    // The order: `order[rank[v]] == v`.
    pub(super) rank: Vec<u32>,
    pub(super) order: Vec<u32>,
    // Suppressed pairs (sorted pair indices) and their blocking paths. A
    // pair's path is `path_pool[start..start + len]` with `(start, len) =
    // blocking[pair]`; paths of pairs no longer suppressed are dead and are
    // dropped by compaction when the pool is full (`make_room_for_path`).
    pub(super) suppressed: Vec<u32>,
    pub(super) touched: Vec<u32>,
    pub(super) blocking: Vec<(u32, u32)>,
    pub(super) path_pool: Vec<u32>,
    pub(super) path_pool_spare: Vec<u32>,
    // Search scratch.
    pub(super) mark: Vec<u32>,
    pub(super) stamp: u32,
    pub(super) parent: Vec<(u32, u32)>,
    pub(super) stack: Vec<u32>,
    pub(super) forward: Vec<u32>,
    pub(super) backward: Vec<u32>,
    pub(super) rank_pool: Vec<u32>,
    pub(super) cycle: Vec<u32>,
    pub(super) cycle_pairs: Vec<u32>,
    /// One bit per pair: those touching a root of `R_k` (see
    /// `changed_pairs_of_roots`).
    pub(super) pair_marks: Vec<u64>,
    // Per-frame reports.
    pub(super) became_prior: Vec<u32>,
    pub(super) gained_prior: Vec<u32>,
    pub(super) moved: Vec<u32>,
    // Update and rebuild scratch.
    pub(super) changed: Vec<(u32, u32, f32, u32)>,
    pub(super) frame_changed: Vec<(u32, u32, f32)>,
    pub(super) retry: Vec<u32>,
    pub(super) next_pairs: Vec<(u32, u32)>,
    pub(super) next_delta: Vec<f32>,
    pub(super) next_state: Vec<Edge>,
    pub(super) next_blocking: Vec<(u32, u32)>,
    pub(super) pair_map: Vec<u32>,
    pub(super) fresh: Vec<u32>,
    pub(super) sort_keys: Vec<u64>,
    pub(super) waiting: Vec<u32>,
    pub(super) heap: BinaryHeap<Reverse<(u32, u32)>>,
}

impl PriorityOrder {
    /// An empty order (no roots). Call [`build_static`](Self::build_static).
    pub fn new() -> Self {
        Self::default()
    }

    /// Number of roots.
    pub fn node_count(&self) -> usize {
        self.rank.len()
    }

    /// The adjustment sequence: prior roots first, so every edge's prior
    /// root comes before its dependent.
    pub fn order(&self) -> &[u32] {
        &self.order
    }

    /// Every root's position in [`order`](Self::order) (`order()[ranks()[v]] == v`).
    pub fn ranks(&self) -> &[u32] {
        &self.rank
    }

    /// Position of `node` in [`order`](Self::order).
    pub fn rank_of(&self, node: u32) -> u32 {
        self.rank[node as usize]
    }

    /// The pair set, sorted, `a < b`.
    pub fn pairs(&self) -> &[(u32, u32)] {
        &self.pairs
    }

    /// Number of edges currently in the DAG.
    pub fn edge_count(&self) -> usize {
        self.edge_count
    }

    /// The stored `ΔP_ab` of the pair `{a, b}` (sign as asked), or `None`
    /// when `{a, b}` is not a pair.
    pub fn pair_delta(&self, a: u32, b: u32) -> Option<f32> {
        let pid = self.find_pair(a, b)? as usize;
        Some(if a < b { self.delta[pid] } else { -self.delta[pid] })
    }

    /// The prior root of the edge on `{a, b}`, or `None` when there is no
    /// edge (no pair, `ΔP = 0`, or the pair is suppressed without an edge).
    pub fn prior_in_pair(&self, a: u32, b: u32) -> Option<u32> {
        let pid = self.find_pair(a, b)? as usize;
        match self.state[pid] {
            Edge::Absent => None,
            Edge::LoPrior => Some(self.pairs[pid].0),
            Edge::HiPrior => Some(self.pairs[pid].1),
        }
    }

    /// Every root paired with `node`, by index.
    pub fn partners_of(&self, node: u32) -> impl Iterator<Item = u32> + '_ {
        self.incidence(node).iter().map(|e| e.other)
    }

    /// `N*_node`: the roots `node` depends on (prior to it, placed first).
    pub fn priors_of(&self, node: u32) -> impl Iterator<Item = u32> + '_ {
        self.incidence(node)
            .iter()
            .filter(move |e| is_prior_side(e.other, node, self.state[e.pair as usize]))
            .map(|e| e.other)
    }

    /// The roots that depend on `node` (it is prior to them).
    pub fn dependants_of(&self, node: u32) -> impl Iterator<Item = u32> + '_ {
        self.incidence(node)
            .iter()
            .filter(move |e| is_prior_side(node, e.other, self.state[e.pair as usize]))
            .map(|e| e.other)
    }

    /// The suppressed pairs: their wanted edge (sign of `ΔP`) is not in the
    /// DAG because it would close a cycle of stronger edges.
    pub fn suppressed_pairs(&self) -> impl Iterator<Item = (u32, u32)> + '_ {
        self.suppressed.iter().map(|&p| self.pairs[p as usize])
    }

    /// Number of suppressed pairs.
    pub fn suppressed_count(&self) -> usize {
        self.suppressed.len()
    }

    /// Edges whose prior root comes after their dependent in the order
    /// (always 0; a check for tests and reports).
    pub fn count_violations(&self) -> usize {
        (0..self.pairs.len())
            .filter(|&p| match self.edge_endpoints(p as u32, self.state[p]) {
                Some((prior, dependent)) => self.rank[prior as usize] >= self.rank[dependent as usize],
                None => false,
            })
            .count()
    }

    /// Roots that became prior to a partner since [`begin_frame`](Self::begin_frame)
    /// (reversal, new pair or successful retry), sorted: with `R_k` they form
    /// the paper's `R*_k` and must be readjusted.
    pub fn became_prior(&self) -> &[u32] {
        &self.became_prior
    }

    /// The partners on the other side of those edges: roots that gained a
    /// prior since [`begin_frame`](Self::begin_frame), sorted. They now have
    /// a new obstacle to lie on.
    pub fn gained_prior(&self) -> &[u32] {
        &self.gained_prior
    }

    /// Roots whose rank changed since [`begin_frame`](Self::begin_frame),
    /// sorted. Obstacle sets taken "earlier in the order" may differ for them.
    pub fn moved(&self) -> &[u32] {
        &self.moved
    }

    /// Starts a frame: clears the per-frame root lists.
    pub fn begin_frame(&mut self) {
        self.became_prior.clear();
        self.gained_prior.clear();
        self.moved.clear();
        // Room for every pair to be suppressed and retried: how many are
        // follows the coat's state, and the heap must not creep up with it.
        let pairs = self.pairs.len();
        self.suppressed.reserve(pairs.saturating_sub(self.suppressed.len()));
        self.retry.reserve(pairs.saturating_sub(self.retry.len()));
    }

    pub(super) fn incidence(&self, node: u32) -> &[Incidence] {
        self.inc.row(node as usize)
    }

    /// Index of the pair `{a, b}` (either orientation).
    pub(super) fn find_pair(&self, a: u32, b: u32) -> Option<u32> {
        let list = self.incidence(a);
        list.binary_search_by_key(&b, |e| e.other).ok().map(|k| list[k].pair)
    }

    /// `(prior, dependent)` of `edge` placed on pair `pid`.
    pub(super) fn edge_endpoints(&self, pid: u32, edge: Edge) -> Option<(u32, u32)> {
        let (lo, hi) = self.pairs[pid as usize];
        match edge {
            Edge::Absent => None,
            Edge::LoPrior => Some((lo, hi)),
            Edge::HiPrior => Some((hi, lo)),
        }
    }

    /// Whether pair `a`'s edge is stronger than pair `b`'s: larger `|ΔP|`,
    /// ties to the smaller pair index.
    #[inline]
    pub(super) fn stronger(&self, a: u32, b: u32) -> bool {
        let (wa, wb) = (self.delta[a as usize].abs(), self.delta[b as usize].abs());
        wa > wb || (wa == wb && a < b)
    }

    pub(super) fn is_suppressed(&self, pid: u32) -> bool {
        Edge::wanted(self.delta[pid as usize]) != self.state[pid as usize]
    }

    pub(super) fn set_edge(&mut self, pid: u32, edge: Edge) {
        let slot = &mut self.state[pid as usize];
        match (*slot == Edge::Absent, edge == Edge::Absent) {
            (true, false) => self.edge_count += 1,
            (false, true) => self.edge_count -= 1,
            _ => {}
        }
        *slot = edge;
    }

    /// Rebuilds the incidence lists from the pair set (each root's list
    /// comes out sorted by partner because pairs are sorted).
    pub(super) fn rebuild_incidence(&mut self) {
        let n = self.node_count();
        let pairs = &self.pairs;
        self.inc.rebuild(n, || {
            pairs.iter().enumerate().flat_map(|(pid, &(a, b))| {
                let pair = pid as u32;
                [(a as usize, Incidence { other: b, pair }), (b as usize, Incidence { other: a, pair })]
            })
        });
    }

    /// Resizes the per-root arrays for `n` roots and forgets all pairs.
    pub(super) fn reset(&mut self, n: usize) {
        assert!(u32::try_from(n).is_ok(), "too many roots for u32 indices");
        self.pairs.clear();
        self.delta.clear();
        self.state.clear();
        self.blocking.clear();
        self.edge_count = 0;
        self.suppressed.clear();
        self.touched.clear();
        self.path_pool.clear();
        self.rank.clear();
        self.rank.resize(n, 0);
        self.order.clear();
        self.mark.clear();
        self.mark.resize(n, 0);
        self.stamp = 0;
        self.parent.clear();
        self.parent.resize(n, (0, 0));
        self.begin_frame();
    }

    /// A fresh visit stamp (clearing the marks on wrap-around).
    pub(super) fn next_stamp(&mut self) -> u32 {
        self.stamp = self.stamp.wrapping_add(1);
        if self.stamp == 0 {
            self.mark.fill(0);
            self.stamp = 1;
        }
        self.stamp
    }
}

/// Strongest first: larger `|ΔP|`, ties to the smaller pair index.
pub(super) fn strength_order(delta: &[f32], a: u32, b: u32) -> std::cmp::Ordering {
    delta[b as usize].abs().total_cmp(&delta[a as usize].abs()).then(a.cmp(&b))
}

/// Checks the pair-set precondition: strictly increasing, `a < b < n`.
pub(super) fn check_pairs(pairs: &[(u32, u32)], n: usize) {
    for (k, &(a, b)) in pairs.iter().enumerate() {
        assert!(a < b && (b as usize) < n, "pair {k} = ({a}, {b}) must have a < b < {n}");
        if k > 0 {
            assert!(pairs[k - 1] < (a, b), "pairs must be sorted and unique (at index {k})");
        }
    }
}

crate::memory::clone_by_fields!(PriorityOrder {
    pairs,
    delta,
    state,
    inc,
    edge_count,
    rank,
    order,
    suppressed,
    touched,
    blocking,
    path_pool,
    path_pool_spare,
    mark,
    stamp,
    parent,
    stack,
    forward,
    backward,
    rank_pool,
    cycle,
    cycle_pairs,
    pair_marks,
    became_prior,
    gained_prior,
    moved,
    changed,
    frame_changed,
    retry,
    next_pairs,
    next_delta,
    next_state,
    next_blocking,
    pair_map,
    fresh,
    sort_keys,
    waiting,
    heap
});
crate::memory::heap_size_of_fields!(PriorityOrder {
    pairs, delta, state, inc, rank, order, suppressed, touched, blocking, path_pool, path_pool_spare, mark, parent,
    stack, forward, backward, rank_pool, cycle, cycle_pairs, pair_marks, became_prior, gained_prior, moved, changed,
    frame_changed, retry, next_pairs, next_delta, next_state, next_blocking, pair_map, fresh, sort_keys, waiting, heap
} plain { edge_count, stamp });
