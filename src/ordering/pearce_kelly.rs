//! Inserting an edge into the dynamic topological order: Pearce–Kelly's
//! searches and reassignment, and the paper's cycle rule on top of them
//! (paper §3.3; DESIGN §5 step 3). Storage: [`PriorityOrder`] in
//! `order_graph`.
//!
//! # Why our own Pearce–Kelly
//! Insertions use the Pearce–Kelly algorithm (PK, paper ref. \[12\]): when an
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

use super::order_graph::{Edge, Incidence, PriorityOrder, ReorderStats, is_prior_side};

impl PriorityOrder {
    /// PK forward search: marks the roots reachable from `start` along
    /// prior → dependent edges that rank below `upper`, collecting them in
    /// `forward` with parent links. With `stronger_than`, only edges
    /// stronger than that pair's are followed. Returns true (and stops) as
    /// soon as `target` is reached: a cycle. The search is breadth-first, so
    /// the cycle found is a shortest one: local, as the cycle rule intends (a
    /// long detour would make it delete some far, unrelated weak edge).
    pub(super) fn search_dependants(
        &mut self,
        start: u32,
        target: u32,
        upper: u32,
        stronger_than: Option<u32>,
    ) -> bool {
        let s = self.next_stamp();
        self.forward.clear();
        self.mark[start as usize] = s;
        self.forward.push(start);
        let mut head = 0;
        while head < self.forward.len() {
            let v = self.forward[head];
            head += 1;
            for k in self.inc.span(v as usize) {
                let Incidence { other: w, pair } = self.inc.items()[k];
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
    pub(super) fn search_priors(&mut self, start: u32, lower: u32) {
        let s = self.next_stamp();
        self.backward.clear();
        self.stack.clear();
        self.mark[start as usize] = s;
        self.backward.push(start);
        self.stack.push(start);
        while let Some(v) = self.stack.pop() {
            for k in self.inc.span(v as usize) {
                let Incidence { other: w, pair } = self.inc.items()[k];
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
    pub(super) fn reorder_affected(&mut self) {
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
    pub(super) fn trace_cycle(&mut self, dependent: u32, prior: u32) {
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
    pub(super) fn weakest_on_path(&self) -> usize {
        let mut best = 0;
        for i in 1..self.cycle_pairs.len() {
            if self.stronger(self.cycle_pairs[best], self.cycle_pairs[i]) {
                best = i;
            }
        }
        best
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
    pub(super) fn realize_wanted(&mut self, pid: u32, stats: &mut ReorderStats) -> bool {
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
}
