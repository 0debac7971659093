// scratch: quick figures (not committed)
#[path = "../tests/common/mod.rs"]
mod common;
use plumage::{Config, MeshInput, System};
use std::time::Instant;

fn main() {
    let file = std::env::args().nth(1).unwrap_or("Flamingo.glb".into());
    let target: usize = std::env::args().nth(2).map(|s| s.parse().unwrap()).unwrap_or(2000);
    let shape = if file == "sphere" { sphere(40, 80, 10.0) } else { common::gltf_mesh::load_model(&file).unwrap() };
    bbox(&shape.positions);
    let flow: Vec<f32> =
        std::env::args().nth(3).unwrap_or("1,0,0".into()).split(',').map(|x| x.parse().unwrap()).collect();
    let steps: usize = std::env::args().nth(4).map(|s| s.parse().unwrap()).unwrap_or(0);
    let cfg = Config {
        target_feathers: target,
        threads: 1,
        flow_axis: glam::Vec3::new(flow[0], flow[1], flow[2]),
        feather_length: std::env::var("LEN").ok().and_then(|v| v.parse().ok()).unwrap_or(0.0),
        feather_width: std::env::var("WID").ok().and_then(|v| v.parse().ok()).unwrap_or(0.0),
        ..Config::default()
    };
    let t = Instant::now();
    let mut sys = System::new(&cfg, &MeshInput::new(&shape.positions, &shape.indices)).unwrap();
    println!("create {:.3}s feathers {}", t.elapsed().as_secs_f64(), sys.feather_count());
    println!("{:?}\n{:?}\n{:?}", sys.sampling_report(), sys.ordering_report(), sys.frame_report());
    let t = Instant::now();
    println!("{:?} ({:.3}s)", sys.validate(), t.elapsed().as_secs_f64());
    // bend: a wave
    for k in 1..=steps {
        let p: Vec<f32> = shape
            .positions
            .chunks(3)
            .flat_map(|v| {
                let a = 0.05 * k as f32 * (v[0] * 0.1).sin();
                [v[0], v[1] + a * v[2], v[2]]
            })
            .collect();
        sys.step(&p).unwrap();
        println!("step {k}: {:?}", sys.frame_report());
        println!("   {:?}", sys.validate());
    }
}
#[allow(dead_code)]
fn bbox(p: &[f32]) {
    let mut lo = [f32::MAX; 3];
    let mut hi = [f32::MIN; 3];
    for v in p.chunks(3) {
        for k in 0..3 {
            lo[k] = lo[k].min(v[k]);
            hi[k] = hi[k].max(v[k]);
        }
    }
    println!("bbox {:?} {:?}", lo, hi);
}

fn sphere(rings: usize, segs: usize, r: f32) -> common::shapes::Shape {
    let mut s = common::shapes::Shape::default();
    s.positions.extend_from_slice(&[0.0, 0.0, r]);
    for i in 1..rings {
        let th = std::f32::consts::PI * i as f32 / rings as f32;
        for j in 0..segs {
            let ph = std::f32::consts::TAU * j as f32 / segs as f32;
            s.positions.extend_from_slice(&[r * th.sin() * ph.cos(), r * th.sin() * ph.sin(), r * th.cos()]);
        }
    }
    s.positions.extend_from_slice(&[0.0, 0.0, -r]);
    let ring = |i: usize, j: usize| (1 + (i - 1) * segs + j % segs) as u32;
    let south = (s.positions.len() / 3 - 1) as u32;
    for j in 0..segs {
        s.indices.extend_from_slice(&[0, ring(1, j), ring(1, j + 1)]);
    }
    for i in 1..rings - 1 {
        for j in 0..segs {
            s.indices.extend_from_slice(&[
                ring(i, j),
                ring(i + 1, j),
                ring(i + 1, j + 1),
                ring(i, j),
                ring(i + 1, j + 1),
                ring(i, j + 1),
            ]);
        }
    }
    for j in 0..segs {
        s.indices.extend_from_slice(&[ring(rings - 1, j), south, ring(rings - 1, j + 1)]);
    }
    s
}
