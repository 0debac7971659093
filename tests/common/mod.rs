//! Helpers shared by the integration tests: procedural meshes and the glTF
//! test-model loader. Each test binary uses only some of them.
#![allow(dead_code)]

pub mod character;
pub mod fuzz;
pub mod gltf_mesh;
pub mod shapes;
