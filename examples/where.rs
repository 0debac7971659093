#[path = "../tests/common/mod.rs"]
mod common;
use plumage::{Config, MeshInput, System};
fn main() {
    let shape = common::gltf_mesh::load_model("Flamingo.glb").unwrap();
    let cfg = Config { target_feathers: 2000, threads: 2, flow_axis: glam::Vec3::NEG_Z, ..Config::default() };
    let sys = System::new(&cfg, &MeshInput::new(&shape.positions, &shape.indices)).unwrap();
    // histogram of pitch by height band (y) and by z band
    let mut bands = std::collections::BTreeMap::new();
    for f in sys.feathers() {
        let key = ((f.root[1] / 10.0).floor() as i32, (f.root[2] / 25.0).floor() as i32);
        let e = bands.entry(key).or_insert((0usize, 0.0f32, 0usize, 0.0f32));
        e.0 += 1;
        e.1 += f.pitch.to_degrees();
        if f.pitch > 1.09 {
            e.2 += 1;
        }
        e.3 = e.3.max(f.length);
    }
    for ((y, z), (n, p, c, l)) in bands {
        println!(
            "y {:>4} z {:>4}: n {:>4} mean pitch {:>6.1} clamped {:>4} len {:.1}",
            y * 10,
            z * 25,
            n,
            p / n as f32,
            c,
            l
        );
    }
}
