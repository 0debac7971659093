//! Bounded-work probe (issue 23): one extreme request, its outcome, time
//! and peak memory. `cargo run --release --example bounded_probe -- CASE`,
//! CASE one of target1e6, target1e7, spacing1e-9, spacing1e-3, huge, big,
//! tiny, tinier, scaleS, offsetO, feathersN (a cylinder of 24 576 triangles
//! dressed with N feathers, one thread), soup1971 (fuzz_create seed 7 case
//! 1971: an explicit spacing of 0.013 on a soup of 56 triangles that all
//! cross one another, 64 499 feathers).

#[path = "../tests/common/shapes.rs"]
#[allow(dead_code)]
mod shapes;

use plumage::{Config, MeshInput, System};
use shapes::{Shape, cylinder};
use std::time::Instant;

fn scaled(shape: &Shape, s: f32) -> Shape {
    Shape { positions: shape.positions.iter().map(|x| x * s).collect(), indices: shape.indices.clone() }
}

/// Peak resident set of this process, KiB (Linux; 0 elsewhere).
fn peak_rss_kib() -> u64 {
    std::fs::read_to_string("/proc/self/status")
        .ok()
        .and_then(|s| {
            s.lines().find(|l| l.starts_with("VmHWM:")).and_then(|l| l.split_whitespace().nth(1)?.parse().ok())
        })
        .unwrap_or(0)
}

/// fuzz_create seed 7 case 1971 (printed by PLUMAGE_FUZZ_DEBUG=1).
const SOUP_POSITIONS: [f32; 36] = [
    -2886185.0,
    -0.6346791,
    -0.22770822,
    -2886186.0,
    -0.09694326,
    0.6965897,
    -2886186.5,
    -0.41981816,
    0.693583,
    -2886186.0,
    0.27782738,
    -0.8242718,
    -2886186.0,
    -0.8965132,
    -0.538146,
    -2886185.8,
    0.7397909,
    -0.8163912,
    -2886184.8,
    0.38776064,
    0.26807594,
    -2886185.5,
    -0.21550035,
    -0.89072347,
    -2886185.0,
    0.35825014,
    -0.1794784,
    -2886184.8,
    -0.79472184,
    -0.14268267,
    -2886186.5,
    0.40108526,
    0.4152521,
    -2886186.0,
    0.0078703165,
    -0.66335297,
];
const SOUP_INDICES: [u32; 168] = [
    8, 9, 5, 4, 4, 11, 4, 0, 7, 2, 10, 10, 7, 3, 6, 3, 11, 5, 7, 5, 11, 1, 8, 9, 8, 5, 8, 8, 10, 4, 7, 7, 0, 9, 7, 8,
    6, 8, 0, 10, 3, 6, 10, 3, 10, 8, 8, 10, 7, 9, 7, 11, 1, 1, 6, 0, 5, 5, 1, 7, 7, 7, 6, 4, 2, 11, 9, 1, 9, 2, 9, 3,
    2, 7, 0, 8, 8, 4, 9, 3, 2, 8, 0, 8, 6, 5, 9, 0, 4, 4, 3, 3, 10, 5, 0, 7, 6, 10, 1, 0, 3, 1, 10, 11, 1, 6, 0, 3, 3,
    0, 9, 11, 8, 6, 11, 6, 2, 8, 5, 9, 5, 1, 8, 5, 10, 0, 11, 3, 7, 5, 5, 2, 3, 4, 2, 2, 3, 9, 4, 7, 3, 11, 4, 7, 1, 2,
    8, 11, 10, 8, 3, 11, 7, 9, 9, 7, 6, 0, 11, 8, 3, 7, 9, 9, 2, 0, 4, 1,
];
const SOUP_SPACING_MAP: [f32; 12] = [
    1.5706763, 0.6114829, 0.9934196, 0.9436588, 1.9363153, 0.2725883, 1.624658, 0.34806213, 0.22247884, 1.2115529,
    0.29609412, 1.8222578,
];

fn main() {
    let case = std::env::args().nth(1).unwrap_or_default();
    let base = cylinder(1.0, 3.0, 24, 12);
    let diag = (3.0f32 * 3.0 + 2.0 * 2.0 + 2.0 * 2.0).sqrt();
    let soup = Shape { positions: SOUP_POSITIONS.to_vec(), indices: SOUP_INDICES.to_vec() };
    let (shape, cfg) = match case.as_str() {
        "target1e7" => (base, Config { target_feathers: 10_000_000, ..Config::default() }),
        "target1e6" => (base, Config { target_feathers: 1_000_000, ..Config::default() }),
        "spacing1e-9" => (base, Config { spacing: 1e-9 * diag, ..Config::default() }),
        "spacing1e-3" => (base, Config { spacing: 1e-3 * diag, ..Config::default() }),
        "huge" => (scaled(&base, 1e30), Config { target_feathers: 2000, ..Config::default() }),
        "big" => (scaled(&base, 1e18), Config { target_feathers: 2000, ..Config::default() }),
        "tiny" => (scaled(&base, 1e-20), Config { target_feathers: 2000, ..Config::default() }),
        "tinier" => (scaled(&base, 1e-35), Config { target_feathers: 2000, ..Config::default() }),
        "soup1971" => (soup, Config { spacing: 0.012977033, target_feathers: 25, threads: 1, ..Config::default() }),
        other if other.starts_with("feathers") => {
            let n: usize = other[8..].parse().expect("feathersN: N a number");
            (cylinder(1.0, 3.0, 128, 96), Config { target_feathers: n, threads: 1, ..Config::default() })
        }
        other if other.starts_with("offset") => {
            let o: f32 = other[6..].parse().expect("offsetO: O a number");
            let mut b = base.clone();
            b.positions.iter_mut().step_by(3).for_each(|x| *x += o);
            (b, Config { target_feathers: 2000, ..Config::default() })
        }
        other if other.starts_with("scale") => {
            let s: f32 = other[5..].parse().expect("scaleS: S a number");
            (scaled(&base, s), Config { target_feathers: 2000, ..Config::default() })
        }
        other => {
            eprintln!("unknown case {other:?} (see the file's notes)");
            std::process::exit(2);
        }
    };
    let mut mesh = MeshInput::new(&shape.positions, &shape.indices);
    if case == "soup1971" {
        mesh.spacing_scale = Some(&SOUP_SPACING_MAP);
    }
    let t = Instant::now();
    let r = System::new(&cfg, &mesh);
    println!(
        "{case}: {:?} in {:.2} s, peak RSS {} KiB",
        r.as_ref().map(|s| s.feather_count()).map_err(|e| e.to_string()),
        t.elapsed().as_secs_f64(),
        peak_rss_kib()
    );
}
