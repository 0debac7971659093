//! The ways an ordered run goes through the coat: by levels of the
//! obstacle relation, or serially along the order (a sparse run; a
//! verifying one, with the checks made ahead on the other threads).

use super::visit::{
    Inputs, Level, Marks, PosedGeometry, Precheck, Selection, Worker, adjust_one, check_clear, collect_obstacle_ids,
    kept_locally, run_level,
};
use super::{AdjustStats, Adjuster, SerialWalk};
use crate::feather::FeatherPose;
use std::sync::atomic::{AtomicBool, AtomicU8, AtomicUsize, Ordering};

impl Adjuster {
    /// How the run goes: a serial walk when sparse or verifying (a
    /// verifying run's obstacle relation runs through thousands of levels
    /// of a feather or two, which the walk's checks made ahead spread over
    /// the threads instead); else by levels (`None`). Any way gives the
    /// same poses.
    pub(super) fn choose_walk(&self, inputs: &Inputs<'_>, sparse: bool) -> Option<SerialWalk> {
        if sparse {
            Some(SerialWalk::Symmetric)
        } else if matches!(inputs.selection, Selection::Verify { .. }) && !self.verifies_by_levels() {
            Some(SerialWalk::Transposed)
        } else {
            None
        }
    }

    /// The serial walk of a sparse run: the selected feathers one after
    /// another along the order, each one changed bringing the later
    /// feathers of its (symmetric) candidate row into scope.
    pub(super) fn walk_serially(
        &mut self,
        inputs: &Inputs<'_>,
        order: &[u32],
        poses: &mut [FeatherPose],
        stats: &mut AdjustStats,
    ) -> Option<()> {
        let (n, rank, candidates) = (order.len(), inputs.rank, inputs.candidates);
        self.mark_selected(n, inputs.selection);
        for (k, &i) in order.iter().enumerate() {
            if k % 16 == 0 && !(inputs.keep_going)(k as f32 / n.max(1) as f32) {
                return None;
            }
            let i = i as usize;
            if !self.in_scope[i] {
                continue;
            }
            let marks = Marks { moved: &self.moved, changed: &self.changed, prechecked: self.prechecked.cells() };
            let posed = self.posed.view();
            let visit = adjust_one(inputs, i, poses, posed, marks, &mut self.workers[0]);
            self.apply(i, &visit, inputs, poses, stats);
            if self.changed[i] {
                bring_into_scope(&mut self.in_scope, rank, i, candidates.row(i));
            }
        }
        stats.levels = usize::from(stats.adjusted + stats.verified > 0);
        Some(())
    }

    /// The walk of a verifying run: the feathers in scope one after another
    /// along the order on this thread, each one changed bringing what lies
    /// on it (the obstacle rows' transpose) into scope; meanwhile the other
    /// threads check the suspects and the seeds ahead of it where they lie,
    /// in order, against the coat as it was before the walk ([`Precheck`]):
    /// a suspect is verified by its check, and a feather to be lowered
    /// whose step down fails is kept where it lies by it. The walk
    /// sets aside the poses it gives (see [`super::aside`]) until it ends,
    /// so that the coat those checks read never changes. A feather the
    /// walk reaches before its check ahead is checked there instead; the
    /// checks keep [`LEAD`] positions ahead of the walk, so that when the
    /// walk has only checks to make the two share them rather than race
    /// for the same feathers.
    ///
    /// A check made ahead is the answer the walk's check gives when no
    /// obstacle changed since (same pose, same obstacles, same body), and
    /// one that passed needs redoing only against the obstacles that
    /// changed (see [`adjust_one`]): which checks are made ahead depends on
    /// the threads' timing, the poses never do.
    pub(super) fn walk_checking_ahead(
        &mut self,
        inputs: &Inputs<'_>,
        order: &[u32],
        poses: &mut [FeatherPose],
        stats: &mut AdjustStats,
    ) -> Option<()> {
        let Selection::Verify { seeds, suspects, .. } = inputs.selection else {
            unreachable!("a walk checking ahead verifies")
        };
        let n = order.len();
        self.mark_selected(n, inputs.selection);
        self.transpose(inputs.candidates);
        // Sized for every feather up front, so the heap never creeps up.
        self.precheck_items.clear();
        self.precheck_items.reserve(n);
        self.precheck_items.extend(order.iter().copied().filter(|&i| {
            let i = i as usize;
            // A seed's check where it lies is of use only to one kept in
            // place (checked there when its step down fails).
            self.in_scope[i] && (suspects[i] || seeds[i] && kept_locally(inputs, i, poses[i]))
        }));
        self.aside.reset(n);
        // What the checks ahead read, lent out of the adjuster for the walk.
        let items = std::mem::take(&mut self.precheck_items);
        let prechecked = std::mem::take(&mut self.prechecked);
        let mut workers = std::mem::take(&mut self.workers);
        let posed = std::mem::take(&mut self.posed);
        let before = posed.view();
        let (walker, checkers) = workers.split_first_mut().expect("prepare_workers makes a worker per thread");
        let helpers = rayon::current_num_threads().saturating_sub(1).min(checkers.len());
        let ahead = Ahead {
            items: &items,
            prechecked: prechecked.cells(),
            walked: AtomicUsize::new(0),
            next: AtomicUsize::new(0),
        };
        let done = AtomicBool::new(false);
        #[cfg(test)]
        if self.checks_ahead_first {
            ahead.check(inputs, poses, before, &done, walker);
        }
        let walked = rayon::scope(|s| {
            let (ahead, done, now) = (&ahead, &done, &*poses);
            for worker in checkers.iter_mut().take(helpers) {
                s.spawn(move |_| ahead.check(inputs, now, before, done, worker));
            }
            let walked = self.walk_aside(inputs, order, now, before, ahead, walker, stats);
            done.store(true, Ordering::Relaxed);
            walked
        });
        self.precheck_items = items;
        self.prechecked = prechecked;
        self.workers = workers;
        self.posed = posed;
        walked?;
        self.aside.merge_into(poses, &mut self.posed);
        // The checks ahead, then one feather adjusted after another.
        stats.levels = 1 + stats.adjusted;
        Some(())
    }

    /// The walk of [`Adjuster::walk_checking_ahead`] on this thread, over
    /// the geometry `before` the walk with its changes set aside.
    #[allow(clippy::too_many_arguments)]
    fn walk_aside(
        &mut self,
        inputs: &Inputs<'_>,
        order: &[u32],
        poses: &[FeatherPose],
        before: PosedGeometry<'_>,
        ahead: &Ahead<'_>,
        walker: &mut Worker,
        stats: &mut AdjustStats,
    ) -> Option<()> {
        let (n, rank) = (order.len(), inputs.rank);
        for (k, &i) in order.iter().enumerate() {
            // The checks ahead leave this one and those before it alone.
            ahead.walked.store(k, Ordering::Relaxed);
            if k % 16 == 0 && !(inputs.keep_going)(k as f32 / n.max(1) as f32) {
                return None;
            }
            let i = i as usize;
            if !self.in_scope[i] {
                continue;
            }
            ahead.take(i);
            let marks = Marks { moved: &self.moved, changed: &self.changed, prechecked: ahead.prechecked };
            let posed = PosedGeometry { aside: Some(&self.aside), ..before };
            let visit = adjust_one(inputs, i, poses, posed, marks, walker);
            self.apply_aside(i, &visit, inputs, poses, stats);
            if self.changed[i] {
                bring_into_scope(&mut self.in_scope, rank, i, self.dependents.row(i));
            }
        }
        Some(())
    }

    /// By levels of the obstacle relation: each level's feathers in
    /// parallel, then what became of them applied in order.
    pub(super) fn walk_levels(
        &mut self,
        inputs: &Inputs<'_>,
        order: &[u32],
        poses: &mut [FeatherPose],
        stats: &mut AdjustStats,
    ) -> Option<()> {
        let keep_going = inputs.keep_going;
        self.mark_scope(order, inputs.rank, inputs.candidates, inputs.selection);
        if !keep_going(0.0) {
            return None;
        }
        stats.levels = self.assign_levels(order, inputs.rank, inputs.candidates);
        let levels = stats.levels;
        for l in 0..levels {
            if !keep_going(l as f32 / levels.max(1) as f32) {
                return None;
            }
            let items = self.levels.row(l);
            let outcomes = &mut self.outcomes[..items.len()];
            let marks = Marks { moved: &self.moved, changed: &self.changed, prechecked: self.prechecked.cells() };
            let posed = self.posed.view();
            let done = l as f32 / levels.max(1) as f32;
            run_level(inputs, Level { items, done }, poses, posed, marks, outcomes, &mut self.workers);
            // A level cut short left some outcomes unvisited: nothing is applied.
            if !keep_going(done) {
                return None;
            }
            for k in 0..self.levels.row(l).len() {
                let (i, outcome) = (self.levels.row(l)[k] as usize, self.outcomes[k]);
                self.apply(i, &outcome, inputs, poses, stats);
            }
        }
        Some(())
    }
}

/// Marks in scope the feathers of `lying_on` that come after feather `i`,
/// which changed pose: what lies on it may now meet it or stand on nothing.
fn bring_into_scope(in_scope: &mut [bool], rank: &[u32], i: usize, lying_on: &[u32]) {
    for &j in lying_on {
        if rank[j as usize] > rank[i] {
            in_scope[j as usize] = true;
        }
    }
}

/// The checks made ahead of a verifying walk: the feathers to check, in
/// order; their answers, by feather; the walk's place in the order; the
/// next feather to check.
struct Ahead<'a> {
    items: &'a [u32],
    prechecked: &'a [AtomicU8],
    walked: AtomicUsize,
    next: AtomicUsize,
}

/// A feather's cell in `Ahead::prechecked` while a thread checks it (or
/// once the walk has taken it): no answer yet, and no other thread is to
/// check it.
const TAKEN: u8 = 3;
/// How far ahead of the walk (positions in the order) the checks ahead
/// keep: a check that falls closer goes on from there, so that the walk
/// and the checks share the feathers when the walk has only checks to
/// make (it then checks the feathers in between itself).
const LEAD: usize = 32;
/// How long the walk waits for a check ahead under way on the feather it
/// reaches before it checks the feather itself: about a millisecond, some
/// hundred checks' time (a check takes a few microseconds, so the wait
/// ends sooner unless the checking thread was descheduled).
const WAIT_SPINS: u32 = 1 << 14;

impl Ahead<'_> {
    /// Before the walk visits feather `i`: takes it when no thread checks
    /// it (the walk then checks it itself, and no thread will), else waits
    /// for the check under way to end, up to [`WAIT_SPINS`]. Either way the
    /// walk's answer is the same; waiting spares checking a feather twice
    /// when the walk catches up with the checks ahead.
    fn take(&self, i: usize) {
        let cell = &self.prechecked[i];
        for _ in 0..WAIT_SPINS {
            match cell.compare_exchange(Precheck::None as u8, TAKEN, Ordering::Relaxed, Ordering::Relaxed) {
                Err(TAKEN) => std::hint::spin_loop(),
                _ => return,
            }
        }
    }

    /// Checks feathers ahead of the walk, taking them in order, until none
    /// is left, the walk is `done` or `keep_going` says stop; those the
    /// walk has reached are passed over. Reads only the coat as it was
    /// before the walk (`posed`, `poses`).
    fn check(
        &self,
        inputs: &Inputs<'_>,
        poses: &[FeatherPose],
        posed: PosedGeometry<'_>,
        done: &AtomicBool,
        worker: &mut Worker,
    ) {
        let mut checked = 0usize;
        while !done.load(Ordering::Relaxed) {
            let Some(&i) = self.items.get(self.next.fetch_add(1, Ordering::Relaxed)) else { break };
            let i = i as usize;
            // Close behind the walk, a check would race it to the same
            // feathers: go on from a lead ahead of it instead (the walk
            // checks the feathers between itself and there).
            let lead = self.walked.load(Ordering::Relaxed) + LEAD;
            if (inputs.rank[i] as usize) < lead {
                let ahead = self.items.partition_point(|&j| (inputs.rank[j as usize] as usize) < lead);
                self.next.fetch_max(ahead, Ordering::Relaxed);
                continue;
            }
            let taken = |cell: &AtomicU8| {
                cell.compare_exchange(Precheck::None as u8, TAKEN, Ordering::Relaxed, Ordering::Relaxed).is_err()
            };
            if taken(&self.prechecked[i]) {
                continue;
            }
            checked += 1;
            // Told the share the walk has done (progress never goes back).
            let done_share = self.walked.load(Ordering::Relaxed) as f32 / inputs.rank.len().max(1) as f32;
            if checked % 16 == 0 && !(inputs.keep_going)(done_share) {
                break;
            }
            collect_obstacle_ids(inputs, i, posed, worker);
            let clear = check_clear(inputs, i, poses, posed, worker);
            (if clear { Precheck::Clear } else { Precheck::Blocked }).store(&self.prechecked[i]);
        }
    }
}
