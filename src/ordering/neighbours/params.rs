//! The parameters of the neighbourhood search and the rules every row
//! follows: which roots may be related, how a feather's reach is read, a
//! row of a CSR structure.

use crate::geometry::RootFrame;

/// Parameters of the neighbourhood search.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct NeighbourParams {
    /// k of the k-nearest-root neighbourhoods (`config.k_neighbours`, default 10).
    pub k: usize,
    /// Roots `i, j` with `n_i·n_j` below this are never related. The default
    /// −0.5 (normals more than 120° apart) separates the skins of thin parts
    /// while keeping neighbours across sharp creases; `f32::NEG_INFINITY`
    /// disables the test.
    pub min_normal_dot: f32,
}

impl Default for NeighbourParams {
    fn default() -> Self {
        Self { k: 10, min_normal_dot: -0.5 }
    }
}

/// Row `i` of a CSR structure (empty when `i` is out of range).
pub(super) fn row<'a>(offsets: &[u32], indices: &'a [u32], i: u32) -> &'a [u32] {
    let i = i as usize;
    if i + 1 >= offsets.len() {
        return &[];
    }
    &indices[offsets[i] as usize..offsets[i + 1] as usize]
}

/// Whether two roots may be related: their normals do not disagree more
/// than `min_dot` allows. Symmetric bitwise (the dot product commutes).
#[inline]
pub(super) fn normals_agree(a: &RootFrame, b: &RootFrame, min_dot: f32) -> bool {
    min_dot == f32::NEG_INFINITY || a.normal.dot(b.normal) >= min_dot
}

/// Feather reach as used by the obstacle test: negative or non-finite → 0.
#[inline]
pub(super) fn sanitized_reach(r: f32) -> f32 {
    if r.is_finite() && r > 0.0 { r } else { 0.0 }
}
