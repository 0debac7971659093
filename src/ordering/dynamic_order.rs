//! The priority DAG and its dynamic topological order (paper §2.2, §3.3;
//! DESIGN §4, §5 step 3).
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
//!
//! # Why our own Pearce–Kelly
//! Insertions use the Pearce–Kelly algorithm (PK, paper ref. [12]): when an
//! edge `p → q` goes backwards in the order, search forward from `q` among
//! roots ranked before `p`, backward from `p` among roots ranked after `q`,
//! and shuffle only those two sets. `petgraph::acyclic::Acyclic` implements
//! PK too, but on a cycle it reports a single node, while the paper's cycle
//! rule needs the whole cycle to find its weakest edge. Our forward search
//! keeps parent links, so the cycle path falls out of the search that
//! detected it at no extra cost, and the pair-state representation avoids
//! petgraph's general edge storage (and its allocations) entirely.
//!
//! # Cycle rule
//! Edge strength is `|ΔP|`, ties broken by pair index (= by `(lo, hi)`), so
//! it is a total order. Inserting an edge that closes a cycle: find the
//! cycle (a path `q ⇝ p` plus the new edge); if the new edge is the weakest
//! on it, the insertion is refused (and, for a reversal, the old edge is
//! restored); otherwise the weakest edge is deleted and the search repeats,
//! since a second path may still close another cycle. The paper assumes a
//! single cycle; with several, we refuse when the new edge is the weakest on
//! *any* of them, i.e. exactly when a path `q ⇝ p` made only of stronger
//! edges exists, and decide that before deleting anything, so every
//! operation is all-or-nothing. Cycles are searched breadth-first: the
//! shortest, most local cycle is the one whose weakest edge goes.
//!
//! # Suppressed pairs
//! A pair whose wanted edge (the sign of its latest `ΔP`) is not in the graph
//! is *suppressed*. Each keeps the node path that blocked it (stronger edges
//! only). [`PriorityOrder::retry_suppressed`] first checks that path: while
//! every edge on it still exists and is still stronger, the retry would be
//! refused and is skipped; otherwise the insertion is tried again. Passes
//! repeat until none succeeds, so afterwards every suppressed pair is blocked
//! by a path of stronger edges.

use super::priority::Priorities;
use std::cmp::Reverse;
use std::collections::BinaryHeap;
use std::ops::AddAssign;
use std::time::Instant;

/// Upper bound on retry passes per call (a pass that inserts nothing ends
/// the loop; in practice one or two passes suffice).
const MAX_RETRY_PASSES: usize = 8;

/// Room, beyond twice the live paths and the path being stored, that a
/// compaction leaves in the path pool, as a multiple of the pair count, so
/// that compactions (each a pass over the pairs) stay rare.
const PATH_POOL_ROOM_PER_PAIR: usize = 1;

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
fn is_prior_side(v: u32, u: u32, edge: Edge) -> bool {
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
#[derive(Clone, Debug, Default)]
pub struct PriorityOrder {
    // The graph.
    pub(super) pairs: Vec<(u32, u32)>,
    pub(super) delta: Vec<f32>,
    pub(super) state: Vec<Edge>,
    pub(super) inc_offsets: Vec<u32>,
    pub(super) inc: Vec<Incidence>,
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
    path_pool_spare: Vec<u32>,
    // Search scratch.
    pub(super) mark: Vec<u32>,
    stamp: u32,
    parent: Vec<(u32, u32)>,
    stack: Vec<u32>,
    forward: Vec<u32>,
    backward: Vec<u32>,
    rank_pool: Vec<u32>,
    cycle: Vec<u32>,
    cycle_pairs: Vec<u32>,
    // Per-frame reports.
    became_prior: Vec<u32>,
    gained_prior: Vec<u32>,
    moved: Vec<u32>,
    // Update and rebuild scratch.
    changed: Vec<(u32, u32, f32, u32)>,
    frame_changed: Vec<(u32, u32, f32)>,
    retry: Vec<u32>,
    next_pairs: Vec<(u32, u32)>,
    next_delta: Vec<f32>,
    next_state: Vec<Edge>,
    next_blocking: Vec<(u32, u32)>,
    pair_map: Vec<u32>,
    fresh: Vec<u32>,
    cursor: Vec<u32>,
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
    }

    /// One frame of reordering (DESIGN §5 step 3, paper §3.3):
    /// [`begin_frame`](Self::begin_frame); if `pairs` is given (neighbourhoods
    /// recomputed at the current pose), [`sync_pairs`](Self::sync_pairs) with
    /// it, new pairs taking their `ΔP` from `priorities`; then recompute `ΔP`
    /// of every pair touching a root of `roots` (`R_k`) and
    /// [`update_pairs`](Self::update_pairs) with them; finally
    /// [`retry_suppressed`](Self::retry_suppressed). Returns the summed stats
    /// (`seconds` covers the whole call, `ΔP` recomputation included);
    /// afterwards [`became_prior`](Self::became_prior) lists the roots to add
    /// to `R_k` for readjustment (`R*_k`).
    pub fn update_frame(
        &mut self,
        pairs: Option<&[(u32, u32)]>,
        roots: &[u32],
        priorities: &Priorities<'_>,
    ) -> ReorderStats {
        let start = Instant::now();
        self.begin_frame();
        let mut stats = ReorderStats::default();
        if let Some(pairs) = pairs {
            stats += self.sync_pairs(pairs, |a, b| priorities.delta(a, b));
        }
        let mut changed = std::mem::take(&mut self.frame_changed);
        priorities.changed_pairs_of_roots(self, roots, &mut changed);
        stats += self.update_pairs(&changed);
        self.frame_changed = changed;
        stats += self.retry_suppressed();
        stats.seconds = start.elapsed().as_secs_f64();
        stats
    }

    /// Replaces the pair set (e.g. neighbourhoods recomputed at the current
    /// pose). Pairs that vanished lose their edge (a deletion never
    /// invalidates the order); pairs that appeared get `ΔP_ab =
    /// new_pair_delta(a, b)` and are inserted strongest first with the cycle
    /// rule. Kept pairs keep their edge and `ΔP`. Cheap when nothing changed.
    ///
    /// # Panics
    /// If `pairs` is not strictly increasing with `a < b < node_count`.
    pub fn sync_pairs(
        &mut self,
        pairs: &[(u32, u32)],
        mut new_pair_delta: impl FnMut(u32, u32) -> f32,
    ) -> ReorderStats {
        let start = Instant::now();
        let mut stats = ReorderStats::default();
        if pairs == self.pairs.as_slice() {
            stats.seconds = start.elapsed().as_secs_f64();
            return stats;
        }
        check_pairs(pairs, self.node_count());
        self.merge_pair_set(pairs, &mut new_pair_delta, &mut stats);
        self.rebuild_incidence();
        let fresh = std::mem::take(&mut self.fresh);
        for &pid in &fresh {
            self.touched.push(pid);
            self.realize_wanted(pid, &mut stats);
        }
        self.fresh = fresh;
        self.finish_call();
        stats.seconds = start.elapsed().as_secs_f64();
        stats
    }

    /// New `ΔP` values for some pairs, as `(a, b, ΔP_ab)` in any order and
    /// orientation (duplicates: the last one wins). Pairs whose sign is
    /// unchanged only get their weight `|ΔP|` updated; a sign change reverses
    /// the edge with the cycle rule; `ΔP = 0` removes it. Entries naming no
    /// pair are counted in `unknown_pairs` and ignored. Pairs are processed
    /// in `(lo, hi)` order, so the result does not depend on input order.
    pub fn update_pairs(&mut self, changed: &[(u32, u32, f32)]) -> ReorderStats {
        let start = Instant::now();
        let mut stats = ReorderStats::default();
        let mut entries = std::mem::take(&mut self.changed);
        entries.clear();
        for (idx, &(a, b, d)) in changed.iter().enumerate() {
            match a.cmp(&b) {
                std::cmp::Ordering::Less => entries.push((a, b, d, idx as u32)),
                std::cmp::Ordering::Greater => entries.push((b, a, -d, idx as u32)),
                std::cmp::Ordering::Equal => stats.unknown_pairs += 1,
            }
        }
        entries.sort_unstable_by_key(|&(lo, hi, _, idx)| (lo, hi, idx));
        for k in 0..entries.len() {
            let (lo, hi, d, _) = entries[k];
            if entries.get(k + 1).is_some_and(|next| (next.0, next.1) == (lo, hi)) {
                continue;
            }
            let Some(pid) = self.find_pair(lo, hi) else {
                stats.unknown_pairs += 1;
                continue;
            };
            stats.pairs_updated += 1;
            let new_delta = sanitized_delta(d);
            if Edge::wanted(new_delta) != Edge::wanted(self.delta[pid as usize]) {
                stats.priority_changes += 1;
            }
            self.delta[pid as usize] = new_delta;
            self.touched.push(pid);
            self.realize_wanted(pid, &mut stats);
        }
        self.changed = entries;
        self.finish_call();
        stats.seconds = start.elapsed().as_secs_f64();
        stats
    }

    /// Tries again to insert the wanted edge of every suppressed pair whose
    /// blocking path no longer holds (an edge on it vanished, turned or
    /// became weaker), in pair order, until a pass changes nothing.
    pub fn retry_suppressed(&mut self) -> ReorderStats {
        let start = Instant::now();
        let mut stats = ReorderStats::default();
        let mut quiet = false;
        for _ in 0..MAX_RETRY_PASSES {
            let mut batch = std::mem::take(&mut self.retry);
            batch.clear();
            batch.extend_from_slice(&self.suppressed);
            let mut progress = false;
            for &pid in &batch {
                if !self.is_suppressed(pid) || self.blocking_path_holds(pid) {
                    continue;
                }
                stats.retried += 1;
                self.touched.push(pid);
                if self.realize_wanted(pid, &mut stats) {
                    stats.retries_succeeded += 1;
                    progress = true;
                }
            }
            self.retry = batch;
            self.refresh_suppressed();
            if !progress {
                quiet = true;
                break;
            }
        }
        stats.retry_passes_exhausted = !quiet;
        self.finish_call();
        stats.seconds = start.elapsed().as_secs_f64();
        stats
    }

    // ----- graph access -------------------------------------------------

    pub(super) fn incidence(&self, node: u32) -> &[Incidence] {
        let v = node as usize;
        if v + 1 >= self.inc_offsets.len() {
            return &[];
        }
        &self.inc[self.inc_offsets[v] as usize..self.inc_offsets[v + 1] as usize]
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

    /// Rebuilds the incidence lists from the pair set (counting sort; each
    /// root's list comes out sorted by partner because pairs are sorted).
    pub(super) fn rebuild_incidence(&mut self) {
        let n = self.node_count();
        self.inc_offsets.clear();
        self.inc_offsets.resize(n + 1, 0);
        for &(a, b) in &self.pairs {
            self.inc_offsets[a as usize + 1] += 1;
            self.inc_offsets[b as usize + 1] += 1;
        }
        for v in 0..n {
            self.inc_offsets[v + 1] += self.inc_offsets[v];
        }
        self.cursor.clear();
        self.cursor.extend_from_slice(&self.inc_offsets[..n]);
        self.inc.clear();
        self.inc.resize(self.pairs.len() * 2, Incidence::default());
        for (pid, &(a, b)) in self.pairs.iter().enumerate() {
            let pair = pid as u32;
            let ca = &mut self.cursor[a as usize];
            self.inc[*ca as usize] = Incidence { other: b, pair };
            *ca += 1;
            let cb = &mut self.cursor[b as usize];
            self.inc[*cb as usize] = Incidence { other: a, pair };
            *cb += 1;
        }
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

    // ----- Pearce–Kelly -------------------------------------------------

    /// PK forward search: marks the roots reachable from `start` along
    /// prior → dependent edges that rank below `upper`, collecting them in
    /// `forward` with parent links. With `stronger_than`, only edges
    /// stronger than that pair's are followed. Returns true (and stops) as
    /// soon as `target` is reached: a cycle. The search is breadth-first, so
    /// the cycle found is a shortest one: local, as the cycle rule intends (a
    /// long detour would make it delete some far, unrelated weak edge).
    fn search_dependants(&mut self, start: u32, target: u32, upper: u32, stronger_than: Option<u32>) -> bool {
        let s = self.next_stamp();
        self.forward.clear();
        self.mark[start as usize] = s;
        self.forward.push(start);
        let mut head = 0;
        while head < self.forward.len() {
            let v = self.forward[head];
            head += 1;
            let (from, to) = (self.inc_offsets[v as usize] as usize, self.inc_offsets[v as usize + 1] as usize);
            for k in from..to {
                let Incidence { other: w, pair } = self.inc[k];
                if !is_prior_side(v, w, self.state[pair as usize])
                    || stronger_than.is_some_and(|than| !self.stronger(pair, than))
                {
                    continue;
                }
                if w == target {
                    self.parent[w as usize] = (v, pair);
                    return true;
                }
                if self.mark[w as usize] != s && self.rank[w as usize] < upper {
                    self.mark[w as usize] = s;
                    self.parent[w as usize] = (v, pair);
                    self.forward.push(w);
                }
            }
        }
        false
    }

    /// PK backward search: collects in `backward` the roots from which
    /// `start` is reachable and that rank above `lower`.
    fn search_priors(&mut self, start: u32, lower: u32) {
        let s = self.next_stamp();
        self.backward.clear();
        self.stack.clear();
        self.mark[start as usize] = s;
        self.backward.push(start);
        self.stack.push(start);
        while let Some(v) = self.stack.pop() {
            let (from, to) = (self.inc_offsets[v as usize] as usize, self.inc_offsets[v as usize + 1] as usize);
            for k in from..to {
                let Incidence { other: w, pair } = self.inc[k];
                if is_prior_side(w, v, self.state[pair as usize])
                    && self.mark[w as usize] != s
                    && self.rank[w as usize] > lower
                {
                    self.mark[w as usize] = s;
                    self.backward.push(w);
                    self.stack.push(w);
                }
            }
        }
    }

    /// PK reassignment: the backward set, then the forward set, each in its
    /// old relative order, take the union of their old ranks.
    fn reorder_affected(&mut self) {
        let mut backward = std::mem::take(&mut self.backward);
        let mut forward = std::mem::take(&mut self.forward);
        backward.sort_unstable_by_key(|&v| self.rank[v as usize]);
        forward.sort_unstable_by_key(|&v| self.rank[v as usize]);
        self.rank_pool.clear();
        self.rank_pool.extend(backward.iter().chain(forward.iter()).map(|&v| self.rank[v as usize]));
        self.rank_pool.sort_unstable();
        for (&v, &r) in backward.iter().chain(forward.iter()).zip(self.rank_pool.iter()) {
            if self.rank[v as usize] != r {
                self.moved.push(v);
            }
            self.rank[v as usize] = r;
            self.order[r as usize] = v;
        }
        self.backward = backward;
        self.forward = forward;
    }

    /// After a forward search hit `prior`, writes the path `dependent ⇝
    /// prior` to `cycle` (nodes) and `cycle_pairs` (pair `i` joins nodes `i`
    /// and `i + 1`).
    fn trace_cycle(&mut self, dependent: u32, prior: u32) {
        self.cycle.clear();
        self.cycle_pairs.clear();
        let mut v = prior;
        self.cycle.push(v);
        while v != dependent {
            let (from, pair) = self.parent[v as usize];
            self.cycle_pairs.push(pair);
            self.cycle.push(from);
            v = from;
        }
        self.cycle.reverse();
        self.cycle_pairs.reverse();
    }

    /// Index (into `cycle_pairs`) of the weakest edge on the traced path.
    fn weakest_on_path(&self) -> usize {
        let mut best = 0;
        for i in 1..self.cycle_pairs.len() {
            if self.stronger(self.cycle_pairs[best], self.cycle_pairs[i]) {
                best = i;
            }
        }
        best
    }

    /// Stores `first` then `second` as the blocking path of pair `pid`.
    fn record_blocking_path(&mut self, pid: u32, first: &[u32], second: &[u32]) {
        let need = first.len() + second.len();
        if self.path_pool.len() + need > self.path_pool.capacity() {
            self.make_room_for_path(need);
        }
        let start = self.path_pool.len() as u32;
        self.path_pool.extend_from_slice(first);
        self.path_pool.extend_from_slice(second);
        self.blocking[pid as usize] = (start, (first.len() + second.len()) as u32);
    }

    /// Inserts the wanted edge of pair `pid` (currently absent) with the
    /// cycle rule (module notes). Returns the number of weaker edges deleted
    /// to break cycles, or `None` when the insertion was refused (the graph
    /// is then unchanged).
    ///
    /// On the first cycle found, a second search restricted to edges stronger
    /// than the new one decides at once whether some cycle has the new edge
    /// as its weakest (refusal, with that path recorded as the blocker).
    /// Otherwise every cycle has a weaker edge, so the loop deletes the
    /// weakest edge of each shortest cycle until none is left: it cannot end
    /// in a refusal and never needs to undo a deletion.
    pub(super) fn insert_with_cycle_rule(&mut self, pid: u32) -> Option<usize> {
        let wanted = Edge::wanted(self.delta[pid as usize]);
        let (prior, dependent) = self.edge_endpoints(pid, wanted)?;
        debug_assert_eq!(self.state[pid as usize], Edge::Absent);
        let mut deleted = 0;
        loop {
            let (upper, lower) = (self.rank[prior as usize], self.rank[dependent as usize]);
            if upper < lower {
                break;
            }
            if !self.search_dependants(dependent, prior, upper, None) {
                self.search_priors(prior, lower);
                self.reorder_affected();
                break;
            }
            self.trace_cycle(dependent, prior);
            if deleted == 0 && self.search_dependants(dependent, prior, upper, Some(pid)) {
                self.trace_cycle(dependent, prior);
                let cycle = std::mem::take(&mut self.cycle);
                self.record_blocking_path(pid, &cycle, &[]);
                self.cycle = cycle;
                return None;
            }
            // Delete the weakest edge; what is left of the cycle (through the
            // new edge) is the path that now blocks it.
            let w = self.weakest_on_path();
            let weakest = self.cycle_pairs[w];
            debug_assert!(self.stronger(pid, weakest));
            self.set_edge(weakest, Edge::Absent);
            self.touched.push(weakest);
            deleted += 1;
            let cycle = std::mem::take(&mut self.cycle);
            self.record_blocking_path(weakest, &cycle[w + 1..], &cycle[..=w]);
            self.cycle = cycle;
        }
        self.set_edge(pid, wanted);
        Some(deleted)
    }

    /// Brings pair `pid`'s edge to what its `ΔP` wants: nothing to do,
    /// removal, insertion or reversal (with the cycle rule). Returns whether
    /// the pair now has its wanted edge.
    fn realize_wanted(&mut self, pid: u32, stats: &mut ReorderStats) -> bool {
        let wanted = Edge::wanted(self.delta[pid as usize]);
        let actual = self.state[pid as usize];
        if wanted == actual {
            return true;
        }
        if wanted == Edge::Absent {
            self.set_edge(pid, Edge::Absent);
            stats.edges_removed += 1;
            return true;
        }
        let reversal = actual != Edge::Absent;
        self.set_edge(pid, Edge::Absent);
        match self.insert_with_cycle_rule(pid) {
            Some(broken) => {
                stats.cycles_broken += broken;
                if reversal {
                    stats.reversals_done += 1;
                } else {
                    stats.edges_inserted += 1;
                }
                if let Some((prior, dependent)) = self.edge_endpoints(pid, wanted) {
                    self.became_prior.push(prior);
                    self.gained_prior.push(dependent);
                }
                true
            }
            None => {
                self.set_edge(pid, actual);
                if reversal {
                    stats.reversals_refused += 1;
                } else {
                    stats.insertions_refused += 1;
                }
                false
            }
        }
    }

    // ----- suppressed pairs ---------------------------------------------

    /// Whether the recorded blocking path of suppressed pair `pid` still
    /// runs from its wanted dependent to its wanted prior over existing edges
    /// that are all stronger than it (then a retry would be refused).
    fn blocking_path_holds(&self, pid: u32) -> bool {
        let Some((prior, dependent)) = self.edge_endpoints(pid, Edge::wanted(self.delta[pid as usize])) else {
            return false;
        };
        let (start, len) = self.blocking[pid as usize];
        let Some(path) = self.path_pool.get(start as usize..(start + len) as usize) else {
            return false;
        };
        if path.len() < 2 || path[0] != dependent || path[path.len() - 1] != prior {
            return false;
        }
        path.windows(2).all(|step| match self.find_pair(step[0], step[1]) {
            Some(e) => is_prior_side(step[0], step[1], self.state[e as usize]) && self.stronger(e, pid),
            None => false,
        })
    }

    /// Folds the pairs touched by the last operations into the sorted
    /// suppressed list and drops those that got their wanted edge.
    pub(super) fn refresh_suppressed(&mut self) {
        // Only pairs still suppressed join the list, once each, so its
        // length (and capacity) follows the number of suppressed pairs, not
        // how many pairs a call happened to touch.
        let (delta, state) = (&self.delta, &self.state);
        let still_suppressed = |p: &u32| Edge::wanted(delta[*p as usize]) != state[*p as usize];
        self.suppressed.retain(still_suppressed);
        self.touched.retain(still_suppressed);
        self.touched.sort_unstable();
        self.touched.dedup();
        let listed = &self.suppressed;
        self.touched.retain(|p| listed.binary_search(p).is_err());
        if !self.touched.is_empty() {
            self.suppressed.extend_from_slice(&self.touched);
            self.suppressed.sort_unstable();
        }
        self.touched.clear();
    }

    /// Called when the path pool cannot take `need` more entries without
    /// growing: first drops the dead paths (those of pairs no longer
    /// suppressed), moving the live ones to the front unchanged, and grows
    /// the pool only if the live paths, the new one and some room still do
    /// not fit. The pool's capacity so follows the live paths and the pair
    /// count, however many paths the frames have recorded; a pool that only
    /// appended would grow with the animation length. Compaction never
    /// changes a path, so results do not depend on when it happens.
    ///
    /// A pair is live when its wanted edge differs from its edge, checked on
    /// the pair states rather than the suppressed list, which lags within a
    /// call: a pair that was refused or lost its edge earlier in this call
    /// is already suppressed and keeps its path.
    fn make_room_for_path(&mut self, need: usize) {
        self.path_pool_spare.clear();
        for pid in 0..self.blocking.len() {
            let (start, len) = self.blocking[pid];
            let path = self.path_pool.get(start as usize..(start + len) as usize).filter(|p| !p.is_empty());
            match path {
                Some(path) if self.is_suppressed(pid as u32) => {
                    self.blocking[pid] = (self.path_pool_spare.len() as u32, len);
                    self.path_pool_spare.extend_from_slice(path);
                }
                _ => self.blocking[pid] = (0, 0),
            }
        }
        // Copied back rather than swapped: the pool keeps its capacity and
        // the spare only ever holds the live paths.
        self.path_pool.clear();
        self.path_pool.extend_from_slice(&self.path_pool_spare);
        let live = self.path_pool.len();
        let room = 2 * live + need + PATH_POOL_ROOM_PER_PAIR * self.pairs.len();
        if room > self.path_pool.capacity() {
            self.path_pool.reserve_exact(room - live);
        }
    }

    /// End of a public mutating call: suppressed list and sorted reports.
    pub(super) fn finish_call(&mut self) {
        self.refresh_suppressed();
        for list in [&mut self.became_prior, &mut self.gained_prior, &mut self.moved] {
            list.sort_unstable();
            list.dedup();
        }
    }

    // ----- pair-set changes ---------------------------------------------

    /// Merges the new pair set into the per-pair arrays (keeping the state
    /// of surviving pairs), remaps the suppressed list and lists the new
    /// pairs, strongest first, in `fresh`.
    fn merge_pair_set(
        &mut self,
        pairs: &[(u32, u32)],
        new_pair_delta: &mut impl FnMut(u32, u32) -> f32,
        stats: &mut ReorderStats,
    ) {
        self.refresh_suppressed();
        self.next_pairs.clear();
        self.next_delta.clear();
        self.next_state.clear();
        self.next_blocking.clear();
        self.fresh.clear();
        self.pair_map.clear();
        self.pair_map.resize(self.pairs.len(), u32::MAX);
        let mut old = 0;
        for &pair in pairs {
            while old < self.pairs.len() && self.pairs[old] < pair {
                self.drop_pair(old, stats);
                old += 1;
            }
            let new_pid = self.next_pairs.len() as u32;
            self.next_pairs.push(pair);
            if old < self.pairs.len() && self.pairs[old] == pair {
                self.pair_map[old] = new_pid;
                self.next_delta.push(self.delta[old]);
                self.next_state.push(self.state[old]);
                self.next_blocking.push(self.blocking[old]);
                old += 1;
            } else {
                stats.pairs_added += 1;
                self.next_delta.push(sanitized_delta(new_pair_delta(pair.0, pair.1)));
                self.next_state.push(Edge::Absent);
                self.next_blocking.push((0, 0));
                self.fresh.push(new_pid);
            }
        }
        while old < self.pairs.len() {
            self.drop_pair(old, stats);
            old += 1;
        }
        std::mem::swap(&mut self.pairs, &mut self.next_pairs);
        std::mem::swap(&mut self.delta, &mut self.next_delta);
        std::mem::swap(&mut self.state, &mut self.next_state);
        std::mem::swap(&mut self.blocking, &mut self.next_blocking);
        let map = &self.pair_map;
        self.suppressed.retain_mut(|p| {
            *p = map[*p as usize];
            *p != u32::MAX
        });
        let delta = &self.delta;
        self.fresh.sort_unstable_by(|&a, &b| strength_order(delta, a, b));
    }

    /// Forgets old pair `old` (its edge, if any, disappears).
    fn drop_pair(&mut self, old: usize, stats: &mut ReorderStats) {
        stats.pairs_removed += 1;
        if self.state[old] != Edge::Absent {
            self.edge_count -= 1;
            stats.edges_removed += 1;
        }
    }
}

/// Strongest first: larger `|ΔP|`, ties to the smaller pair index.
fn strength_order(delta: &[f32], a: u32, b: u32) -> std::cmp::Ordering {
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

#[cfg(test)]
mod tests {
    use super::*;

    /// One frame with explicit new `ΔP` values.
    fn frame(order: &mut PriorityOrder, changed: &[(u32, u32, f32)]) -> ReorderStats {
        order.begin_frame();
        let mut stats = order.update_pairs(changed);
        stats += order.retry_suppressed();
        stats
    }

    /// Pairs of a triangle 0, 1, 2 with `ΔP` chosen per pair.
    fn triangle(d01: f32, d02: f32, d12: f32) -> PriorityOrder {
        let mut order = PriorityOrder::new();
        let report = order.build_static(3, &[(0, 1), (0, 2), (1, 2)], &[d01, d02, d12]);
        assert_eq!(report.violations, 0);
        order
    }

    #[test]
    fn static_build_drops_the_weakest_edge_of_a_cycle() {
        // 0 before 1 (|ΔP| 3), 1 before 2 (2), 2 before 0 (1): a cycle.
        let mut order = PriorityOrder::new();
        let report = order.build_static(3, &[(0, 1), (0, 2), (1, 2)], &[-3.0, 1.0, -2.0]);
        assert_eq!((report.edges, report.dropped, report.zero_pairs), (2, 1, 0));
        assert_eq!(order.order(), &[0, 1, 2]);
        assert_eq!(order.suppressed_pairs().collect::<Vec<_>>(), vec![(0, 2)]);
        assert_eq!(order.prior_in_pair(2, 0), None);
        assert_eq!(order.rank_of(2), 2);
    }

    #[test]
    fn reversal_without_cycle_then_retry_restores_suppressed_pair() {
        let mut order = PriorityOrder::new();
        order.build_static(3, &[(0, 1), (0, 2), (1, 2)], &[-3.0, 1.0, -2.0]);
        // ΔP_01 turns positive: 1 becomes prior to 0.
        let stats = frame(&mut order, &[(1, 0, -3.0)]);
        assert_eq!((stats.priority_changes, stats.reversals_done, stats.reversals_refused), (1, 1, 0));
        // The pair (0, 2) wanting 2 before 0 no longer closes a cycle.
        assert_eq!(stats.retries_succeeded, 1);
        assert_eq!(order.suppressed_count(), 0);
        assert_eq!(order.order(), &[1, 2, 0]);
        assert_eq!(order.became_prior(), &[1, 2]);
        assert_eq!(order.count_violations(), 0);
    }

    #[test]
    fn inserting_a_stronger_edge_breaks_the_weakest_edge_of_the_cycle() {
        let mut order = triangle(-3.0, 0.0, -1.0);
        assert_eq!(order.edge_count(), 2);
        // Pair (0, 2) now wants 2 before 0 with |ΔP| 2: cycle 2→0→1→2 whose
        // weakest edge is 1→2 (|ΔP| 1).
        let stats = frame(&mut order, &[(0, 2, 2.0)]);
        assert_eq!((stats.edges_inserted, stats.cycles_broken), (1, 1));
        assert_eq!(order.prior_in_pair(0, 2), Some(2));
        assert_eq!(order.prior_in_pair(1, 2), None);
        assert_eq!(order.suppressed_pairs().collect::<Vec<_>>(), vec![(1, 2)]);
        assert_eq!(order.order(), &[2, 0, 1]);
        // Its blocking path 2→0→1 still holds: nothing to retry.
        let again = order.retry_suppressed();
        assert_eq!(again.retried, 0);
    }

    #[test]
    fn weakest_reversal_is_refused_and_the_old_edge_restored() {
        let mut order = triangle(-3.0, -1.0, -2.0);
        assert_eq!(order.order(), &[0, 1, 2]);
        // (0, 2) wants to turn (2 before 0) but is weaker than 0→1→2.
        let stats = frame(&mut order, &[(0, 2, 1.0)]);
        assert_eq!((stats.priority_changes, stats.reversals_refused, stats.reversals_done), (1, 1, 0));
        assert_eq!(order.prior_in_pair(0, 2), Some(0));
        assert_eq!(order.suppressed_pairs().collect::<Vec<_>>(), vec![(0, 2)]);
        assert!(order.became_prior().is_empty());
        // Weakening 1→2 below it lets the reversal through on the next frame.
        let stats = frame(&mut order, &[(1, 2, -0.5)]);
        assert_eq!((stats.retried, stats.reversals_done, stats.cycles_broken), (1, 1, 1));
        assert_eq!(order.prior_in_pair(0, 2), Some(2));
        assert_eq!(order.prior_in_pair(1, 2), None);
        assert_eq!(order.count_violations(), 0);
    }

    #[test]
    fn blocking_paths_do_not_pile_up_over_frames() {
        // (0, 2) turns back and forth against the stronger path 0→1→2: on
        // every other frame its reversal is refused and a new blocking path
        // recorded, the previous one being dead by then.
        let mut order = triangle(-3.0, -1.0, -2.0);
        let mut capacity_at_100 = 0;
        for k in 0..=10_000 {
            let refused = k % 2 == 0;
            let stats = frame(&mut order, &[(0, 2, if refused { 1.0 } else { -1.0 })]);
            assert_eq!(stats.reversals_refused, usize::from(refused));
            assert_eq!(stats.retried, 0, "the recorded path must hold (frame {k})");
            assert_eq!(order.suppressed_count(), usize::from(refused));
            if k == 100 {
                capacity_at_100 = order.path_pool.capacity();
            }
        }
        // One live path of 3 roots on 3 pairs: the pool holds it and a little
        // room (dead paths fill the room until the next compaction), and it
        // stopped growing long before frame 100.
        assert!(order.path_pool.capacity() <= 16, "pool capacity {}", order.path_pool.capacity());
        assert_eq!(order.path_pool.capacity(), capacity_at_100);
        // The path kept through all those compactions still works: weakening
        // 1→2 below (0, 2) lets the reversal through.
        let stats = frame(&mut order, &[(1, 2, -0.5)]);
        assert_eq!((stats.retried, stats.reversals_done), (1, 1));
        assert_eq!(order.prior_in_pair(0, 2), Some(2));
    }

    #[test]
    fn zero_delta_removes_the_edge_and_unknown_pairs_are_counted() {
        let mut order = triangle(-3.0, -1.0, -2.0);
        let stats = order.update_pairs(&[(0, 2, 0.0), (0, 5, 1.0), (1, 1, 1.0)]);
        assert_eq!((stats.edges_removed, stats.unknown_pairs, stats.pairs_updated), (1, 2, 1));
        assert_eq!(order.edge_count(), 2);
        assert_eq!(order.suppressed_count(), 0);
    }

    #[test]
    fn pair_set_changes_keep_edges_and_insert_new_pairs() {
        let mut order = PriorityOrder::new();
        order.build_static(4, &[(0, 1), (1, 2)], &[-1.0, -1.0]);
        let stats = order.sync_pairs(&[(1, 2), (2, 3)], |a, b| if (a, b) == (2, 3) { 4.0 } else { 0.0 });
        assert_eq!((stats.pairs_added, stats.pairs_removed, stats.edges_removed, stats.edges_inserted), (1, 1, 1, 1));
        assert_eq!(order.prior_in_pair(1, 2), Some(1));
        assert_eq!(order.prior_in_pair(2, 3), Some(3));
        assert_eq!(order.edge_count(), 2);
        assert_eq!(order.count_violations(), 0);
        assert_eq!(order.pair_delta(3, 2), Some(-4.0));
    }

    #[test]
    fn sort_key_orders_strongest_first() {
        let mut order = PriorityOrder::new();
        // Equal |ΔP| everywhere: ties go to the smaller pair, so the pair
        // (1, 2) — the last in the cycle — is the one dropped.
        let report = order.build_static(3, &[(0, 1), (0, 2), (1, 2)], &[-1.0, 1.0, -1.0]);
        assert_eq!(report.dropped, 1);
        assert_eq!(order.suppressed_pairs().collect::<Vec<_>>(), vec![(1, 2)]);
    }
}
