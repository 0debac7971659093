//! Frame cost of the three modes on the flamingo's flying clip (30 fps,
//! about 2000 feathers, one thread): `flamingo_clip/<mode>` steps one frame
//! per iteration, through the clip and round again. Compare the modes of
//! one run only (the machine may be shared); the frame count per mode, the
//! adjusted feathers per frame and the ratios of the three means are
//! printed at the end. Skipped when the model is not available (see
//! `tests/common/gltf_mesh.rs` for where it is looked for).

#[path = "../tests/common/mod.rs"]
mod common;

use criterion::{Criterion, criterion_group, criterion_main};
use plumage::{Config, MeshInput, Mode, System};
use std::cell::Cell;
use std::time::Duration;

fn benches(c: &mut Criterion) {
    let Some((rest, frames)) = common::gltf_mesh::morph_clip("Flamingo.glb", 30.0) else { return };
    let mut group = c.benchmark_group("flamingo_clip");
    let mut summary = Vec::new();
    for mode in [Mode::Legacy, Mode::Incremental, Mode::Rebuild] {
        let cfg = Config { mode, target_feathers: 2000, threads: 1, flow_axis: glam::Vec3::NEG_Z, ..Config::default() };
        let mut sys = System::new(&cfg, &MeshInput::new(&rest.positions, &rest.indices)).expect("create");
        let next = Cell::new(0usize);
        let (seconds, adjusted, steps) = (Cell::new(0.0f64), Cell::new(0usize), Cell::new(0usize));
        group.bench_function(format!("{mode:?}").to_lowercase(), |b| {
            b.iter(|| {
                let k = next.get();
                next.set((k + 1) % frames.len());
                sys.step(&frames[k]).expect("step");
                let report = sys.frame_report().expect("report");
                seconds.set(seconds.get() + report.step_seconds);
                adjusted.set(adjusted.get() + report.adjusted);
                steps.set(steps.get() + 1);
            })
        });
        let n = steps.get().max(1) as f64;
        summary.push((mode, seconds.get() / n, adjusted.get() as f64 / n, sys.feather_count()));
    }
    group.finish();
    for &(mode, seconds, adjusted, feathers) in &summary {
        println!("{mode:?}: {feathers} feathers, mean step {:.2} ms, adjusted {adjusted:.1} per frame", seconds * 1e3);
    }
    let mean = |m: Mode| summary.iter().find(|s| s.0 == m).map_or(f64::NAN, |s| s.1);
    println!(
        "incremental / rebuild {:.3}, incremental / legacy {:.3} (library step seconds of this run)",
        mean(Mode::Incremental) / mean(Mode::Rebuild),
        mean(Mode::Incremental) / mean(Mode::Legacy)
    );
}

criterion_group! {
    name = animation;
    config = Criterion::default().sample_size(10).warm_up_time(Duration::from_millis(500)).measurement_time(Duration::from_secs(3));
    targets = benches
}
criterion_main!(animation);
