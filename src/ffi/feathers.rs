//! What a host reads back about the feathers: their count (and the mesh's
//! vertex count every frame must give), one `PlumageFeather` record each,
//! their triangles, and every feather as a mesh (`PlumageFeatherGeometry`).

use super::boundary::{PlumageSystem, with_system_ref};
use super::convention::{Failure, copy_out, read_versioned, write_versioned};
use super::status::*;

/// One feather, copied out by `plumage_system_feathers`.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default)]
pub struct PlumageFeather {
    /// Stable 64-bit id derived from the root's rest binding and the seed.
    pub id: u64,
    /// Position of the feather in the adjustment order (0 = placed first).
    pub order_index: u32,
    /// The caller's triangle (index into the rest mesh's triangles) holding the root.
    pub triangle: u32,
    /// Barycentric weights of the root on that triangle's three corners.
    pub barycentric: [f32; 3],
    /// Root position at the current pose.
    pub root: [f32; 3],
    /// Unit surface normal at the root.
    pub normal: [f32; 3],
    /// Unit shaft direction after pitch and roll.
    pub direction: [f32; 3],
    /// Pitch, radians (positive lifts the tip away from the skin).
    pub pitch: f32,
    /// Roll about the shaft, radians.
    pub roll: f32,
    /// Length along the shaft, as placed: a feather that cannot lie down
    /// within the pitch limit is shortened, and one that fits at no size is
    /// left out with length and width 0 (its triangles collapse to the root).
    pub length: f32,
    /// Width across the vanes, as placed (shortened with the length).
    pub width: f32,
    /// Thickness.
    pub thickness: f32,
    /// Always 0 (keeps the struct free of padding bytes).
    pub reserved: u32,
}

impl From<&crate::stats::FeatherRecord> for PlumageFeather {
    fn from(f: &crate::stats::FeatherRecord) -> Self {
        Self {
            id: f.id,
            order_index: f.order_index,
            triangle: f.triangle,
            barycentric: f.barycentric,
            root: f.root,
            normal: f.normal,
            direction: f.direction,
            pitch: f.pitch,
            roll: f.roll,
            length: f.length,
            width: f.width,
            thickness: f.thickness,
            reserved: 0,
        }
    }
}

// Copied out as they are: free of padding, so that the bytes a host sees
// are fully defined (and comparable with memcmp).
const _: () = assert!(std::mem::size_of::<PlumageFeather>() == 8 + 4 + 4 + 4 * 3 * 4 + 4 * 5 + 4);

/// Caller buffers for `plumage_system_feather_geometry`: every feather as a
/// mesh. Fill with `plumage_feather_geometry_init`, then point the buffers
/// you want at your memory (NULL skips one); capacities count elements
/// (floats, indices or bytes). The library writes the totals back.
///
/// Layout: feathers one after the other, in the order of
/// `plumage_system_feathers`; a feather's vertices are contiguous, and the
/// layout (indices, UVs, vertex-to-feather map, counts) depends only on the
/// configuration and the mesh, never on the frame, so a host can upload it
/// once and refresh positions and normals each frame.
#[repr(C)]
#[derive(Clone, Copy, Debug)]
pub struct PlumageFeatherGeometry {
    /// Set by `plumage_feather_geometry_init` to `sizeof(PlumageFeatherGeometry)`.
    pub struct_size: u32,
    /// Padding; always 0.
    pub reserved: u32,
    /// Out: number of feathers.
    pub feather_count: u64,
    /// Out: vertices of all feathers.
    pub vertex_count: u64,
    /// Out: triangles of all feathers.
    pub triangle_count: u64,
    /// xyz per vertex, world space (3 × vertex_count floats).
    pub positions: *mut f32,
    /// Capacity of `positions`, in floats.
    pub positions_capacity: usize,
    /// Unit normal per vertex, facing away from the skin on the feather's
    /// visible side (3 × vertex_count floats).
    pub normals: *mut f32,
    /// Capacity of `normals`, in floats.
    pub normals_capacity: usize,
    /// (u, v) per vertex: u from 0 at the root to 1 at the tip along the
    /// shaft, v from 0 to 1 across the vanes (0.5 on the shaft, 1 on the
    /// binormal side) (2 × vertex_count floats).
    pub uvs: *mut f32,
    /// Capacity of `uvs`, in floats.
    pub uvs_capacity: usize,
    /// Three vertex indices per triangle, into the whole vertex array, each
    /// triangle facing away from the skin (3 × triangle_count).
    pub indices: *mut u32,
    /// Capacity of `indices`, in indices.
    pub indices_capacity: usize,
    /// Per vertex: the index of its feather (vertex_count).
    pub vertex_feathers: *mut u32,
    /// Capacity of `vertex_feathers`.
    pub vertex_feathers_capacity: usize,
    /// Per feather: its vertex count (feather_count).
    pub vertex_counts: *mut u32,
    /// Capacity of `vertex_counts`.
    pub vertex_counts_capacity: usize,
    /// Per feather: its triangle count (feather_count).
    pub triangle_counts: *mut u32,
    /// Capacity of `triangle_counts`.
    pub triangle_counts_capacity: usize,
    /// Per feather: 1 when placed, 0 when left out (no size fitted; its
    /// vertices all lie at its root and its triangles have no area, so a
    /// host may skip it) (feather_count bytes).
    pub placed: *mut u8,
    /// Capacity of `placed`, in bytes.
    pub placed_capacity: usize,
}

impl PlumageFeatherGeometry {
    /// No buffers, no totals, `struct_size` set.
    pub(crate) fn empty() -> Self {
        let null_f = std::ptr::null_mut();
        let null_u = std::ptr::null_mut();
        Self {
            struct_size: std::mem::size_of::<Self>() as u32,
            reserved: 0,
            feather_count: 0,
            vertex_count: 0,
            triangle_count: 0,
            positions: null_f,
            positions_capacity: 0,
            normals: null_f,
            normals_capacity: 0,
            uvs: null_f,
            uvs_capacity: 0,
            indices: null_u,
            indices_capacity: 0,
            vertex_feathers: null_u,
            vertex_feathers_capacity: 0,
            vertex_counts: null_u,
            vertex_counts_capacity: 0,
            triangle_counts: null_u,
            triangle_counts_capacity: 0,
            placed: std::ptr::null_mut(),
            placed_capacity: 0,
        }
    }
}

/// Writes the number of feathers to `*out`.
///
/// # Safety
/// `sys` is NULL or a live handle from `plumage_system_create`; other threads
/// may only make read-only (`const`) calls on it during the call. `out` is NULL
/// or points to a writable `size_t`.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn plumage_system_feather_count(sys: *const PlumageSystem, out: *mut usize) -> PlumageStatus {
    with_system_ref(sys, |system| {
        if out.is_null() {
            return Err(Failure::null("out"));
        }
        // SAFETY: non-NULL, points to a size_t (contract).
        unsafe { *out = system.feather_count() };
        Ok(())
    })
}

/// Writes the number of vertices every frame must provide (the rest mesh's
/// count, in the caller's numbering) to `*out`.
///
/// # Safety
/// `sys` is NULL or a live handle from `plumage_system_create`; other threads
/// may only make read-only (`const`) calls on it during the call. `out` is NULL
/// or points to a writable `size_t`.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn plumage_system_vertex_count(sys: *const PlumageSystem, out: *mut usize) -> PlumageStatus {
    with_system_ref(sys, |system| {
        if out.is_null() {
            return Err(Failure::null("out"));
        }
        // SAFETY: non-NULL, points to a size_t (contract).
        unsafe { *out = system.vertex_count() };
        Ok(())
    })
}

/// Copies one `PlumageFeather` per feather into `buf` (`capacity` elements).
/// `*out_len` receives the feather count; a NULL or too small `buf` gives
/// PLUMAGE_STATUS_BUFFER_TOO_SMALL and writes nothing else.
///
/// # Safety
/// `sys` is NULL or a live handle from `plumage_system_create`; other threads
/// may only make read-only (`const`) calls on it during the call. `buf` is NULL
/// or holds `capacity` writable elements; `out_len` is NULL or points to a
/// writable `size_t`.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn plumage_system_feathers(
    sys: *const PlumageSystem,
    buf: *mut PlumageFeather,
    capacity: usize,
    out_len: *mut usize,
) -> PlumageStatus {
    with_system_ref(sys, |system| {
        let records: Vec<PlumageFeather> = system.feathers().iter().map(PlumageFeather::from).collect();
        copy_out(&records, buf, capacity, out_len)
    })
}

/// Copies the feathers' triangles as xyz floats, in the order of
/// `plumage_system_feathers`; `capacity` and `*out_len` count floats. A
/// feather of one shaft segment (the default, `shaft_segments` = 1) has two
/// triangles of three corners, 18 floats: (root, tip, left corner), (root,
/// right corner, tip), where "left" lies on the binormal side (normal ×
/// shaft); both face away from the skin, and the root and tip corners of
/// the two triangles are bit-identical, so a host can share them. With S ≥ 2
/// segments each feather has 4·S − 4 triangles (9 floats each), in the
/// order of `plumage_system_feather_geometry`'s indices; that call also
/// gives shared vertices, normals and UVs.
///
/// # Safety
/// `sys` is NULL or a live handle from `plumage_system_create`; other threads
/// may only make read-only (`const`) calls on it during the call. `xyz` is NULL
/// or holds `capacity` writable floats; `out_len` is NULL or points to a
/// writable `size_t`.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn plumage_system_feather_triangles(
    sys: *const PlumageSystem,
    xyz: *mut f32,
    capacity: usize,
    out_len: *mut usize,
) -> PlumageStatus {
    with_system_ref(sys, |system| copy_out(system.feather_triangles().as_flattened(), xyz, capacity, out_len))
}

/// Fills `geometry` with NULL buffers, zero capacities and totals, and sets
/// `struct_size`. NULL is ignored.
///
/// # Safety
/// `geometry` is NULL or points to writable memory for one `PlumageFeatherGeometry`.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn plumage_feather_geometry_init(geometry: *mut PlumageFeatherGeometry) {
    if geometry.is_null() {
        return;
    }
    // SAFETY: non-NULL, points to a PlumageFeatherGeometry (contract).
    unsafe { geometry.write(PlumageFeatherGeometry::empty()) };
}

/// Copies every feather out as a mesh at the current pose: positions,
/// normals, UVs, triangle indices, the feather of each vertex, per-feather
/// vertex and triangle counts and whether each feather is placed (see
/// `PlumageFeatherGeometry` for the layout). The totals are always written
/// back. Each non-NULL buffer must hold what it is for; if any is too
/// small the call returns PLUMAGE_STATUS_BUFFER_TOO_SMALL (naming it) and
/// writes no buffer, so call once with no buffers to learn the totals.
///
/// # Safety
/// `sys` is NULL or a live handle from `plumage_system_create`; other threads
/// may only make read-only (`const`) calls on it during the call. `geometry`
/// is NULL or points to a `PlumageFeatherGeometry` whose `struct_size` bytes
/// are readable and writable and whose non-NULL buffers hold their stated
/// capacities of writable elements.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn plumage_system_feather_geometry(
    sys: *const PlumageSystem,
    geometry: *mut PlumageFeatherGeometry,
) -> PlumageStatus {
    with_system_ref(sys, |system| {
        if geometry.is_null() {
            return Err(Failure::null("geometry"));
        }
        let size = std::mem::size_of::<PlumageFeatherGeometry>();
        // SAFETY: non-NULL, caller struct of struct_size bytes (contract).
        let mut io =
            unsafe { read_versioned(geometry, size, PlumageFeatherGeometry::empty(), "PlumageFeatherGeometry") }?;
        let mesh = system.feather_mesh();
        io.feather_count = mesh.vertex_counts.len() as u64;
        io.vertex_count = mesh.positions.len() as u64;
        io.triangle_count = mesh.indices.len() as u64;
        // SAFETY: as above; only the totals change.
        unsafe { write_versioned(geometry, size, io, "PlumageFeatherGeometry") }?;
        let flat = |v: &[[f32; 3]]| v.as_flattened().to_vec();
        let buffers = CallerBuffers {
            name: "PlumageFeatherGeometry",
            floats: [
                ("positions", io.positions, io.positions_capacity, flat(&mesh.positions)),
                ("normals", io.normals, io.normals_capacity, flat(&mesh.normals)),
                ("uvs", io.uvs, io.uvs_capacity, mesh.uvs.as_flattened().to_vec()),
            ],
            indices: [
                ("indices", io.indices, io.indices_capacity, mesh.indices.as_flattened().to_vec()),
                ("vertex_feathers", io.vertex_feathers, io.vertex_feathers_capacity, mesh.vertex_feathers),
                ("vertex_counts", io.vertex_counts, io.vertex_counts_capacity, mesh.vertex_counts),
                ("triangle_counts", io.triangle_counts, io.triangle_counts_capacity, mesh.triangle_counts),
            ],
            bytes: [("placed", io.placed, io.placed_capacity, mesh.placed)],
        };
        buffers.check()?;
        // SAFETY: every non-NULL buffer holds its capacity (contract), checked above to be enough.
        unsafe { buffers.write() };
        Ok(())
    })
}

/// One caller buffer of a struct of buffers: (field name, caller pointer,
/// capacity, contents).
pub(super) type CallerBuffer<T> = (&'static str, *mut T, usize, Vec<T>);

/// The buffers of one call that fills a struct of caller buffers
/// (`PlumageFeatherGeometry`, `PlumageFeatherTemplate`) with what goes
/// into each.
pub(super) struct CallerBuffers<const F: usize, const I: usize, const B: usize> {
    /// The C struct's name, for messages.
    pub name: &'static str,
    pub floats: [CallerBuffer<f32>; F],
    pub indices: [CallerBuffer<u32>; I],
    pub bytes: [CallerBuffer<u8>; B],
}

impl<const F: usize, const I: usize, const B: usize> CallerBuffers<F, I, B> {
    /// Refuses the call when a given buffer is too small for its contents.
    pub fn check(&self) -> Result<(), Failure> {
        let sizes = self.floats.iter().map(|(n, p, c, v)| (*n, p.is_null(), *c, v.len()));
        let sizes = sizes
            .chain(self.indices.iter().map(|(n, p, c, v)| (*n, p.is_null(), *c, v.len())))
            .chain(self.bytes.iter().map(|(n, p, c, v)| (*n, p.is_null(), *c, v.len())));
        for (name, null, capacity, needed) in sizes {
            if !null && capacity < needed {
                return Err(Failure::new(
                    PLUMAGE_STATUS_BUFFER_TOO_SMALL,
                    format!("{}.{name} holds {capacity} elements but {needed} are needed", self.name),
                ));
            }
        }
        Ok(())
    }

    /// Copies the contents into every non-NULL buffer.
    ///
    /// # Safety
    /// Every non-NULL pointer holds at least as many elements as its contents.
    pub unsafe fn write(&self) {
        fn put<T: Copy>(ptr: *mut T, items: &[T]) {
            if !ptr.is_null() {
                // SAFETY: the caller's buffer holds items.len() elements (checked).
                unsafe { std::ptr::copy_nonoverlapping(items.as_ptr(), ptr, items.len()) };
            }
        }
        self.floats.iter().for_each(|(_, p, _, v)| put(*p, v));
        self.indices.iter().for_each(|(_, p, _, v)| put(*p, v));
        self.bytes.iter().for_each(|(_, p, _, v)| put(*p, v));
    }
}
