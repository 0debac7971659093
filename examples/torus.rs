use plumage::{Config, MeshInput, System};
fn main() {
    let (big, small, nu, nv) = (10.0f32, 3.0f32, 120usize, 40usize);
    let (mut p, mut hint, mut idx) = (vec![], vec![], vec![]);
    for i in 0..nu {
        let u = std::f32::consts::TAU * i as f32 / nu as f32;
        for j in 0..nv {
            let v = std::f32::consts::TAU * j as f32 / nv as f32;
            let r = big + small * v.cos();
            p.extend_from_slice(&[r * u.cos(), r * u.sin(), small * v.sin()]);
            hint.extend_from_slice(&[-u.sin(), u.cos(), 0.0]);
        }
    }
    for i in 0..nu {
        for j in 0..nv {
            let a = (i * nv + j) as u32;
            let b = (((i + 1) % nu) * nv + j) as u32;
            let c = (((i + 1) % nu) * nv + (j + 1) % nv) as u32;
            let d = (i * nv + (j + 1) % nv) as u32;
            idx.extend_from_slice(&[a, b, c, a, c, d]);
        }
    }
    let target: usize = std::env::args().nth(1).map(|s| s.parse().unwrap()).unwrap_or(4000);
    let cfg = Config { target_feathers: target, threads: 2, ..Config::default() };
    let mut mesh = MeshInput::new(&p, &idx);
    mesh.orientations = Some(&hint);
    let sys = System::new(&cfg, &mesh).unwrap();
    println!("torus {} feathers {:?}", sys.feather_count(), sys.frame_report().map(|r| r.clamped));
    println!("{:?}", sys.validate());
}
