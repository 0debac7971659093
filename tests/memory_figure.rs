//! The memory figure (issue 36): `System::memory` counts what the system
//! holds from its containers' capacities; a counting allocator in this test
//! binary measures the live heap the system really added. They must agree
//! within 10 % on the built-in body at 1 000, 10 000 and 100 000 feathers,
//! after create and after some frames. `Config::memory_limit` is kept:
//! a limit below what create needs is refused, leaving nothing allocated;
//! a step that would pass it is refused and undone.

mod common;

use common::counting::{Counting, LIVE, PEAK};
use common::shapes::{swim_body, swim_pose};
use plumage::progress::{Phase, Progress, ProgressSink};
use plumage::{Config, MeshInput, System};
use std::sync::atomic::Ordering;

#[global_allocator]
static ALLOCATOR: Counting<false> = Counting;

/// A progress sink that never asks to stop.
struct GoOn;

impl ProgressSink for GoOn {
    fn report(&self, _: Phase, _: f32) -> bool {
        true
    }
}

/// One test only in this binary: the live count is process-wide.
/// (The figure and the limit share it, one after the other.)
#[test]
fn the_memory_figure_is_within_a_tenth_of_the_live_heap() {
    let (rings, segments) = (48, 64);
    let body = swim_body(rings, segments);
    let frames: Vec<Vec<f32>> = (1..=4).map(|k| swim_pose(rings, segments, 0.1 * k as f64)).collect();
    let mesh = MeshInput::new(&body.positions, &body.indices);
    // A first system leaves the per-thread scratch of the burial rays and
    // the validation at this mesh's size; it is not part of any system.
    drop(System::new(&Config { target_feathers: 1000, threads: 1, ..Config::default() }, &mesh).unwrap());
    let mut failures = Vec::new();
    for feathers in [1_000, 10_000, 100_000] {
        let cfg = Config { target_feathers: feathers, threads: 1, ..Config::default() };
        let before = LIVE.load(Ordering::SeqCst);
        let mut sys = System::new(&cfg, &mesh).unwrap();
        let mut check = |sys: &System, when: &str| {
            let live = (LIVE.load(Ordering::SeqCst) - before) as f64;
            let figure = sys.memory();
            let ratio = figure.total() as f64 / live;
            println!(
                "{feathers} feathers, {when}: figure {} B ({figure:?}), live heap {live} B, ratio {ratio:.3}",
                figure.total()
            );
            if !(0.9..=1.1).contains(&ratio) {
                failures.push(format!("{feathers} feathers, {when}: figure/live = {ratio:.3}"));
            }
        };
        check(&sys, "after create");
        for frame in &frames {
            sys.step(frame).unwrap();
        }
        check(&sys, "after 4 frames");
        // Steps a host can stop keep a copy of the coat to restore: the
        // figure counts it.
        let sink = GoOn;
        for frame in frames.iter().rev().take(2) {
            sys.step_with_progress(frame, &Progress::to(&sink)).unwrap();
        }
        check(&sys, "after 2 frames that could be stopped");
    }
    assert!(failures.is_empty(), "{}", failures.join("\n"));
    the_memory_limit_is_kept(&mesh, &frames);
}

fn the_memory_limit_is_kept(mesh: &MeshInput<'_>, frames: &[Vec<f32>]) {
    use plumage::ErrorKind;
    let base = Config { target_feathers: 10_000, threads: 1, ..Config::default() };
    let full = System::new(&base, mesh).unwrap();
    let (needed, state) = (full.memory().total(), full.save_state());
    drop(full);

    // Below what the feathers' own arrays need: refused before they are
    // allocated (the call's peak stays far below the full system's size).
    let floor = plumage::system::feather_arrays_floor(10_000);
    assert!(floor < needed, "the floor {floor} is a lower bound of {needed}");
    let before = LIVE.load(Ordering::SeqCst);
    PEAK.store(before, Ordering::SeqCst);
    let err = System::new(&Config { memory_limit: floor / 2, ..base }, mesh).expect_err("refused up front");
    let peak = (PEAK.load(Ordering::SeqCst) - before) as usize;
    println!("limit {}: {err}; the call's peak {peak} B", floor / 2);
    assert_eq!(err.kind(), ErrorKind::LimitExceeded, "{err}");
    assert!(err.message().contains("memory_limit"), "{err}");
    assert!(peak < needed / 4, "the refused create peaked at {peak} B of {needed}");
    drop(err);
    assert_eq!(LIVE.load(Ordering::SeqCst), before, "nothing stays allocated");

    // Above the arrays but below the whole system: refused after building,
    // everything freed.
    let err = System::new(&Config { memory_limit: needed * 9 / 10, ..base }, mesh).expect_err("refused");
    println!("limit {}: {err}", needed * 9 / 10);
    assert_eq!(err.kind(), ErrorKind::LimitExceeded, "{err}");
    drop(err);
    assert_eq!(LIVE.load(Ordering::SeqCst), before, "nothing stays allocated");

    // Enough for create: the same coat; then the step that would pass the
    // limit is refused and the system is as it was before it.
    let mut sys = System::new(&Config { memory_limit: needed + needed / 20, ..base }, mesh).unwrap();
    assert_eq!(sys.save_state(), state, "a limit changes no result");
    let mut refused = false;
    for frame in frames {
        let (before_step, held) = (sys.save_state(), sys.memory().total());
        match sys.step(frame) {
            Ok(()) => assert!(sys.memory().total() <= needed + needed / 20),
            Err(e) => {
                println!("step refused: {e}");
                assert_eq!(e.kind(), ErrorKind::LimitExceeded, "{e}");
                assert_eq!(sys.save_state(), before_step, "a refused step is undone");
                // Nor does it keep the coat it made: only a step's scratch
                // and buffers may have grown (a few MB here; the coat it
                // made is some 50 MB).
                let after = sys.memory().total();
                println!("held {held} B before the refused step, {after} B after");
                assert!(after < held + needed / 10, "held {after} B after the refused step, {held} B before");
                refused = true;
                break;
            }
        }
    }
    assert!(refused, "the steps grew the system past 105 % of create's size, and one is refused");
}
