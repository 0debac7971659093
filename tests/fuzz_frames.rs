//! Fuzz target: frames of positions through `plumage_system_step` and
//! `plumage_system_evaluate`. Small systems in every mode get random
//! deformations (affine moves at any scale, noise) with hazards arriving
//! mid-clip: NaN and infinite coordinates, coordinates beyond the limit,
//! a region or the whole mesh collapsed to a point, the mesh flattened,
//! wrong vertex counts. A refused frame must leave the system exactly as it
//! was (saved state and feathers byte-identical); an accepted one must give
//! finite feathers. No call may panic.
//!
//! Short run: `cargo test --release --test fuzz_frames`; long run:
//! `PLUMAGE_FUZZ_CASES=100000 cargo test --release --test fuzz_frames -- --nocapture`.

mod common;

use common::fuzz::{self, Rng, Tally};
use common::shapes::{Shape, cylinder, grid};
use plumage::ffi::*;

fn frame(rng: &mut Rng, rest: &[f32]) -> Vec<f32> {
    let s = if rng.chance(0.2) { rng.log_uniform(-4.0, 4.0) } else { rng.range(0.8, 1.2) };
    let (a, t) = (rng.range(-3.2, 3.2), [rng.range(-2.0, 2.0), rng.range(-2.0, 2.0), rng.range(-2.0, 2.0)]);
    let noise = if rng.chance(0.3) { rng.log_uniform(-6.0, 0.0) } else { 0.0 };
    let (c, sn) = (a.cos(), a.sin());
    let mut out: Vec<f32> = rest
        .chunks(3)
        .flat_map(|p| [s * (c * p[0] - sn * p[1]) + t[0], s * (sn * p[0] + c * p[1]) + t[1], s * p[2] + t[2]])
        .collect();
    out.iter_mut().for_each(|x| *x += noise * (rng.unit() - 0.5));
    let n = out.len() / 3;
    match rng.below(10) {
        0 => {
            let k = rng.below(out.len());
            out[k] = rng.nasty_f32();
        }
        1 => {
            // A region collapsed to one point.
            let (a, len) = (rng.below(n), 1 + rng.below(n));
            let p = [out[3 * a], out[3 * a + 1], out[3 * a + 2]];
            (a..(a + len).min(n)).for_each(|v| out[3 * v..3 * v + 3].copy_from_slice(&p));
        }
        2 => out.iter_mut().for_each(|x| *x = 0.5),
        3 => out.iter_mut().skip(2).step_by(3).for_each(|z| *z = 0.0),
        4 => {
            let k = rng.below(out.len());
            out[k] = 2.0 * PLUMAGE_MAX_COORDINATE;
        }
        _ => {}
    }
    out
}

fn case(rng: &mut Rng, tally: &mut Tally) {
    let shape: Shape = match rng.below(3) {
        0 => cylinder(rng.range(0.3, 1.5), rng.range(0.5, 3.0), 4 + rng.below(16), 1 + rng.below(6)),
        1 => grid(rng.range(0.5, 3.0), rng.range(0.5, 3.0), 1 + rng.below(8), 1 + rng.below(8), 0.0, true),
        _ => {
            let mut s = cylinder(1.0, 2.0, 8, 3);
            s.append(&grid(2.0, 2.0, 3, 3, 1.0, false));
            s
        }
    };
    let mut cfg = fuzz::default_config();
    cfg.threads = 1;
    cfg.seed = rng.u64();
    cfg.mode = rng.below(3) as u32;
    cfg.target_feathers = 10 + rng.below(60) as u32;
    cfg.recompute_neighbourhoods = rng.below(2) as u32;
    let d = fuzz::desc(&shape.positions, &shape.indices);
    let Some(handle) = fuzz::create(tally, Some(&cfg), &d) else { return };
    let sys = handle.0;
    let n = shape.vertex_count();
    for k in 0..1 + rng.below(5) {
        let positions = frame(rng, &shape.positions);
        let count = match rng.below(30) {
            0 => n - 1,
            1 => n + 1,
            _ => n,
        };
        let before = (fuzz::save(sys), fuzz::triangles(sys));
        let evaluate = rng.chance(0.2);
        let st = unsafe {
            if evaluate {
                plumage_system_evaluate(sys, positions.as_ptr(), count.min(n))
            } else {
                plumage_system_step(sys, positions.as_ptr(), count.min(n))
            }
        };
        tally.saw(if evaluate { "evaluate" } else { "step" }, st);
        if st == PLUMAGE_STATUS_OK {
            fuzz::assert_finite(sys, &format!("frame {k}"));
        } else {
            assert!(!fuzz::thread_or(sys).is_empty(), "a refused frame leaves a message");
            assert!(
                before == (fuzz::save(sys), fuzz::triangles(sys)),
                "a refused frame ({}) changed the system",
                fuzz::status_name(st)
            );
        }
    }
    if rng.chance(0.3) {
        let mut v = std::mem::MaybeUninit::<PlumageValidation>::zeroed();
        unsafe { (*v.as_mut_ptr()).struct_size = std::mem::size_of::<PlumageValidation>() as u32 };
        tally.saw("validate", unsafe { plumage_system_validate(sys, v.as_mut_ptr()) });
    }
}

#[test]
fn fuzz_frames() {
    fuzz::run("fuzz_frames", 120, case);
}
