//! Plumage dresses animated triangle meshes with feathers or fish scales and
//! keeps them collision-free from frame to frame (Liu et al., "Incremental
//! collision-free feathering for animated surfaces", The Visual Computer,
//! 2017). The safe Rust API is [`System`]; C and C++ hosts use the C ABI in
//! [`ffi`] through `include/plumage.h`.
//!
//! Where things live, and which module may import which: `ARCHITECTURE.md`
//! at the repository root (`mesh`, `surface`, `field`, `sampling` prepare a
//! coat; `frame` runs the phases of a frame on the `coat`; `system` is the
//! safe API; `ffi` every `extern "C"` function, nothing else).

pub mod adjustment;
pub mod animation;
pub mod body;
pub mod coat;
pub mod config;
pub mod csr;
pub mod error;
pub mod feather;
pub mod ffi;
pub mod field;
pub mod frame;
pub mod geometry;
pub mod interior;
pub mod intersect;
pub mod limits;
pub mod memory;
pub mod mesh;
pub mod ordering;
pub mod progress;
pub mod rng;
pub mod roots;
pub mod sampling;
pub mod skeleton;
pub mod snapshot;
pub(crate) mod spacing;
pub mod stats;
pub mod surface;
pub mod system;
pub mod triangle_grid;
pub mod validation;
pub mod workers;

pub use config::{Config, Mode, Preset, SamplerKind};
pub use error::{Error, ErrorKind, Result};
pub use mesh::MeshInput;
pub use skeleton::SkeletonInput;
pub use system::System;
