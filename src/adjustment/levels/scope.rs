//! Which feathers a run may visit (its scope) and the levels of the
//! obstacle relation it goes through, and the transpose of the obstacle
//! rows a serial walk finds what lies on a feather in.

use super::Adjuster;
use super::visit::{Selection, Visit};
use crate::csr::CsrView;

impl Adjuster {
    /// The scope of a sparse run to begin with: the selected feathers.
    pub(super) fn mark_selected(&mut self, n: usize, selection: Selection<'_>) {
        self.in_scope.clear();
        match selection {
            Selection::All => self.in_scope.resize(n, true),
            Selection::Subset(s) | Selection::Propagate { seeds: s, .. } => self.in_scope.extend_from_slice(s),
            Selection::Verify { seeds, suspects, .. } => {
                self.in_scope.extend(seeds.iter().zip(suspects).map(|(&s, &v)| s | v))
            }
        }
    }

    /// Marks the feathers that may be adjusted. With propagation that is
    /// the seeds (and suspects) and everything downstream of them in the
    /// obstacle relation.
    pub(super) fn mark_scope(
        &mut self,
        order: &[u32],
        rank: &[u32],
        candidates: CsrView<'_, u32>,
        selection: Selection<'_>,
    ) {
        let n = order.len();
        self.in_scope.clear();
        match selection {
            Selection::All => self.in_scope.resize(n, true),
            Selection::Subset(s) => self.in_scope.extend_from_slice(s),
            Selection::Propagate { seeds, .. } | Selection::Verify { seeds, .. } => {
                self.in_scope.extend_from_slice(seeds);
                if let Selection::Verify { suspects, .. } = selection {
                    self.in_scope.iter_mut().zip(suspects).for_each(|(s, &v)| *s |= v);
                }
                for &i in order {
                    let i = i as usize;
                    if !self.in_scope[i] {
                        let ri = rank[i];
                        self.in_scope[i] =
                            candidates.row(i).iter().any(|&j| rank[j as usize] < ri && self.in_scope[j as usize]);
                    }
                }
            }
        }
    }

    /// Levels of the feathers in scope and the per-level lists (each in
    /// order). Returns the number of levels.
    pub(super) fn assign_levels(&mut self, order: &[u32], rank: &[u32], candidates: CsrView<'_, u32>) -> usize {
        let n = order.len();
        self.level.clear();
        self.level.resize(n, 0);
        let mut levels = 0u32;
        for &i in order {
            let i = i as usize;
            if !self.in_scope[i] {
                continue;
            }
            let ri = rank[i];
            let below = candidates
                .row(i)
                .iter()
                .filter(|&&j| rank[j as usize] < ri)
                .map(|&j| self.level[j as usize])
                .max()
                .unwrap_or(0);
            self.level[i] = below + 1;
            levels = levels.max(below + 1);
        }
        let levels = levels as usize;
        // Level lists sized for the worst case (one feather per level, or
        // all in one) from the start, so that sparse frames never grow them.
        self.levels.reserve_rows(n);
        self.levels.reserve_items(n);
        self.outcomes.reserve(n.saturating_sub(self.outcomes.len()));
        self.levels.begin(levels);
        for &i in order {
            let l = self.level[i as usize] as usize;
            if l > 0 {
                self.levels.count(l - 1);
            }
        }
        self.levels.allocate();
        for &i in order {
            let l = self.level[i as usize] as usize;
            if l > 0 {
                self.levels.place(l - 1, i);
            }
        }
        let widest = (0..levels).map(|l| self.levels.row(l).len()).max().unwrap_or(0);
        if self.outcomes.len() < widest {
            self.outcomes.resize(widest, Visit::Skipped);
        }
        levels
    }

    /// The transpose of `candidates` into the dependents: row j lists the
    /// feathers whose candidates list j, in increasing order.
    pub(super) fn transpose(&mut self, candidates: CsrView<'_, u32>) {
        let n = candidates.rows();
        let entries = || (0..n).flat_map(move |i| candidates.row(i).iter().map(move |&j| (j as usize, i as u32)));
        self.dependents.rebuild(n, entries);
    }
}
