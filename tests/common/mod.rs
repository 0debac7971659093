//! Helpers shared by the integration tests: procedural meshes and the glTF
//! test-model loader. Each test binary uses only some of them.
#![allow(dead_code)]

pub mod character;
pub mod counting;
pub mod fuzz;
pub mod gltf_mesh;
pub mod shapes;

/// A wall-clock limit for a guard against runaway work (not a benchmark):
/// `seconds` on an idle machine, stretched by the load per core when the
/// machine is busier than that (the 1-minute load average of
/// `/proc/loadavg`; unchanged where it cannot be read).
pub fn runaway_limit(seconds: f64) -> f64 {
    let load = std::fs::read_to_string("/proc/loadavg")
        .ok()
        .and_then(|s| s.split_whitespace().next().and_then(|x| x.parse::<f64>().ok()))
        .unwrap_or(0.0);
    let cores = std::thread::available_parallelism().map_or(1, |n| n.get()) as f64;
    seconds * (load / cores).max(1.0)
}
