//! The feather as geometry, in one place (DESIGN.md §4): its shape, its pose
//! and the posed feather (triangles, shaft, normal, tip), and the mesh a
//! host copies out (vertices, triangles, UVs, normals), and the packed
//! record and template card a renderer instances it from (`record`).
//!
//! Local coordinates follow [`RootFrame`](crate::geometry::RootFrame): x
//! along the tangential orientation `õ`, y along the binormal `b`, z along
//! the normal `n`. Before posing the kite lies in the tangent plane: root
//! (0,0,0), tip (L,0,0), vane corners (s_w·L, ±W/2, 0). It is two
//! triangles, one per vane, sharing the shaft.

mod kind;
mod mesh;
mod pose;
mod record;
mod shape;

pub(crate) use kind::MAX_FEATHER_TYPES;
pub use kind::{FeatherType, FeatherTypeMap};
pub use mesh::{FeatherMesh, FeatherMeshLayout};
pub use pose::{
    FeatherPose, FeatherTriangles, MAX_TRIANGLES, feather_normal, feather_triangles, pose_change, segment_triangles,
    shaft_direction, tip_position, toward, triangles_per_feather,
};
pub use record::{FeatherTemplate, InstanceRecord, RECORD_BEND_RANGE};
pub use shape::{FeatherShape, MAX_JOINTS, MAX_SEGMENTS, MAX_STATIONS, ShaftPlan};
pub(crate) use shape::{LENGTH_PER_SPACING, WIDTH_PER_SPACING};
