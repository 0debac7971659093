#[path = "../tests/common/mod.rs"]
mod common;
use plumage::{Config, MeshInput, System};
fn main() {
    let (rest, frames) = common::gltf_mesh::morph_clip("Flamingo.glb", 30.0).unwrap();
    let cfg = Config { target_feathers: 2000, threads: 2, flow_axis: glam::Vec3::NEG_Z, ..Config::default() };
    let mut sys = System::new(&cfg, &MeshInput::new(&rest.positions, &rest.indices)).unwrap();
    for (k, f) in frames.iter().enumerate().take(12) {
        sys.step(f).unwrap();
        let r = sys.frame_report().unwrap();
        println!(
            "frame {k}: deformed {} seeds {} adjusted {} prio changes {} reorder {:.1} adjust {:.1} step {:.1} ms",
            r.deformed,
            r.seeds,
            r.adjusted,
            r.priority_changes,
            r.reorder_seconds * 1e3,
            r.adjust_seconds * 1e3,
            r.step_seconds * 1e3
        );
    }
}
