//! The caller's mesh: checking it and welding a glTF-style triangle soup
//! (vertices split along UV and normal seams) into one connected surface.

mod input;
mod weld;

pub use input::{MeshInput, check_frame_positions};
pub use weld::{WeldedMesh, weld};
