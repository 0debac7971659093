//! What a system holds in memory: the heap bytes of its parts, counted
//! from the capacities of the containers that hold them ([`HeapSize`]),
//! and the limit a host can set on them.
//!
//! Every type that owns heap memory implements [`HeapSize`] beside its
//! definition with [`heap_size_of_fields!`], whose pattern names every
//! field: a field added later does not compile until it is counted (or
//! said to hold no heap).

use std::collections::{BTreeMap, BinaryHeap};

/// Heap bytes owned by a value (not counting the value itself).
pub trait HeapSize {
    /// Bytes allocated on the heap for this value's containers.
    fn heap_bytes(&self) -> usize;
}

/// A vector of plain values: its capacity.
impl<T: Copy> HeapSize for Vec<T> {
    fn heap_bytes(&self) -> usize {
        self.capacity() * std::mem::size_of::<T>()
    }
}

/// A vector of values that own heap memory themselves (implemented per
/// element type: a blanket impl would overlap the one for plain values).
pub(crate) fn nested_heap_bytes<T: HeapSize>(v: &Vec<T>) -> usize {
    v.capacity() * std::mem::size_of::<T>() + v.iter().map(HeapSize::heap_bytes).sum::<usize>()
}

impl<T: Copy> HeapSize for BinaryHeap<T> {
    fn heap_bytes(&self) -> usize {
        self.capacity() * std::mem::size_of::<T>()
    }
}

/// A B-tree's nodes hold up to 11 entries; counted as one node's overhead
/// (two child pointers and a length) per entry, the blobs at their capacity.
impl HeapSize for BTreeMap<u64, Vec<u8>> {
    fn heap_bytes(&self) -> usize {
        let per_entry = std::mem::size_of::<u64>() + std::mem::size_of::<Vec<u8>>() + 2 * std::mem::size_of::<usize>();
        self.values().map(|blob| per_entry + blob.capacity()).sum()
    }
}

/// Implements [`HeapSize`] for a struct as the sum over `count`ed fields;
/// the fields after `plain` hold no heap of their own. Every field must be
/// named in one list or the other.
macro_rules! heap_size_of_fields {
    ($ty:ty { $($(#[$attr:meta])* $field:ident),* $(,)? } $(plain { $($(#[$pattr:meta])* $skip:ident),* $(,)? })?) => {
        impl $crate::memory::HeapSize for $ty {
            fn heap_bytes(&self) -> usize {
                let Self { $($(#[$attr])* $field,)* $($($(#[$pattr])* $skip: _,)*)? } = self;
                #[allow(unused_mut)]
                let mut bytes = 0;
                $($(#[$attr])* {
                    bytes += $crate::memory::HeapSize::heap_bytes($field);
                })*
                bytes
            }
        }
    };
}
pub(crate) use heap_size_of_fields;

/// Implements `Clone` for a struct field by field, with a `clone_from`
/// that clones each field from the source's in place: a value cloned into
/// again and again (a backup taken every frame) keeps its buffers instead
/// of allocating and freeing them each time. The struct literal names
/// every field, so a field added later does not compile until it is
/// listed.
macro_rules! clone_by_fields {
    ($ty:ident $(<$t:ident>)? { $($field:ident),* $(,)? }) => {
        impl$(<$t: Clone>)? Clone for $ty$(<$t>)? {
            fn clone(&self) -> Self {
                Self { $($field: self.$field.clone()),* }
            }

            fn clone_from(&mut self, source: &Self) {
                $(self.$field.clone_from(&source.$field);)*
            }
        }
    };
}
pub(crate) use clone_by_fields;

/// The refusal of a system that would hold `bytes` under `limit`.
pub(crate) fn over_limit(what: &str, bytes: usize, limit: usize) -> crate::error::Error {
    crate::error::Error::new(
        crate::error::ErrorKind::LimitExceeded,
        format!("{what} {bytes} bytes, more than config.memory_limit ({limit} bytes)"),
    )
}

/// A system's memory, in bytes, by part. Scratch space is what a step
/// works in and keeps between frames so as not to allocate again; it grows
/// with the feathers, never with the number of frames.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct MemoryUse {
    /// The welded mesh, its surface connectivity, the skin's spatial index,
    /// the roots' rest binding and the current vertex positions.
    pub mesh: usize,
    /// The feathers' frames, poses, triangles and records at the current
    /// pose, the previous frame's poses and root frames (and the poses
    /// before those, to undo a call with), and the list of feathers the
    /// last call changed.
    pub coat: usize,
    /// The neighbourhoods (k-nearest and obstacle rows, their tree) and the
    /// priority order between neighbours.
    pub neighbourhoods: usize,
    /// Saved states kept for seeking (checkpoints).
    pub history: usize,
    /// Per-frame working memory kept between calls, with the copy of the
    /// coat a call that may fail keeps to restore it.
    pub scratch: usize,
}

impl MemoryUse {
    /// Every part together.
    pub fn total(&self) -> usize {
        self.mesh + self.coat + self.neighbourhoods + self.history + self.scratch
    }
}
