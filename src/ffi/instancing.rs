//! What a game engine reads back to draw feathers as instances of one
//! card: a packed record per feather (`PlumageFeatherInstance`), the card
//! (`PlumageFeatherTemplate`), and the feathers the last call changed. The
//! packing and its convention live in `crate::feather` (`record.rs`); this
//! file only copies them out.

use super::boundary::{PlumageSystem, with_system_ref};
use super::convention::{Failure, copy_out, read_versioned, write_versioned};
use super::feathers::CallerBuffers;
use super::status::PlumageStatus;
use crate::feather::InstanceRecord;

/// The bend that a `PlumageFeatherInstance.bends` value of 32767 stands
/// for, radians (π as a float): a joint's bend is `bends[k] *
/// PLUMAGE_INSTANCE_BEND_RANGE / 32767`.
#[allow(clippy::approx_constant)] // a literal, so that cbindgen writes it into the header
pub const PLUMAGE_INSTANCE_BEND_RANGE: f32 = 3.1415927;

const _: () = assert!(PLUMAGE_INSTANCE_BEND_RANGE == crate::feather::RECORD_BEND_RANGE);

/// One feather packed for instancing (36 bytes, no padding), copied out by
/// `plumage_system_feather_instances`.
///
/// Convention. The root frame has x along the feather's tangential
/// direction (the shaft before pitch), y along the binormal (the "left"
/// vane's side, normal × shaft), z along the surface normal; x × y = z.
/// The feather's own frame is the root frame turned by the roll about x
/// (right-hand rule: a positive roll lifts the +y vane off the skin), then
/// by the pitch about y, tip towards +z (a positive pitch lifts the tip).
/// `rotation` turns the own frame into world space.
///
/// The shaft runs from the root along the own frame's +x and is cut into
/// S equal segments (`PlumageFeatherTemplate.segments`). Segment k points
/// along (cos a_k, 0, sin a_k), with a_0 = 0 and a_k = a_(k-1) + bend_k:
/// a positive bend turns the rest of the shaft towards +z (off the skin),
/// a negative one towards the skin. A template vertex (x, y, 0) carried by
/// segment k (`PlumageFeatherTemplate.vertex_segments`) lands at
///
/// ```text
/// p = sum over j < k of (L/S)(cos a_j, 0, sin a_j)
///     + (x - k/S) L (cos a_k, 0, sin a_k) + (0, y W, 0)
/// world = root + rotate(q, p)
/// ```
///
/// with L = `length`, W = `width`; `shaders/feather_instance.vert` does
/// this on the GPU. The result matches `plumage_system_feather_geometry`'s
/// positions within 1e-4 of the feather's length.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct PlumageFeatherInstance {
    /// Root position, world space.
    pub root: [f32; 3],
    /// The own frame's rotation to world as a unit quaternion (x, y, z, w),
    /// each component `value / 32767`, w >= 0; normalise after decoding.
    pub rotation: [i16; 4],
    /// Length along the shaft as placed (0 for a feather left out: every
    /// vertex at the root; see `PlumageFeather.length`).
    pub length: f32,
    /// Width across the vanes as placed.
    pub width: f32,
    /// Bend of each joint from the root, `value * PLUMAGE_INSTANCE_BEND_RANGE
    /// / 32767` radians; joints past S - 1 are 0.
    pub bends: [i16; 3],
    /// Always 0 (keeps the struct free of padding bytes).
    pub reserved: u16,
}

const _: () = assert!(std::mem::size_of::<PlumageFeatherInstance>() == 36);
const _: () = assert!(std::mem::size_of::<PlumageFeatherInstance>() <= 40);
const _: () = assert!(crate::feather::MAX_JOINTS == 3);

impl From<&InstanceRecord> for PlumageFeatherInstance {
    fn from(r: &InstanceRecord) -> Self {
        Self { root: r.root, rotation: r.rotation, length: r.length, width: r.width, bends: r.bends, reserved: 0 }
    }
}

/// Caller buffers for `plumage_system_feather_template`: the card every
/// feather of the system is drawn from. Fill with
/// `plumage_feather_template_init`, point the buffers you want at your
/// memory (NULL skips one); capacities count elements. The library writes
/// the counts back.
#[repr(C)]
#[derive(Clone, Copy, Debug)]
pub struct PlumageFeatherTemplate {
    /// Set by `plumage_feather_template_init` to `sizeof(PlumageFeatherTemplate)`.
    pub struct_size: u32,
    /// Out: shaft segments S of every feather of the system.
    pub segments: u32,
    /// Out: vertices of the card (those of one feather in
    /// `plumage_system_feather_geometry`, in the same order).
    pub vertex_count: u32,
    /// Out: triangles of the card (one feather's, in the same order).
    pub triangle_count: u32,
    /// Out: where the vane corners sit along the shaft, as a fraction of
    /// the length.
    pub vane_split: f32,
    /// Padding; always 0.
    pub reserved: u32,
    /// xyz per vertex in the feather's own frame for unit length and width:
    /// x from 0 at the root to 1 at the tip along the unbent shaft, y
    /// across (+-0.5 at the vane corners, + on the binormal side), z 0
    /// (3 × vertex_count floats).
    pub positions: *mut f32,
    /// Capacity of `positions`, in floats.
    pub positions_capacity: usize,
    /// (u, v) per vertex, as in `PlumageFeatherGeometry.uvs` (u = x,
    /// v = 0.5 + y) (2 × vertex_count floats).
    pub uvs: *mut f32,
    /// Capacity of `uvs`, in floats.
    pub uvs_capacity: usize,
    /// Three vertex indices per triangle, facing away from the skin
    /// (3 × triangle_count).
    pub indices: *mut u32,
    /// Capacity of `indices`, in indices.
    pub indices_capacity: usize,
    /// Per vertex: the shaft segment k (0 at the root) that carries it: the
    /// vertex sits (x - k/S) of the length along segment k (vertex_count).
    pub vertex_segments: *mut u32,
    /// Capacity of `vertex_segments`.
    pub vertex_segments_capacity: usize,
}

impl PlumageFeatherTemplate {
    /// No buffers, no counts, `struct_size` set.
    pub(crate) fn empty() -> Self {
        Self {
            struct_size: std::mem::size_of::<Self>() as u32,
            segments: 0,
            vertex_count: 0,
            triangle_count: 0,
            vane_split: 0.0,
            reserved: 0,
            positions: std::ptr::null_mut(),
            positions_capacity: 0,
            uvs: std::ptr::null_mut(),
            uvs_capacity: 0,
            indices: std::ptr::null_mut(),
            indices_capacity: 0,
            vertex_segments: std::ptr::null_mut(),
            vertex_segments_capacity: 0,
        }
    }
}

/// Copies one `PlumageFeatherInstance` per feather into `buf` (`capacity`
/// elements), in the order of `plumage_system_feathers`. `*out_len`
/// receives the feather count; a NULL or too small `buf` gives
/// PLUMAGE_STATUS_BUFFER_TOO_SMALL and writes nothing else.
///
/// # Safety
/// `sys` is NULL or a live handle from `plumage_system_create`; other threads
/// may only make read-only (`const`) calls on it during the call. `buf` is NULL
/// or holds `capacity` writable elements; `out_len` is NULL or points to a
/// writable `size_t`.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn plumage_system_feather_instances(
    sys: *const PlumageSystem,
    buf: *mut PlumageFeatherInstance,
    capacity: usize,
    out_len: *mut usize,
) -> PlumageStatus {
    with_system_ref(sys, |system| {
        let records: Vec<PlumageFeatherInstance> =
            system.feather_instances().iter().map(PlumageFeatherInstance::from).collect();
        copy_out(&records, buf, capacity, out_len)
    })
}

/// Fills `card` with NULL buffers, zero capacities and counts, and sets
/// `struct_size`. NULL is ignored.
///
/// # Safety
/// `card` is NULL or points to writable memory for one `PlumageFeatherTemplate`.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn plumage_feather_template_init(card: *mut PlumageFeatherTemplate) {
    if card.is_null() {
        return;
    }
    // SAFETY: non-NULL, points to a PlumageFeatherTemplate (contract).
    unsafe { card.write(PlumageFeatherTemplate::empty()) };
}

/// Copies out the template card of the system's feathers: vertices in the
/// feather's own frame for unit length and width, UVs, triangles and the
/// shaft segment of each vertex (see `PlumageFeatherTemplate`, and
/// `PlumageFeatherInstance` for how a record places it). It never changes
/// after create. The counts are always written back; if a non-NULL buffer
/// is too small the call returns PLUMAGE_STATUS_BUFFER_TOO_SMALL (naming
/// it) and writes no buffer.
///
/// # Safety
/// `sys` is NULL or a live handle from `plumage_system_create`; other threads
/// may only make read-only (`const`) calls on it during the call. `card`
/// is NULL or points to a `PlumageFeatherTemplate` whose `struct_size` bytes
/// are readable and writable and whose non-NULL buffers hold their stated
/// capacities of writable elements.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn plumage_system_feather_template(
    sys: *const PlumageSystem,
    card: *mut PlumageFeatherTemplate,
) -> PlumageStatus {
    with_system_ref(sys, |system| {
        if card.is_null() {
            return Err(Failure::null("card"));
        }
        let size = std::mem::size_of::<PlumageFeatherTemplate>();
        // SAFETY: non-NULL, caller struct of struct_size bytes (contract).
        let mut io = unsafe { read_versioned(card, size, PlumageFeatherTemplate::empty(), "PlumageFeatherTemplate") }?;
        let template = system.feather_template();
        io.segments = template.segments as u32;
        io.vertex_count = template.vertex_count() as u32;
        io.triangle_count = template.triangles.len() as u32;
        io.vane_split = template.vane_split;
        // SAFETY: as above; only the counts change.
        unsafe { write_versioned(card, size, io, "PlumageFeatherTemplate") }?;
        let buffers = CallerBuffers {
            name: "PlumageFeatherTemplate",
            floats: [
                ("positions", io.positions, io.positions_capacity, template.positions.as_flattened().to_vec()),
                ("uvs", io.uvs, io.uvs_capacity, template.uvs.as_flattened().to_vec()),
            ],
            indices: [
                ("indices", io.indices, io.indices_capacity, template.triangles.as_flattened().to_vec()),
                ("vertex_segments", io.vertex_segments, io.vertex_segments_capacity, template.vertex_segments),
            ],
            bytes: [],
        };
        buffers.check()?;
        // SAFETY: every non-NULL buffer holds its capacity (contract), checked above to be enough.
        unsafe { buffers.write() };
        Ok(())
    })
}

/// Copies the indices of the feathers whose record (and triangles) the
/// last create, step, evaluate, load or seek may have changed, increasing,
/// into `indices` (`capacity` elements); `*out_len` receives their count.
/// Every feather not listed is, bit for bit, as the call before left it:
/// its `PlumageFeatherInstance`, its triangles and vertices in
/// `plumage_system_feather_triangles` and `plumage_system_feather_geometry`,
/// and every field of its `PlumageFeather` but `order_index` (the order may
/// change around a feather that stays put). So an engine re-uploads only
/// the listed records. A step or
/// an evaluate lists the feathers whose root moved or turned (the skin
/// under it moved) or whose pose changed; after a create, a load, or a
/// seek that loaded a checkpoint, every feather is listed and `*out_all`
/// is 1 (otherwise 0). A refused or interrupted call leaves the list as it
/// was. `out_all` may be NULL; it is written only when the call returns
/// PLUMAGE_STATUS_OK. A NULL or too small `indices` (with a non-empty
/// list) gives PLUMAGE_STATUS_BUFFER_TOO_SMALL and writes nothing else.
///
/// # Safety
/// `sys` is NULL or a live handle from `plumage_system_create`; other threads
/// may only make read-only (`const`) calls on it during the call. `indices`
/// is NULL or holds `capacity` writable elements; `out_len` is NULL or
/// points to a writable `size_t`; `out_all` is NULL or points to a writable
/// `uint32_t`.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn plumage_system_changed_feathers(
    sys: *const PlumageSystem,
    indices: *mut u32,
    capacity: usize,
    out_len: *mut usize,
    out_all: *mut u32,
) -> PlumageStatus {
    with_system_ref(sys, |system| {
        let changed = system.changed_feathers();
        copy_out(changed.indices, indices, capacity, out_len)?;
        if !out_all.is_null() {
            // SAFETY: non-NULL, points to a uint32_t (contract).
            unsafe { *out_all = u32::from(changed.all) };
        }
        Ok(())
    })
}
