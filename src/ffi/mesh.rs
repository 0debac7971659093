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
    /// Optional skeleton the vertices are skinned to; may be NULL. Without
    /// `orientations` or a `flow_source`, feathers then run from the head
    /// down the trunk and out along every limb (see `PlumageSkeleton`).
    pub skeleton: *const PlumageSkeleton,
    /// Optional layer per vertex (any finite value); may be NULL. Where two
    /// neighbouring feathers' layers differ, the one on the higher layer
    /// lies on top, whatever the growth priority says; equal layers keep it.
    pub layer: *const f32,
    /// Optional feather type per vertex, an index into `feather_types`; may
    /// be NULL. Each feather takes the type of the corner of its triangle
    /// nearest its root.
    pub feather_type: *const u32,
    /// The types `feather_type` indexes (`feather_type_count` of them, 1 to
    /// 256; fill each with `plumage_feather_type_init`).
    pub feather_types: *const PlumageFeatherType,
    /// Number of `feather_types`.
    pub feather_type_count: u32,
}

/// One kind of feather of a type map: the proportions of its shape to the
/// local spacing (`PlumageConfig.length_per_spacing` and
/// `width_per_spacing` are the configuration's own). 0 takes the
/// configuration's value; every type shares the configuration's shaft
/// segments and bend limit, and its feather_length, feather_width and
/// feather_thickness overrides when they are set.
#[repr(C)]
#[derive(Clone, Copy, Debug)]
pub struct PlumageFeatherType {
    /// Shaft length over the local spacing (0 to 100).
    pub length_per_spacing: f32,
    /// Vane width over the local spacing (0 to 100).
    pub width_per_spacing: f32,
    /// Multiplier of the thickness the width gives (0 to 100; 0 means 1).
    pub thickness_scale: f32,
}

impl From<crate::feather::FeatherType> for PlumageFeatherType {
    fn from(t: crate::feather::FeatherType) -> Self {
        Self {
            length_per_spacing: t.length_per_spacing,
            width_per_spacing: t.width_per_spacing,
            thickness_scale: t.thickness_scale,
        }
    }
}

/// A skeleton and the skin weights binding the mesh's vertices to it, for
/// the orientation field. Joint positions are at the rest pose, in the
/// same space as the mesh's positions (for glTF: the joint nodes' world
/// positions in the pose the rest positions were taken in). Joints no
/// vertex is weighted to and with no weighted ancestor are ignored; each
/// remaining tree of joints is walked from its head, so that every bone
/// points away from it. A skeleton whose weighted joints have no bone
/// leaves the flow axis.
#[repr(C)]
#[derive(Clone, Copy, Debug)]
pub struct PlumageSkeleton {
    /// Number of joints (1 to 65536).
    pub joint_count: u32,
    /// Joints each vertex is weighted to (1 to 16; glTF's JOINTS_0 gives 4).
    pub influences: u32,
    /// xyz per joint, `3 * joint_count` floats (finite, within the
    /// coordinate range the positions have).
    pub joint_positions: *const f32,
    /// Per joint, its parent's index, or -1 for a root; no cycles.
    pub joint_parents: *const i32,
    /// `influences` joint indices per vertex (`influences * vertex_count`).
    pub vertex_joints: *const u32,
    /// `influences` weights per vertex, finite and >= 0.
    pub vertex_weights: *const f32,
    /// The joint the flow starts from (the tip of the head or the beak), or
    /// -1: the end joint (one bone attached) farthest against
    /// `PlumageConfig.flow_axis` when that is set, else farthest up and
    /// forward (+Y plus +Z, glTF's conventions).
    pub head_joint: i32,
}

/// The size of the first published `PlumageMeshDesc` (up to `width_scale`).
pub(crate) const MESH_DESC_V1_SIZE: usize = std::mem::offset_of!(PlumageMeshDesc, skeleton);

impl PlumageMeshDesc {
    pub(crate) fn empty() -> Self {
        Self {
            struct_size: std::mem::size_of::<Self>() as u32,
            positions: std::ptr::null(),
            vertex_count: 0,
            indices: std::ptr::null(),
            triangle_count: 0,
            orientations: std::ptr::null(),
            spacing_scale: std::ptr::null(),
            length_scale: std::ptr::null(),
            width_scale: std::ptr::null(),
            skeleton: std::ptr::null(),
            layer: std::ptr::null(),
            feather_type: std::ptr::null(),
            feather_types: std::ptr::null(),
            feather_type_count: 0,
        }
    }
}

/// Borrowed view of the caller's mesh arrays.
///
/// # Safety
/// Every non-NULL pointer of `desc` points to as many elements as its count
/// says, alive for `'a`.
pub(crate) unsafe fn read_mesh<'a>(
    desc: *const PlumageMeshDesc,
    types: &'a mut Vec<crate::feather::FeatherType>,
) -> Result<MeshInput<'a>, Failure> {
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
            skeleton: read_skeleton(d.skeleton, d.vertex_count)?,
            layer: optional_slice(d.layer, d.vertex_count),
            feather_types: read_feather_types(&d, types)?,
        })
    }
}

/// Borrowed view of the type map (`None` when `feather_type` is NULL), the
/// table copied into `types`.
///
/// # Safety
/// As for [`read_mesh`].
unsafe fn read_feather_types<'a>(
    d: &PlumageMeshDesc,
    types: &'a mut Vec<crate::feather::FeatherType>,
) -> Result<Option<crate::feather::FeatherTypeMap<'a>>, Failure> {
    if d.feather_type.is_null() {
        return Ok(None);
    }
    if d.feather_types.is_null() {
        return Err(Failure::null("feather_types"));
    }
    let count = d.feather_type_count as usize;
    if count == 0 || count > crate::feather::MAX_FEATHER_TYPES {
        let text = format!("feather_type_count {count}: it must be 1 to {}", crate::feather::MAX_FEATHER_TYPES);
        return Err(Failure::new(PLUMAGE_STATUS_INVALID_ARGUMENT, text));
    }
    // SAFETY: non-NULL, `count` elements per the contract (bounded above).
    let table = unsafe { std::slice::from_raw_parts(d.feather_types, count) };
    types.clear();
    types.extend(table.iter().map(|t| crate::feather::FeatherType {
        length_per_spacing: t.length_per_spacing,
        width_per_spacing: t.width_per_spacing,
        thickness_scale: t.thickness_scale,
    }));
    // SAFETY: non-NULL, one per vertex per the contract.
    let per_vertex = unsafe { std::slice::from_raw_parts(d.feather_type, d.vertex_count) };
    Ok(Some(crate::feather::FeatherTypeMap { per_vertex, types }))
}

/// Borrowed view of a skeleton's arrays (`None` for NULL).
///
/// # Safety
/// As for [`read_mesh`]: every pointer of a non-NULL `skeleton` points to as
/// many elements as its counts say.
unsafe fn read_skeleton<'a>(
    skeleton: *const PlumageSkeleton,
    vertex_count: usize,
) -> Result<Option<crate::SkeletonInput<'a>>, Failure> {
    if skeleton.is_null() {
        return Ok(None);
    }
    // SAFETY: non-NULL, forwarded contract.
    let s = unsafe { *skeleton };
    for (ptr, name) in [
        (s.joint_positions.cast::<u8>(), "skeleton joint_positions"),
        (s.joint_parents.cast(), "skeleton joint_parents"),
        (s.vertex_joints.cast(), "skeleton vertex_joints"),
        (s.vertex_weights.cast(), "skeleton vertex_weights"),
    ] {
        if ptr.is_null() {
            return Err(Failure::null(name));
        }
    }
    let joints = s.joint_count as usize;
    if joints == 0 || joints > crate::skeleton::MAX_JOINTS {
        let text = format!("skeleton joint_count {joints}: it must be 1 to {}", crate::skeleton::MAX_JOINTS);
        return Err(Failure::new(PLUMAGE_STATUS_INVALID_ARGUMENT, text));
    }
    let influences = s.influences as usize;
    if influences == 0 || influences > crate::skeleton::MAX_INFLUENCES {
        let text = format!("skeleton influences {influences}: it must be 1 to {}", crate::skeleton::MAX_INFLUENCES);
        return Err(Failure::new(PLUMAGE_STATUS_INVALID_ARGUMENT, text));
    }
    let per_vertex = checked_len(vertex_count, influences, "vertex_count × skeleton influences")?;
    // SAFETY: non-NULL, lengths per the contract; sizes bounded above.
    unsafe {
        Ok(Some(crate::SkeletonInput {
            joint_positions: std::slice::from_raw_parts(s.joint_positions, 3 * joints),
            joint_parents: std::slice::from_raw_parts(s.joint_parents, joints),
            influences,
            vertex_joints: std::slice::from_raw_parts(s.vertex_joints, per_vertex),
            vertex_weights: std::slice::from_raw_parts(s.vertex_weights, per_vertex),
            head_joint: s.head_joint,
        }))
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
