//! The ways an ordered run goes through the coat: by levels of the
//! obstacle relation, or serially along the order (a sparse run, or a
//! verifying one that the checks made ahead leave little to adjust), and
//! those checks ahead.

use super::visit::{
    Inputs, Level, Marks, PosedGeometry, Precheck, Selection, adjust_one, check_clear, collect_obstacle_ids, run_level,
};
use super::{AdjustStats, Adjuster, SerialWalk, WALK_SHARE};
use crate::feather::FeatherPose;
use rayon::prelude::*;

impl Adjuster {
    /// How the run goes: a serial walk when sparse, or when verifying by
    /// levels leaves few feathers to adjust once the suspects are checked
    /// ahead (a walk along the order that visits only them and what they
    /// change then costs less than the levels, thousands of them, most
    /// holding a feather or two); else by levels (`None`). Either way gives
    /// the same poses; the choice depends on the checks' answers only,
    /// never on the thread count.
    pub(super) fn choose_walk(
        &mut self,
        inputs: &Inputs<'_>,
        order: &[u32],
        poses: &[FeatherPose],
        sparse: bool,
    ) -> Option<SerialWalk> {
        let n = order.len();
        let mut walk = sparse.then_some(SerialWalk::Symmetric);
        if !sparse && let Selection::Verify { seeds, .. } = inputs.selection {
            self.mark_selected(n, inputs.selection);
            self.precheck(inputs, order, poses);
            let blocked = self.prechecked.iter().filter(|&&p| p == Precheck::Blocked).count();
            let to_adjust = seeds.iter().filter(|&&s| s).count() + blocked;
            #[cfg(test)]
            let share = self.walk_share.unwrap_or(WALK_SHARE);
            #[cfg(not(test))]
            let share = WALK_SHARE;
            if to_adjust.saturating_mul(share) < n {
                self.transpose(inputs.candidates);
                walk = Some(SerialWalk::Transposed);
            }
        }
        walk
    }

    /// The serial walk: the feathers in scope one after another along the
    /// order, each one changed bringing what lies on it into scope.
    pub(super) fn walk_serially(
        &mut self,
        walk: SerialWalk,
        inputs: &Inputs<'_>,
        order: &[u32],
        poses: &mut [FeatherPose],
        stats: &mut AdjustStats,
    ) -> Option<()> {
        let (n, rank, candidates) = (order.len(), inputs.rank, inputs.candidates);
        if walk == SerialWalk::Symmetric {
            self.mark_selected(n, inputs.selection);
        }
        for (k, &i) in order.iter().enumerate() {
            if k % 16 == 0 && !(inputs.keep_going)(k as f32 / n.max(1) as f32) {
                return None;
            }
            let i = i as usize;
            if !self.in_scope[i] {
                continue;
            }
            let marks = Marks { moved: &self.moved, changed: &self.changed, prechecked: &self.prechecked };
            let posed = PosedGeometry {
                triangles: &self.triangles,
                spheres: &self.spheres,
                boxes: &self.boxes,
                bounds: &self.bounds,
            };
            let visit = adjust_one(inputs, i, poses, posed, marks, &mut self.workers[0]);
            self.apply(i, &visit, inputs, poses, stats);
            if self.changed[i] {
                // What lies on it may now meet it or stand on nothing.
                let dependents = match walk {
                    SerialWalk::Symmetric => candidates.row(i),
                    SerialWalk::Transposed => self.dependents.row(i),
                };
                for &j in dependents {
                    if rank[j as usize] > rank[i] {
                        self.in_scope[j as usize] = true;
                    }
                }
            }
        }
        stats.levels = match walk {
            SerialWalk::Symmetric => usize::from(stats.adjusted + stats.verified > 0),
            // The checks ahead, then one feather adjusted after another.
            SerialWalk::Transposed => 1 + stats.adjusted,
        };
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
            let marks = Marks { moved: &self.moved, changed: &self.changed, prechecked: &self.prechecked };
            let posed = PosedGeometry {
                triangles: &self.triangles,
                spheres: &self.spheres,
                boxes: &self.boxes,
                bounds: &self.bounds,
            };
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

    /// Verifying: checks every suspect that is not a seed (those the
    /// ordered pass will most likely only check) ahead, in parallel chunks,
    /// against the poses before the pass. Most checked feathers have no
    /// obstacle that the pass changes before their turn, and their level
    /// then takes this answer instead of checking again; it is the answer
    /// the check would give there (same pose, same obstacles, same body),
    /// so the result does not change, at any thread count. This spreads
    /// the checks over the threads whatever the levels are: the obstacle
    /// relation runs through thousands of levels of a few feathers.
    pub(super) fn precheck(&mut self, inputs: &Inputs<'_>, order: &[u32], poses: &[FeatherPose]) {
        let Selection::Verify { seeds, suspects, .. } = inputs.selection else { return };
        // Sized for every feather up front: how many are checked ahead
        // varies from frame to frame, and the heap must not creep up.
        let n = order.len();
        self.precheck_items.clear();
        self.precheck_items.reserve(n);
        self.precheck_outcomes.reserve(n.saturating_sub(self.precheck_outcomes.len()));
        self.precheck_items.extend(order.iter().copied().filter(|&i| {
            let i = i as usize;
            self.in_scope[i] && suspects[i] && !seeds[i]
        }));
        let items = &self.precheck_items;
        self.precheck_outcomes.clear();
        self.precheck_outcomes.resize(items.len(), Precheck::None);
        let posed = PosedGeometry {
            triangles: &self.triangles,
            spheres: &self.spheres,
            boxes: &self.boxes,
            bounds: &self.bounds,
        };
        let chunk = items.len().div_ceil(self.workers.len()).max(1);
        items
            .par_chunks(chunk)
            .zip(self.precheck_outcomes.par_chunks_mut(chunk))
            .zip(self.workers.par_iter_mut())
            .for_each(|((items, outcomes), worker)| {
                for (k, (&i, out)) in items.iter().zip(outcomes.iter_mut()).enumerate() {
                    // Stopped: the rest stay unchecked (the run is abandoned).
                    if k % 16 == 0 && !(inputs.keep_going)(0.0) {
                        break;
                    }
                    let i = i as usize;
                    collect_obstacle_ids(inputs, i, posed, worker);
                    *out =
                        if check_clear(inputs, i, poses, posed, worker) { Precheck::Clear } else { Precheck::Blocked };
                }
            });
        for (&i, &outcome) in items.iter().zip(&self.precheck_outcomes) {
            self.prechecked[i as usize] = outcome;
        }
    }
}
