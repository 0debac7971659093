#[path = "../tests/common/mod.rs"]
mod common;
use plumage::adjustment::{AdjustParams, AdjustSteps, HeightField, adjust_feather};
use plumage::body::BodyIndex;
use plumage::coat::Dressing;
use plumage::feather::FeatherPose;
use plumage::{Config, MeshInput};
fn main() {
    let file = std::env::args().nth(1).unwrap_or("Flamingo.glb".into());
    let shape = common::gltf_mesh::load_model(&file).unwrap();
    let cfg = Config { target_feathers: 2000, threads: 1, flow_axis: glam::Vec3::NEG_Z, ..Config::default() };
    let mesh = MeshInput::new(&shape.positions, &shape.indices);
    let welded = plumage::mesh::weld(&mesh).unwrap();
    let surface = plumage::surface::Surface::new(&welded);
    let fields = plumage::field::Fields::new(&welded, &surface, None, None, None, None, &cfg).unwrap();
    let s = plumage::sampling::sample_roots(&welded, &surface, &fields, &cfg).unwrap();
    let mut normals = Vec::new();
    surface.vertex_normals(&welded.positions, &mut normals);
    let mut frames = Vec::new();
    plumage::roots::pose_roots(&s.roots, &welded.positions, &welded.triangles, &normals, &mut frames);
    let shapes = Dressing::shapes_for(&s.roots, &cfg);
    let body = BodyIndex::from_mesh(&welded.positions, &welded.triangles);
    let params = AdjustParams::from_config(&cfg);
    let mut hf = HeightField::new(32, 16);
    let mut pitches: Vec<f32> = Vec::new();
    let mut bands = std::collections::BTreeMap::new();
    let mut clamped = 0;
    let mut dump = String::new();
    for (f, sh) in frames.iter().zip(&shapes) {
        let o = adjust_feather(f, sh, FeatherPose::default(), &[], &body, &params, AdjustSteps::Full, &mut hf);
        pitches.push(o.pose.pitch.to_degrees());
        dump += &format!(
            "{} {} {} {} {} {} {} {}\n",
            f.position.x,
            f.position.y,
            f.position.z,
            f.tangent.x,
            f.tangent.y,
            f.tangent.z,
            o.pose.pitch.to_degrees(),
            o.clamped as u8
        );
        let key = ((f.position.y / 10.0).floor() as i32 * 10, (f.position.z / 25.0).floor() as i32 * 25);
        let e = bands.entry(key).or_insert((0usize, 0usize, 0.0f32));
        e.0 += 1;
        e.1 += o.clamped as usize;
        e.2 += f.tangent.dot(glam::Vec3::NEG_Z);
        clamped += o.clamped as usize;
    }
    for (k, (n, c, d)) in &bands {
        println!("{k:?}: n {n} clamped {c} mean tangent.(-z) {:.2}", d / *n as f32);
    }
    std::fs::write("/tmp/roots.txt", dump).unwrap();
    let mut vd = String::new();
    for p in &welded.positions {
        vd += &format!("{} {} {}\n", p.x, p.y, p.z);
    }
    std::fs::write("/tmp/verts.txt", vd).unwrap();
    pitches.sort_by(|a, b| a.partial_cmp(b).unwrap());
    let n = pitches.len();
    println!(
        "{n} feathers, body only: clamped {clamped}, pitch p10 {:.1} p50 {:.1} p90 {:.1} max {:.1} mean {:.1}",
        pitches[n / 10],
        pitches[n / 2],
        pitches[9 * n / 10],
        pitches[n - 1],
        pitches.iter().sum::<f32>() / n as f32
    );
}
