//! Status codes of the C ABI. Numbers are never reused or renumbered.

/// What every call that can fail returns: `PLUMAGE_STATUS_OK` (0) or one
/// of the other `PLUMAGE_STATUS_*` values (`plumage_status_name` names it).
pub type PlumageStatus = u32;

/// The call succeeded.
pub const PLUMAGE_STATUS_OK: u32 = 0;
/// A required pointer argument was NULL.
pub const PLUMAGE_STATUS_NULL_POINTER: u32 = 1;
/// A parameter is outside its documented range.
pub const PLUMAGE_STATUS_INVALID_ARGUMENT: u32 = 2;
/// The mesh's structure cannot be used (array lengths that do not match, ...).
pub const PLUMAGE_STATUS_INVALID_MESH: u32 = 3;
/// A frame's vertex count differs from the rest mesh's.
pub const PLUMAGE_STATUS_VERTEX_COUNT_MISMATCH: u32 = 4;
/// The output buffer is NULL or too small; `*out_len` holds the needed length.
pub const PLUMAGE_STATUS_BUFFER_TOO_SMALL: u32 = 5;
/// The progress callback asked to stop; the system is as it was before the call.
pub const PLUMAGE_STATUS_INTERRUPTED: u32 = 6;
/// An earlier call panicked inside the library; only destroy is allowed.
pub const PLUMAGE_STATUS_POISONED: u32 = 7;
/// This call panicked inside the library; the system is now poisoned.
pub const PLUMAGE_STATUS_PANIC: u32 = 8;
/// A position or parameter is NaN or infinite.
pub const PLUMAGE_STATUS_NON_FINITE: u32 = 9;
/// `struct_size` is smaller than the first published layout of the struct.
pub const PLUMAGE_STATUS_UNSUPPORTED_STRUCT_SIZE: u32 = 10;
/// A triangle index is not below the vertex count.
pub const PLUMAGE_STATUS_INDEX_OUT_OF_RANGE: u32 = 11;
/// The mesh has no vertices or no triangles.
pub const PLUMAGE_STATUS_EMPTY_MESH: u32 = 12;
/// Every triangle of the mesh is degenerate.
pub const PLUMAGE_STATUS_DEGENERATE_MESH: u32 = 13;
/// A count is so large that its byte size overflows.
pub const PLUMAGE_STATUS_SIZE_OVERFLOW: u32 = 14;
/// A saved state blob is truncated, corrupt, foreign or from another system.
pub const PLUMAGE_STATUS_INVALID_STATE: u32 = 15;
/// The requested figure has not been computed for this system (yet).
pub const PLUMAGE_STATUS_NOT_AVAILABLE: u32 = 16;
/// The request is outside the documented limits (feather count, estimated
/// root count of a spacing, coordinate magnitude); refused up front, before
/// anything large is allocated. The message names the limit.
pub const PLUMAGE_STATUS_LIMIT_EXCEEDED: u32 = 17;
/// Another call is running on the same system (from another thread, or
/// from the progress callback of the running call): a system admits one
/// mutating call (or destroy) at a time and no read-only call during one.
/// Nothing was done; the call may be retried once the other has returned.
pub const PLUMAGE_STATUS_BUSY: u32 = 18;

/// Every status with its name, in numeric order.
pub(crate) const STATUS_NAMES: &[(u32, &std::ffi::CStr)] = &[
    (PLUMAGE_STATUS_OK, c"OK"),
    (PLUMAGE_STATUS_NULL_POINTER, c"NULL_POINTER"),
    (PLUMAGE_STATUS_INVALID_ARGUMENT, c"INVALID_ARGUMENT"),
    (PLUMAGE_STATUS_INVALID_MESH, c"INVALID_MESH"),
    (PLUMAGE_STATUS_VERTEX_COUNT_MISMATCH, c"VERTEX_COUNT_MISMATCH"),
    (PLUMAGE_STATUS_BUFFER_TOO_SMALL, c"BUFFER_TOO_SMALL"),
    (PLUMAGE_STATUS_INTERRUPTED, c"INTERRUPTED"),
    (PLUMAGE_STATUS_POISONED, c"POISONED"),
    (PLUMAGE_STATUS_PANIC, c"PANIC"),
    (PLUMAGE_STATUS_NON_FINITE, c"NON_FINITE"),
    (PLUMAGE_STATUS_UNSUPPORTED_STRUCT_SIZE, c"UNSUPPORTED_STRUCT_SIZE"),
    (PLUMAGE_STATUS_INDEX_OUT_OF_RANGE, c"INDEX_OUT_OF_RANGE"),
    (PLUMAGE_STATUS_EMPTY_MESH, c"EMPTY_MESH"),
    (PLUMAGE_STATUS_DEGENERATE_MESH, c"DEGENERATE_MESH"),
    (PLUMAGE_STATUS_SIZE_OVERFLOW, c"SIZE_OVERFLOW"),
    (PLUMAGE_STATUS_INVALID_STATE, c"INVALID_STATE"),
    (PLUMAGE_STATUS_NOT_AVAILABLE, c"NOT_AVAILABLE"),
    (PLUMAGE_STATUS_LIMIT_EXCEEDED, c"LIMIT_EXCEEDED"),
    (PLUMAGE_STATUS_BUSY, c"BUSY"),
];

/// The status a safe-API error kind maps to.
pub(crate) fn status_of(kind: crate::ErrorKind) -> u32 {
    use crate::ErrorKind as K;
    match kind {
        K::InvalidArgument => PLUMAGE_STATUS_INVALID_ARGUMENT,
        K::InvalidMesh => PLUMAGE_STATUS_INVALID_MESH,
        K::VertexCountMismatch => PLUMAGE_STATUS_VERTEX_COUNT_MISMATCH,
        K::NonFinite => PLUMAGE_STATUS_NON_FINITE,
        K::IndexOutOfRange => PLUMAGE_STATUS_INDEX_OUT_OF_RANGE,
        K::EmptyMesh => PLUMAGE_STATUS_EMPTY_MESH,
        K::DegenerateMesh => PLUMAGE_STATUS_DEGENERATE_MESH,
        K::SizeOverflow => PLUMAGE_STATUS_SIZE_OVERFLOW,
        K::Interrupted => PLUMAGE_STATUS_INTERRUPTED,
        K::InvalidState => PLUMAGE_STATUS_INVALID_STATE,
        K::LimitExceeded => PLUMAGE_STATUS_LIMIT_EXCEEDED,
    }
}
