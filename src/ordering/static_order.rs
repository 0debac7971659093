//! The static order (paper §2.2, DESIGN §4): the pair graph made acyclic
//! greedily, then topologically sorted.
//!
//! Every pair with `ΔP ≠ 0` wants an edge. Edges are inserted strongest
//! first (`|ΔP|` descending, ties by `(lo, hi)`) into the dynamic topological
//! order of [`PriorityOrder`]; an edge that would close a cycle is dropped.
//! Since everything already kept is stronger, a dropped edge is the weakest
//! on the cycle it closes, which is the 2015 paper's greedy rule, and the
//! set of kept edges is the unique result of that rule.
//!
//! The kept set does not depend on the starting order, but the work does:
//! Pearce–Kelly only reshuffles when an edge goes backwards. So the order
//! starts from a Kahn topological sort of *all* wanted edges that, when every
//! remaining root still waits on a prior (a cycle), places the root waiting
//! on the fewest. Only edges in or near cycles then need a search.

use super::order_graph::{Edge, PriorityOrder, check_pairs, sanitized_delta};
use std::cmp::Reverse;
use std::time::Instant;

/// What [`PriorityOrder::build_static`] did.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct StaticReport {
    /// Neighbour pairs given.
    pub pairs: usize,
    /// Edges kept in the DAG.
    pub edges: usize,
    /// Edges dropped because they closed a cycle of stronger edges.
    pub dropped: usize,
    /// Pairs with `ΔP` exactly 0 (or non-finite): no edge wanted.
    pub zero_pairs: usize,
    /// Kept edges whose prior root comes after its dependent (must be 0).
    pub violations: usize,
    /// Wall time, seconds.
    pub seconds: f64,
}

impl PriorityOrder {
    /// Builds the static order of `node_count` roots from the pair set
    /// `pairs` (sorted, `a < b`, as [`Neighbourhoods::pairs`](super::Neighbourhoods::pairs)
    /// gives) and their priority differences `deltas[k] = ΔP_ab` of
    /// `pairs[k] = (a, b)`. Replaces any previous state; dropped edges become
    /// suppressed pairs that later frames retry.
    ///
    /// # Panics
    /// If `pairs` is not strictly increasing with `a < b < node_count`, or
    /// `deltas` differs from `pairs` in length.
    pub fn build_static(&mut self, node_count: usize, pairs: &[(u32, u32)], deltas: &[f32]) -> StaticReport {
        let start = Instant::now();
        check_pairs(pairs, node_count);
        assert_eq!(pairs.len(), deltas.len(), "one ΔP per pair");
        self.reset(node_count);
        self.pairs.extend_from_slice(pairs);
        self.delta.extend(deltas.iter().map(|&d| sanitized_delta(d)));
        self.state.resize(pairs.len(), Edge::Absent);
        self.blocking.resize(pairs.len(), (0, 0));
        self.rebuild_incidence();
        self.start_from_kahn_order();

        let mut report = StaticReport { pairs: pairs.len(), ..StaticReport::default() };
        let mut keys = std::mem::take(&mut self.sort_keys);
        keys.clear();
        for (pid, &d) in self.delta.iter().enumerate() {
            if Edge::wanted(d) == Edge::Absent {
                report.zero_pairs += 1;
            } else {
                keys.push(strongest_first_key(d, pid as u32));
            }
        }
        keys.sort_unstable();
        for &key in &keys {
            let pid = key as u32;
            match self.insert_with_cycle_rule(pid) {
                Some(_) => report.edges += 1,
                None => {
                    report.dropped += 1;
                    self.touched.push(pid);
                }
            }
        }
        self.sort_keys = keys;
        self.finish_call();
        self.begin_frame();
        report.violations = self.count_violations();
        report.seconds = start.elapsed().as_secs_f64();
        report
    }

    /// Initial order: Kahn's algorithm over every wanted edge; when all
    /// remaining roots still wait on priors, the one waiting on the fewest
    /// goes next (ties to the smaller index).
    fn start_from_kahn_order(&mut self) {
        let n = self.node_count();
        self.waiting.clear();
        self.waiting.resize(n, 0);
        for (pid, &(lo, hi)) in self.pairs.iter().enumerate() {
            match Edge::wanted(self.delta[pid]) {
                Edge::LoPrior => self.waiting[hi as usize] += 1,
                Edge::HiPrior => self.waiting[lo as usize] += 1,
                Edge::Absent => {}
            }
        }
        let mut heap = std::mem::take(&mut self.heap);
        heap.clear();
        heap.extend((0..n as u32).map(|v| Reverse((self.waiting[v as usize], v))));
        let placed = self.next_stamp();
        self.order.clear();
        while let Some(Reverse((waits, v))) = heap.pop() {
            if self.mark[v as usize] == placed || waits != self.waiting[v as usize] {
                continue;
            }
            self.mark[v as usize] = placed;
            self.rank[v as usize] = self.order.len() as u32;
            self.order.push(v);
            for k in self.inc.span(v as usize) {
                let e = self.inc.items()[k];
                let (lo, hi) = self.pairs[e.pair as usize];
                let v_is_prior = match Edge::wanted(self.delta[e.pair as usize]) {
                    Edge::LoPrior => v == lo,
                    Edge::HiPrior => v == hi,
                    Edge::Absent => false,
                };
                if v_is_prior && self.mark[e.other as usize] != placed {
                    let w = &mut self.waiting[e.other as usize];
                    *w -= 1;
                    heap.push(Reverse((*w, e.other)));
                }
            }
        }
        self.heap = heap;
    }
}

/// Sort key putting the strongest edge first: `|ΔP|` descending (the bits of
/// a non-negative finite `f32` order like its value), then pair index.
fn strongest_first_key(delta: f32, pid: u32) -> u64 {
    (u64::from(!delta.abs().to_bits()) << 32) | u64::from(pid)
}
