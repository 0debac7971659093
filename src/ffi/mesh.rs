//! The mesh a host passes to `plumage_system_create`: `PlumageMeshDesc`
//! and the checked, borrowed view of its arrays.

use super::convention::{Failure, read_versioned};
use super::status::*;
use crate::MeshInput;

/// A mesh handed to `plumage_system_create`, in the caller's own numbering.
/// Triangle soups (vertices split along UV or normal seams) are welded by
/// position internally. Fill with `plumage_mesh_desc_init` first.
#[repr(C)]
#[derive(Clone, Copy, Debug)]
pub struct PlumageMeshDesc {
    /// `sizeof(PlumageMeshDesc)` as the caller compiled it (set by init).
    pub struct_size: u32,
    /// xyz per vertex, `3 * vertex_count` floats.
    pub positions: *const f32,
    /// Number of vertices; every frame must give exactly this many.
    pub vertex_count: usize,
    /// Three vertex indices per triangle.
    pub indices: *const u32,
    /// Number of triangles.
    pub triangle_count: usize,
    /// Optional xyz tangent hint per vertex (the orientation field); may be NULL.
    pub orientations: *const f32,
    /// Optional spacing multiplier per vertex (0 = bare skin); may be NULL.
    pub spacing_scale: *const f32,
    /// Optional feather length multiplier per vertex; may be NULL.
    pub length_scale: *const f32,
    /// Optional feather width multiplier per vertex; may be NULL.
    pub width_scale: *const f32,
}

pub(crate) const MESH_DESC_V1_SIZE: usize = std::mem::size_of::<PlumageMeshDesc>();

impl PlumageMeshDesc {
    pub(crate) fn empty() -> Self {
        Self {
            struct_size: MESH_DESC_V1_SIZE as u32,
            positions: std::ptr::null(),
            vertex_count: 0,
            indices: std::ptr::null(),
            triangle_count: 0,
            orientations: std::ptr::null(),
            spacing_scale: std::ptr::null(),
            length_scale: std::ptr::null(),
            width_scale: std::ptr::null(),
        }
    }
}

/// Borrowed view of the caller's mesh arrays.
///
/// # Safety
/// Every non-NULL pointer of `desc` points to as many elements as its count
/// says, alive for `'a`.
pub(crate) unsafe fn read_mesh<'a>(desc: *const PlumageMeshDesc) -> Result<MeshInput<'a>, Failure> {
    if desc.is_null() {
        return Err(Failure::null("mesh description"));
    }
    // SAFETY: forwarded contract.
    let d = unsafe { read_versioned(desc, MESH_DESC_V1_SIZE, PlumageMeshDesc::empty(), "PlumageMeshDesc") }?;
    if d.positions.is_null() {
        return Err(Failure::null("mesh positions"));
    }
    if d.indices.is_null() {
        return Err(Failure::null("mesh indices"));
    }
    if d.vertex_count == 0 {
        return Err(Failure::new(PLUMAGE_STATUS_EMPTY_MESH, "mesh has no vertices"));
    }
    if d.triangle_count == 0 {
        return Err(Failure::new(PLUMAGE_STATUS_EMPTY_MESH, "mesh has no triangles"));
    }
    let floats = checked_len(d.vertex_count, 3, "vertex_count")?;
    let idx = checked_len(d.triangle_count, 3, "triangle_count")?;
    // SAFETY: non-NULL, lengths per the contract; sizes checked against overflow.
    unsafe {
        Ok(MeshInput {
            positions: std::slice::from_raw_parts(d.positions, floats),
            indices: std::slice::from_raw_parts(d.indices, idx),
            orientations: optional_slice(d.orientations, floats),
            spacing_scale: optional_slice(d.spacing_scale, d.vertex_count),
            length_scale: optional_slice(d.length_scale, d.vertex_count),
            width_scale: optional_slice(d.width_scale, d.vertex_count),
        })
    }
}

/// `count × per` elements of 4 bytes, refused when the byte size overflows
/// or exceeds what a slice may span.
pub(crate) fn checked_len(count: usize, per: usize, name: &str) -> Result<usize, Failure> {
    count
        .checked_mul(per)
        .filter(|n| n.checked_mul(4).is_some_and(|b| b <= isize::MAX as usize))
        .filter(|_| count <= u32::MAX as usize)
        .ok_or_else(|| Failure::new(PLUMAGE_STATUS_SIZE_OVERFLOW, format!("{name} {count} is too large")))
}

unsafe fn optional_slice<'a>(ptr: *const f32, len: usize) -> Option<&'a [f32]> {
    // SAFETY: forwarded contract of `read_mesh`.
    (!ptr.is_null()).then(|| unsafe { std::slice::from_raw_parts(ptr, len) })
}
