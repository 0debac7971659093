//! Frame cost of the modes on the flamingo's flying clip (30 fps, about
//! 2000 feathers flowing from the beak, one thread): `flamingo_clip/<mode>`
//! steps one frame per iteration, through the clip and round again. The
//! ratios are then measured side by side: every system steps the same
//! frame in turn, three times through the clip, so that a busy moment of
//! the (shared) machine falls on all of them alike; the mean step time,
//! the adjusted and checked feathers per frame and the ratios are printed
//! at the end. "paper" is incremental with the paper's readjustment rule
//! (`drift_tolerance` = θs, no exact checks). Skipped when the model is not
//! available (see `tests/common/gltf_mesh.rs` for where it is looked for).

#[path = "../tests/common/mod.rs"]
mod common;

use criterion::{Criterion, criterion_group, criterion_main};
use plumage::{Config, MeshInput, Mode, System};
use std::cell::Cell;
use std::time::Duration;

/// Where the Flamingo's beak tip is, in model units.
const BEAK: glam::Vec3 = glam::Vec3::new(0.0, 0.0, 100.4);
/// Rounds through the clip of the side-by-side pass.
const ROUNDS: usize = 3;

fn benches(c: &mut Criterion) {
    let Some((rest, frames)) = common::gltf_mesh::morph_clip("Flamingo.glb", 30.0) else { return };
    let config =
        |mode| Config { mode, target_feathers: 2000, threads: 1, flow_source: Some(BEAK), ..Config::default() };
    let runs = [
        ("legacy", config(Mode::Legacy)),
        ("incremental", config(Mode::Incremental)),
        ("paper", Config { drift_tolerance: 0.05, ..config(Mode::Incremental) }),
        ("rebuild", config(Mode::Rebuild)),
    ];
    let mut systems: Vec<System> = runs
        .iter()
        .map(|(_, cfg)| System::new(cfg, &MeshInput::new(&rest.positions, &rest.indices)).expect("create"))
        .collect();
    let mut group = c.benchmark_group("flamingo_clip");
    for ((name, _), sys) in runs.iter().zip(&mut systems) {
        let next = Cell::new(0usize);
        group.bench_function(*name, |b| {
            b.iter(|| {
                let k = next.get();
                next.set((k + 1) % frames.len());
                sys.step(&frames[k]).expect("step");
            })
        });
    }
    group.finish();

    // Side by side: fresh systems (so that the counts printed do not
    // depend on how many iterations criterion ran), each from the clip's
    // first frame, then every frame stepped by all of them in turn (frame
    // 0, the jump from the rest pose, is left out of the means).
    drop(systems);
    let mut systems: Vec<System> = runs
        .iter()
        .map(|(_, cfg)| System::new(cfg, &MeshInput::new(&rest.positions, &rest.indices)).expect("create"))
        .collect();
    let mut totals = vec![(0.0f64, 0usize, 0usize); runs.len()];
    for sys in &mut systems {
        sys.step(&frames[0]).expect("step");
    }
    let mut steps = 0usize;
    for _ in 0..ROUNDS {
        for frame in &frames[1..] {
            for (sys, total) in systems.iter_mut().zip(&mut totals) {
                sys.step(frame).expect("step");
                let report = sys.frame_report().expect("report");
                total.0 += report.step_seconds;
                total.1 += report.adjusted;
                total.2 += report.verified;
            }
            steps += 1;
        }
    }
    let n = steps.max(1) as f64;
    for ((name, _), (seconds, adjusted, verified)) in runs.iter().zip(&totals) {
        println!(
            "{name}: {} feathers, mean step {:.2} ms, adjusted {:.1} and checked {:.1} per frame",
            systems[0].feather_count(),
            seconds / n * 1e3,
            *adjusted as f64 / n,
            *verified as f64 / n
        );
    }
    let mean = |name: &str| runs.iter().zip(&totals).find(|(r, _)| r.0 == name).map_or(f64::NAN, |(_, t)| t.0 / n);
    println!(
        "side by side over {steps} frames: incremental / rebuild {:.3}, incremental / legacy {:.3}, paper / rebuild {:.3}, paper / legacy {:.3}",
        mean("incremental") / mean("rebuild"),
        mean("incremental") / mean("legacy"),
        mean("paper") / mean("rebuild"),
        mean("paper") / mean("legacy"),
    );
}

criterion_group! {
    name = animation;
    config = Criterion::default().sample_size(10).warm_up_time(Duration::from_millis(500)).measurement_time(Duration::from_secs(3));
    targets = benches
}
criterion_main!(animation);
