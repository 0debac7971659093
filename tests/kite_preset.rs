//! The `kite` preset is the paper's rigid feather: exactly the coat that
//! was the library's default before the bent feather took its place
//! (issue #30). Its feathers on the shared models, created and stepped
//! through a few frames, hash to the values recorded from that default
//! (commit 7e363d6, `Config::default()`), at one and two threads.

mod common;

use plumage::{Config, MeshInput, Preset, System};

/// FNV-1a over the bit patterns of every feather vertex coordinate.
fn hash_triangles(sys: &System, hash: &mut u64) {
    for v in sys.feather_triangles() {
        for c in v {
            for b in c.to_bits().to_le_bytes() {
                *hash ^= u64::from(b);
                *hash = hash.wrapping_mul(0x0000_0100_0000_01b3);
            }
        }
    }
}

/// The rest positions moved by a slow travelling wave of amplitude `a`
/// (a fraction of the model's extent), as a deformation to step through.
fn waved(positions: &[f32], a: f32) -> Vec<f32> {
    let (lo, hi) = positions.chunks(3).fold((f32::MAX, f32::MIN), |(lo, hi), p| (lo.min(p[0]), hi.max(p[0])));
    let extent = (hi - lo).max(f32::MIN_POSITIVE);
    let mut out = positions.to_vec();
    for p in out.chunks_mut(3) {
        let u = (p[0] - lo) / extent;
        p[1] += a * extent * (std::f32::consts::TAU * u).sin();
    }
    out
}

/// The coat's hash: created with `cfg`, then stepped through `frames`.
fn coat_hash(cfg: &Config, positions: &[f32], indices: &[u32], frames: &[Vec<f32>]) -> u64 {
    let mut sys = System::new(cfg, &MeshInput::new(positions, indices)).expect("create");
    let mut hash = 0xcbf2_9ce4_8422_2325u64;
    hash_triangles(&sys, &mut hash);
    for f in frames {
        sys.step(f).expect("step");
        hash_triangles(&sys, &mut hash);
    }
    hash
}

/// The recorded hashes: (model, hash).
const RECORDED: [(&str, u64); 3] =
    [("Flamingo.glb", 0x1eeb_8ce7_2d9d_028a), ("Fox.glb", 0x408e_82e3_c3c4_8c91), ("bird.glb", 0x9e2a_d03c_219d_2a70)];

#[test]
fn the_kite_preset_is_the_former_default_coat() {
    let print = std::env::var_os("PLUMAGE_PRINT_KITE_HASHES").is_some();
    let kite = Config::preset(Preset::Kite);
    assert_ne!(kite, Config::default(), "the default is no longer the kite");
    for (file, recorded) in RECORDED {
        let Some(shape) = common::gltf_mesh::load_model(file) else { continue };
        let frames = [waved(&shape.positions, 0.002), waved(&shape.positions, 0.005), waved(&shape.positions, 0.004)];
        for threads in [1, 2] {
            let cfg = Config { target_feathers: 600, seed: 3, threads, ..kite.clone() };
            let hash = coat_hash(&cfg, &shape.positions, &shape.indices, &frames);
            if print {
                println!("{file} threads {threads}: 0x{hash:016x}");
                continue;
            }
            assert_eq!(hash, recorded, "{file}, {threads} threads: the kite coat differs from the former default's");
        }
    }
}
