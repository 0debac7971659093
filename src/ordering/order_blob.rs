//! Saving and restoring a [`PriorityOrder`] in a state blob (see
//! [`crate::snapshot`]).
//!
//! # What is state
//! The semantic state is what later calls read: the order (the rank is its
//! inverse), the pair set, `ΔP` and the edge of every pair, and the
//! suppressed pairs with their blocking paths. Everything else is derived
//! or scratch:
//! * the incidence lists and the edge count follow from the pairs and edges;
//! * the visit marks and their stamp only ever answer "visited in the
//!   current search?" (`mark[v] == stamp`, with a fresh stamp per search and
//!   all marks cleared on wrap-around), so zero marks with a zero stamp
//!   answer exactly as the saved ones would; the parent links are written
//!   by a search before the cycle trace reads them;
//! * the per-frame root lists are cleared by `begin_frame` before a frame
//!   fills them, and the pending `touched` list is empty between public
//!   calls;
//! * the path pool holds dead paths besides the live ones. A pair's
//!   blocking path is read only while the pair is suppressed, and a pair
//!   only becomes suppressed through a refusal or a cycle break that
//!   records a new path for it, so only the suppressed pairs' paths are
//!   stored; on load the pool holds just those (compaction, which a full
//!   pool triggers, moves paths without changing them).
//!
//! # Layout
//! node count (u64); order (u32 slice); pair count (u64) then `(lo, hi)`
//! as two u32 each; `ΔP` (f32 slice); edges (u64 count, one u8 each: 0 none,
//! 1 `lo` prior, 2 `hi` prior); suppressed pair indices (u32 slice); then
//! each suppressed pair's blocking path (u32 slice of nodes).

use super::order_graph::{Edge, PriorityOrder};
use crate::error::{Error, ErrorKind, Result};
use crate::snapshot::{Reader, Writer};

impl PriorityOrder {
    /// Appends the order's semantic state to a state blob (module notes).
    pub fn write_state(&self, w: &mut Writer) {
        w.u64(self.node_count() as u64);
        w.u32s(&self.order);
        w.u64(self.pairs.len() as u64);
        for &(lo, hi) in &self.pairs {
            w.u32(lo);
            w.u32(hi);
        }
        w.f32s(&self.delta);
        w.u64(self.state.len() as u64);
        for &edge in &self.state {
            w.u8(edge_code(edge));
        }
        w.u32s(&self.suppressed);
        for &pid in &self.suppressed {
            w.u32s(self.blocking_path(pid));
        }
    }

    /// Reads an order of `roots` roots written by
    /// [`write_state`](Self::write_state), refusing with `InvalidState`
    /// anything a real order could not be: the order must be a permutation
    /// of the roots; pairs strictly increasing with `lo < hi < roots`; every
    /// `ΔP` finite; an edge only on a pair with `ΔP ≠ 0`, and every edge
    /// going forward in the order (so the graph is acyclic); the suppressed
    /// list exactly the pairs whose edge differs from what their `ΔP`
    /// wants, each with a blocking path of at most `roots` roots running
    /// from its wanted dependent to its wanted prior.
    pub fn read_state(r: &mut Reader<'_>, roots: usize) -> Result<Self> {
        if u32::try_from(roots).is_err() {
            return Err(invalid("too many roots for a saved order"));
        }
        if r.u64()? != roots as u64 {
            return Err(invalid("saved order has another root count"));
        }
        let mut s = Self::default();
        s.reset(roots);

        r.u32s_into(&mut s.order, Some(roots))?;
        s.rank.fill(u32::MAX);
        for (k, &v) in s.order.iter().enumerate() {
            match s.rank.get_mut(v as usize) {
                Some(slot) if *slot == u32::MAX => *slot = k as u32,
                _ => return Err(invalid("saved order is not a permutation of the roots")),
            }
        }

        let m = r.len(8, None)?;
        for k in 0..m {
            let (lo, hi) = (r.u32()?, r.u32()?);
            if lo >= hi || hi as usize >= roots || (k > 0 && s.pairs[k - 1] >= (lo, hi)) {
                return Err(invalid(format!("saved pair {k} = ({lo}, {hi}) breaks the sorted pair set")));
            }
            s.pairs.push((lo, hi));
        }
        r.f32s_into(&mut s.delta, Some(m))?;
        if s.delta.iter().any(|d| !d.is_finite()) {
            return Err(invalid("saved order holds a non-finite priority difference"));
        }
        r.len(1, Some(m))?;
        for pid in 0..m {
            let edge =
                edge_from_code(r.u8()?).ok_or_else(|| invalid(format!("saved edge of pair {pid} is unknown")))?;
            if edge != Edge::Absent && Edge::wanted(s.delta[pid]) == Edge::Absent {
                return Err(invalid(format!("saved pair {pid} has an edge but no priority difference")));
            }
            s.state.push(edge);
            if let Some((prior, dependent)) = s.edge_endpoints(pid as u32, edge) {
                if s.rank[prior as usize] >= s.rank[dependent as usize] {
                    return Err(invalid(format!("saved edge of pair {pid} goes backwards in the order")));
                }
                s.edge_count += 1;
            }
        }

        r.u32s_into(&mut s.suppressed, None)?;
        let wanted_differs = |p: usize| Edge::wanted(s.delta[p]) != s.state[p];
        let mut expected = (0..m).filter(|&p| wanted_differs(p));
        let listed_exactly = s.suppressed.iter().all(|&p| expected.next() == Some(p as usize));
        if !listed_exactly || expected.next().is_some() {
            return Err(invalid("saved suppressed pairs do not match the saved edges"));
        }
        s.blocking.resize(m, (0, 0));
        let mut path = Vec::new();
        for k in 0..s.suppressed.len() {
            let pid = s.suppressed[k];
            r.u32s_into(&mut path, None)?;
            let ends = s.edge_endpoints(pid, Edge::wanted(s.delta[pid as usize]));
            let joins =
                matches!((ends, path.first(), path.last()), (Some((p, d)), Some(&f), Some(&l)) if f == d && l == p);
            if path.len() > roots || !joins || path.iter().any(|&v| v as usize >= roots) {
                return Err(invalid(format!("saved blocking path of pair {pid} is not a path between its roots")));
            }
            let start = u32::try_from(s.path_pool.len()).map_err(|_| invalid("saved blocking paths are too long"))?;
            s.blocking[pid as usize] = (start, path.len() as u32);
            s.path_pool.extend_from_slice(&path);
        }
        s.rebuild_incidence();
        Ok(s)
    }

    /// The recorded blocking path of pair `pid` (empty when there is none).
    fn blocking_path(&self, pid: u32) -> &[u32] {
        let Some(&(start, len)) = self.blocking.get(pid as usize) else {
            return &[];
        };
        self.path_pool.get(start as usize..start as usize + len as usize).unwrap_or(&[])
    }
}

fn edge_code(edge: Edge) -> u8 {
    match edge {
        Edge::Absent => 0,
        Edge::LoPrior => 1,
        Edge::HiPrior => 2,
    }
}

fn edge_from_code(code: u8) -> Option<Edge> {
    match code {
        0 => Some(Edge::Absent),
        1 => Some(Edge::LoPrior),
        2 => Some(Edge::HiPrior),
        _ => None,
    }
}

fn invalid(message: impl Into<String>) -> Error {
    Error::new(ErrorKind::InvalidState, message)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn round_trip(order: &PriorityOrder, n: usize) -> PriorityOrder {
        let mut w = Writer::new(7);
        order.write_state(&mut w);
        let blob = w.finish();
        let mut r = Reader::open(&blob, 7).unwrap();
        let back = PriorityOrder::read_state(&mut r, n).unwrap();
        r.finish().unwrap();
        back
    }

    /// The blob of `order`.
    fn blob_of(order: &PriorityOrder) -> Vec<u8> {
        let mut w = Writer::new(7);
        order.write_state(&mut w);
        w.finish()
    }

    #[test]
    fn a_suppressed_pair_and_its_path_survive() {
        // 0→1 (3), 1→2 (2) kept; 2→0 (1) dropped and blocked by 0→1→2.
        let mut order = PriorityOrder::new();
        order.build_static(3, &[(0, 1), (0, 2), (1, 2)], &[-3.0, 1.0, -2.0]);
        let back = round_trip(&order, 3);
        assert_eq!(back.order(), order.order());
        assert_eq!(back.ranks(), order.ranks());
        assert_eq!(back.edge_count(), order.edge_count());
        assert_eq!(back.suppressed_pairs().collect::<Vec<_>>(), vec![(0, 2)]);
        assert_eq!(blob_of(&back), blob_of(&order));
        // Both behave the same on the next frame.
        let (mut a, mut b) = (order, back);
        for o in [&mut a, &mut b] {
            o.begin_frame();
            o.update_pairs(&[(1, 0, -3.0)]);
            o.retry_suppressed();
        }
        assert_eq!(blob_of(&a), blob_of(&b));
        assert_eq!(a.became_prior(), b.became_prior());
    }

    #[test]
    fn inconsistent_orders_are_refused() {
        let mut order = PriorityOrder::new();
        order.build_static(3, &[(0, 1), (0, 2), (1, 2)], &[-3.0, 1.0, -2.0]);
        let read = |o: &PriorityOrder, n: usize| {
            let blob = blob_of(o);
            let mut r = Reader::open(&blob, 7).unwrap();
            PriorityOrder::read_state(&mut r, n).map(|_| ())
        };
        assert!(read(&order, 3).is_ok());
        assert_eq!(read(&order, 4).unwrap_err().kind(), ErrorKind::InvalidState);
        let mut bad = order.clone();
        bad.order.swap(0, 2);
        assert!(read(&bad, 3).is_err(), "edges going backwards");
        let mut bad = order.clone();
        bad.order[0] = bad.order[1];
        assert!(read(&bad, 3).is_err(), "not a permutation");
        let mut bad = order.clone();
        bad.suppressed.clear();
        assert!(read(&bad, 3).is_err(), "suppressed list out of step with the edges");
        let mut bad = order.clone();
        bad.delta[1] = f32::NAN;
        assert!(read(&bad, 3).is_err(), "non-finite ΔP");
        let mut bad = order.clone();
        bad.pairs.swap(0, 1);
        assert!(read(&bad, 3).is_err(), "unsorted pairs");
        let mut bad = order.clone();
        bad.path_pool.iter_mut().for_each(|v| *v = 9);
        assert!(read(&bad, 3).is_err(), "path through unknown roots");
        let mut bad = order.clone();
        bad.path_pool.reverse();
        assert!(read(&bad, 3).is_err(), "path not from the wanted dependent to the wanted prior");
        let mut bad = order.clone();
        bad.delta[0] = 0.0;
        assert!(read(&bad, 3).is_err(), "edge on a pair without priority difference");
        let mut bad = order.clone();
        bad.state[1] = Edge::HiPrior;
        assert!(read(&bad, 3).is_err(), "a cycle 0→1→2→0 (some edge must go backwards)");
        let mut legal = order.clone();
        legal.state[1] = Edge::LoPrior;
        assert!(read(&legal, 3).is_ok(), "a refused reversal: the old edge kept, the pair suppressed");
    }

    type Frame = (Vec<(u16, i8)>, Vec<u16>, Vec<(u8, u8, i8)>);

    /// One frame on `order`: drop some pairs, offer new ones, change some
    /// `ΔP` (small integers, so ties and zeros happen), retry. Returns the
    /// stats without timing and the per-frame root lists.
    fn step(order: &mut PriorityOrder, n: usize, (updates, drops, offers): &Frame) -> impl PartialEq + std::fmt::Debug {
        let mut next = order.pairs().to_vec();
        for &d in drops {
            if !next.is_empty() {
                next.remove(d as usize % next.len());
            }
        }
        let offered: Vec<(u32, u32, f32)> = offers
            .iter()
            .map(|&(a, b, d)| (a as u32 % n as u32, b as u32 % n as u32, d as f32))
            .filter(|&(a, b, _)| a != b)
            .map(|(a, b, d)| (a.min(b), a.max(b), d))
            .collect();
        next.extend(offered.iter().map(|&(a, b, _)| (a, b)));
        next.sort_unstable();
        next.dedup();
        let changed: Vec<(u32, u32, f32)> = match next.len() {
            0 => Vec::new(),
            len => updates
                .iter()
                .map(|&(k, d)| {
                    let (a, b) = next[k as usize % len];
                    (a, b, d as f32 * 0.5)
                })
                .collect(),
        };
        order.begin_frame();
        let delta_of = |a, b| offered.iter().find(|o| (o.0, o.1) == (a, b)).map_or(1.0, |o| o.2);
        let mut stats = order.sync_pairs(&next, delta_of);
        stats += order.update_pairs(&changed);
        stats += order.retry_suppressed();
        stats.seconds = 0.0;
        (stats, order.became_prior().to_vec(), order.gained_prior().to_vec(), order.moved().to_vec())
    }

    /// Root count, pairs, their `ΔP`, then the frames.
    type Case = (usize, Vec<(u32, u32)>, Vec<f32>, Vec<Frame>);

    fn arb_case() -> impl Strategy<Value = Case> {
        use proptest::collection::vec;
        (3usize..20).prop_flat_map(|n| {
            let all = n * (n - 1) / 2;
            let graph = vec((0u8..3, -4i8..=4), all);
            let frame = (
                vec((any::<u16>(), -4i8..=4), 0..10),
                vec(any::<u16>(), 0..3),
                vec((any::<u8>(), any::<u8>(), -4i8..=4), 0..3),
            );
            (Just(n), graph, vec(frame, 1..8)).prop_map(|(n, picks, frames)| {
                let mut pairs = Vec::new();
                let mut deltas = Vec::new();
                let mut k = 0;
                for a in 0..n as u32 {
                    for b in a + 1..n as u32 {
                        if picks[k].0 > 0 {
                            pairs.push((a, b));
                            deltas.push(picks[k].1 as f32 * 0.5);
                        }
                        k += 1;
                    }
                }
                (n, pairs, deltas, frames)
            })
        })
    }

    use proptest::prelude::*;

    proptest! {
        #![proptest_config(ProptestConfig { rng_seed: proptest::test_runner::RngSeed::Fixed(0x0070_6c75_6d61_6765), cases: 256, ..ProptestConfig::default() })]

        /// After any frame, a saved order loads, saves the same bytes, and
        /// behaves exactly like the original on the next frame.
        #[test]
        fn restored_orders_behave_identically((n, pairs, deltas, frames) in arb_case()) {
            let mut order = PriorityOrder::new();
            order.build_static(n, &pairs, &deltas);
            for frame in &frames {
                let blob = blob_of(&order);
                let mut restored = round_trip(&order, n);
                prop_assert_eq!(blob_of(&restored), blob.clone());
                let a = step(&mut order, n, frame);
                let b = step(&mut restored, n, frame);
                prop_assert_eq!(a, b);
                prop_assert_eq!(blob_of(&order), blob_of(&restored));
            }
        }

        /// When the path pool compacts (a full pool) changes nothing: an
        /// order whose pool has room for every path ever recorded, so never
        /// compacts, behaves exactly like one that compacts as it goes.
        #[test]
        fn path_pool_compaction_changes_no_result((n, pairs, deltas, frames) in arb_case()) {
            let mut order = PriorityOrder::new();
            order.build_static(n, &pairs, &deltas);
            let mut roomy = order.clone();
            roomy.path_pool.reserve(1 << 16);
            for frame in &frames {
                let a = step(&mut order, n, frame);
                let b = step(&mut roomy, n, frame);
                prop_assert_eq!(a, b);
                prop_assert_eq!(blob_of(&order), blob_of(&roomy));
            }
        }
    }
}
