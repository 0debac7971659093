//! The C ABI's call conventions (DESIGN §7) as helpers every entry point
//! shares: a refused call ([`Failure`], its status and message), copy-out
//! under (buffer, capacity, *out_len), and reading and writing structs that
//! start with `uint32_t struct_size`.

use super::status::*;

/// A refused call: its status and message.
#[derive(Debug)]
pub(crate) struct Failure {
    pub status: u32,
    pub message: String,
}

impl Failure {
    pub fn new(status: u32, message: impl Into<String>) -> Self {
        Self { status, message: message.into() }
    }

    pub fn null(what: &str) -> Self {
        Self::new(PLUMAGE_STATUS_NULL_POINTER, format!("{what} is NULL"))
    }

    /// Figures asked for before a system has feathers.
    pub fn not_available(what: &str) -> Self {
        Self::new(PLUMAGE_STATUS_NOT_AVAILABLE, format!("{what} are not available: this system has no feathers yet"))
    }
}

impl From<crate::Error> for Failure {
    fn from(e: crate::Error) -> Self {
        Self::new(status_of(e.kind()), e.message())
    }
}

pub(crate) type CallResult = Result<(), Failure>;

/// Copies `items` out under the (buffer, capacity, out_len) convention:
/// `*out_len` always receives the needed length; a NULL or too-small buffer
/// gives BUFFER_TOO_SMALL and writes nothing.
pub(crate) fn copy_out<T: Copy>(items: &[T], buf: *mut T, capacity: usize, out_len: *mut usize) -> CallResult {
    if out_len.is_null() {
        return Err(Failure::null("out_len"));
    }
    // SAFETY: out_len is non-NULL and points to a size_t (contract).
    unsafe { *out_len = items.len() };
    if items.is_empty() {
        return Ok(());
    }
    if buf.is_null() || capacity < items.len() {
        return Err(Failure::new(
            PLUMAGE_STATUS_BUFFER_TOO_SMALL,
            format!(
                "buffer holds {} elements but {} are needed",
                if buf.is_null() { 0 } else { capacity },
                items.len()
            ),
        ));
    }
    // SAFETY: buf holds at least `capacity >= items.len()` elements (contract).
    unsafe { std::ptr::copy_nonoverlapping(items.as_ptr(), buf, items.len()) };
    Ok(())
}

/// Reads a struct that starts with `uint32_t struct_size`: refuses sizes
/// below `min_size`, copies what both sides know over `defaults` (a larger
/// caller struct is accepted; unknown trailing fields are ignored).
///
/// # Safety
/// `ptr` is non-NULL and points to at least `struct_size` readable bytes.
pub(crate) unsafe fn read_versioned<T: Copy>(
    ptr: *const T,
    min_size: usize,
    defaults: T,
    name: &str,
) -> Result<T, Failure> {
    // SAFETY: every versioned struct starts with a u32 struct_size.
    let declared = unsafe { std::ptr::read_unaligned(ptr as *const u32) } as usize;
    if declared < min_size {
        return Err(Failure::new(
            PLUMAGE_STATUS_UNSUPPORTED_STRUCT_SIZE,
            format!(
                "{name}.struct_size is {declared} but the first published layout has {min_size} bytes; call the init function first"
            ),
        ));
    }
    let mut out = defaults;
    let n = declared.min(std::mem::size_of::<T>());
    // SAFETY: the caller's struct has `declared >= n` bytes; `out` has size_of::<T>() >= n.
    unsafe { std::ptr::copy_nonoverlapping(ptr as *const u8, &mut out as *mut T as *mut u8, n) };
    Ok(out)
}

/// Writes `value` into a caller struct that starts with `uint32_t
/// struct_size` (set by the caller to its `sizeof`): refuses sizes below
/// `min_size`, writes only the bytes both sides know, and sets
/// `struct_size` to the number of bytes written.
///
/// # Safety
/// `ptr` is non-NULL and points to at least `struct_size` writable bytes.
pub(crate) unsafe fn write_versioned<T: Copy>(ptr: *mut T, min_size: usize, value: T, name: &str) -> CallResult {
    // SAFETY: every versioned struct starts with a u32 struct_size.
    let declared = unsafe { std::ptr::read_unaligned(ptr as *const u32) } as usize;
    if declared < min_size {
        return Err(Failure::new(
            PLUMAGE_STATUS_UNSUPPORTED_STRUCT_SIZE,
            format!("{name}.struct_size is {declared}; set it to sizeof({name}) (at least {min_size})"),
        ));
    }
    let n = declared.min(std::mem::size_of::<T>());
    // SAFETY: both sides hold at least n bytes; struct_size is the first field.
    unsafe {
        std::ptr::copy_nonoverlapping(&value as *const T as *const u8, ptr as *mut u8, n);
        std::ptr::write_unaligned(ptr as *mut u32, n as u32);
    }
    Ok(())
}

/// Writes the struct `value` computes into the caller's `out` (see
/// [`write_versioned`]), refusing a NULL `out` before computing anything:
/// the body of every call that fills one caller struct.
///
/// # Safety
/// `out` is NULL or points to at least `struct_size` writable bytes.
pub(crate) unsafe fn write_struct<T: Copy>(
    out: *mut T,
    min_size: usize,
    name: &str,
    value: impl FnOnce() -> Result<T, Failure>,
) -> CallResult {
    if out.is_null() {
        return Err(Failure::null("out"));
    }
    let value = value()?;
    // SAFETY: non-NULL, caller struct of struct_size bytes (contract).
    unsafe { write_versioned(out, min_size, value, name) }
}
