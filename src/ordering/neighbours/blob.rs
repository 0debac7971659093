//! The neighbourhoods in a state blob, and the exhaustive obstacle search
//! the tests compare the fast one against.

use super::Neighbourhoods;
use super::params::row;
#[cfg(test)]
use super::params::sanitized_reach;
use crate::error::{Error, ErrorKind, Result};
#[cfg(test)]
use crate::geometry::RootFrame;
use crate::snapshot::{Reader, Writer};

#[cfg(test)]
impl Neighbourhoods {
    /// Obstacle candidates: one radius query per root, in tree order, into
    /// scratch rows; then a transpose. The relation is symmetric bitwise
    /// (distances and `reach_i + reach_j` commute, and
    /// the tree query is exact), so the transpose of the scratch rows is the
    /// same relation with every row sorted by index, without sorting.
    pub(super) fn obstacles_by_tree(&mut self, frames: &[RootFrame], reach: &[f32]) {
        let n = frames.len();
        self.tree.rebuild(frames.iter().map(|f| f.position));
        let mut offsets = vec![0u32];
        self.scratch_indices.clear();
        let max_reach = reach.iter().fold(0.0f32, |m, &r| m.max(sanitized_reach(r)));
        for (i, frame) in frames.iter().enumerate() {
            if !reach.is_empty() {
                let reach_i = sanitized_reach(reach[i]);
                let bound = reach_i + max_reach;
                let indices = &mut self.scratch_indices;
                self.tree.within(frame.position, bound * bound, &mut |j, d2| {
                    let limit = reach_i + sanitized_reach(reach[j as usize]);
                    if j as usize != i && d2 <= limit * limit {
                        indices.push(j);
                    }
                });
            }
            offsets.push(self.scratch_indices.len() as u32);
        }
        let scratch = &self.scratch_indices;
        let entries = || (0..n as u32).flat_map(|i| row(&offsets, scratch, i).iter().map(move |&j| (j as usize, i)));
        self.obstacles.rebuild(n, entries);
    }
}

/// Saved state (see [`crate::snapshot`]): the k-nearest rows, then the
/// obstacle rows, each as CSR offsets then indices. The obstacle relation is
/// symmetric and its rows sorted, so only the part above the diagonal
/// (`j > i`) is stored and the rest is its transpose. The pair set is
/// derived from the k-nearest rows on load, and the k-d tree and the fill
/// buffers are scratch of [`rebuild`](Self::rebuild), so none of them is
/// stored.
impl Neighbourhoods {
    /// Appends the neighbourhoods to a state blob.
    pub fn write_state(&self, w: &mut Writer) {
        write_csr(w, &self.knn_offsets, &self.knn_indices);
        let n = self.len() as u32;
        debug_assert!((0..n).all(|i| self.obstacle_candidates_of(i).windows(2).all(|p| p[0] < p[1])));
        debug_assert!((0..n).all(|i| {
            self.obstacle_candidates_of(i).iter().all(|&j| self.obstacle_candidates_of(j).binary_search(&i).is_ok())
        }));
        let mut offsets = vec![0u32];
        let mut upper = Vec::new();
        for i in 0..n {
            let candidates = self.obstacle_candidates_of(i);
            upper.extend_from_slice(&candidates[candidates.partition_point(|&j| j <= i)..]);
            offsets.push(upper.len() as u32);
        }
        write_csr(w, &offsets, &upper);
    }

    /// Reads neighbourhoods of `roots` roots written by
    /// [`write_state`](Self::write_state). Everything is checked before it
    /// is used: offsets start at 0, never decrease and end at the index
    /// count; every index is a root other than the row's own; stored
    /// obstacle rows are strictly increasing and above the diagonal (so the
    /// rebuilt relation is symmetric with sorted rows). Anything else is
    /// refused with `InvalidState`.
    pub fn read_state(r: &mut Reader<'_>, roots: usize) -> Result<Self> {
        if u32::try_from(roots).is_err() {
            return Err(invalid("too many roots for a saved neighbourhood"));
        }
        let mut s = Self::default();
        read_csr(r, roots, &mut s.knn_offsets, &mut s.knn_indices, "neighbourhood")?;
        let (mut offsets, mut upper) = (Vec::new(), Vec::new());
        read_csr(r, roots, &mut offsets, &mut upper, "obstacle")?;
        if upper.len() > u32::MAX as usize / 2 {
            return Err(invalid("saved obstacle rows are too long"));
        }
        for i in 0..roots as u32 {
            let stored = row(&offsets, &upper, i);
            if stored.first().is_some_and(|&j| j < i) || stored.windows(2).any(|p| p[0] >= p[1]) {
                return Err(invalid(format!("saved obstacle row {i} is not increasing above the diagonal")));
            }
        }
        s.symmetric_obstacles_from_upper(roots, &offsets, &upper);
        s.rebuild_pairs(roots);
        Ok(s)
    }

    /// Fills the obstacle rows from their part above the diagonal: row `i`
    /// is `{j < i : i ∈ upper_j}` (in increasing `j`) followed by `upper_i`.
    fn symmetric_obstacles_from_upper(&mut self, n: usize, offsets: &[u32], upper: &[u32]) {
        // Within row j: first the i < j that list j (in increasing i),
        // then j's own upper row.
        let lower = (0..n as u32).flat_map(|i| row(offsets, upper, i).iter().map(move |&j| (j as usize, i)));
        let own = (0..n as u32).flat_map(|i| row(offsets, upper, i).iter().map(move |&j| (i as usize, j)));
        self.obstacles.rebuild(n, || lower.clone().chain(own.clone()));
    }
}

/// Writes one CSR structure: offsets (at least the leading 0), then indices.
fn write_csr(w: &mut Writer, offsets: &[u32], indices: &[u32]) {
    w.u32s(if offsets.is_empty() { &[0] } else { offsets });
    w.u32s(indices);
}

/// Reads one CSR structure of `roots` rows and checks its shape and that
/// every index names another root.
fn read_csr(
    r: &mut Reader<'_>,
    roots: usize,
    offsets: &mut Vec<u32>,
    indices: &mut Vec<u32>,
    what: &str,
) -> Result<()> {
    r.u32s_into(offsets, Some(roots + 1))?;
    r.u32s_into(indices, None)?;
    if offsets[0] != 0 || offsets.windows(2).any(|w| w[0] > w[1]) || offsets[roots] as usize != indices.len() {
        return Err(invalid(format!("saved {what} offsets are not a valid row layout")));
    }
    for i in 0..roots as u32 {
        if row(offsets, indices, i).iter().any(|&j| j == i || j as usize >= roots) {
            return Err(invalid(format!("saved {what} row {i} names an invalid root")));
        }
    }
    Ok(())
}

fn invalid(message: impl Into<String>) -> Error {
    Error::new(ErrorKind::InvalidState, message)
}
