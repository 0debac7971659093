//! Interrupt latency (issue 32): how long a call takes to return after the
//! progress callback asks it to stop, in every phase of create, step,
//! evaluate and validate. `cargo run --release --example interrupt_latency
//! -- [FEATHERS] [TRIALS]` (default 2 000 feathers, 40 trials a phase) on
//! the built-in body, one thread. Each trial stops the call at the k-th
//! report of one phase (k drawn from 1 to 12) and measures from the
//! callback's "stop" to the call's return; prints per call and phase the
//! median, 99th percentile and largest latency in milliseconds.

#[path = "../tests/common/shapes.rs"]
#[allow(dead_code)]
mod shapes;

use plumage::progress::{Phase, Progress, ProgressSink};
use plumage::{Config, MeshInput, System};
use std::sync::Mutex;
use std::time::Instant;

/// Asks to stop at the `stop_at`-th report of `phase`; remembers when.
struct StopAt {
    phase: Phase,
    stop_at: usize,
    seen: Mutex<(usize, Option<Instant>)>,
}

impl ProgressSink for StopAt {
    fn report(&self, phase: Phase, _fraction: f32) -> bool {
        let mut seen = self.seen.lock().unwrap();
        if seen.1.is_some() {
            return false;
        }
        if phase == self.phase {
            seen.0 += 1;
            if seen.0 >= self.stop_at {
                seen.1 = Some(Instant::now());
                return false;
            }
        }
        true
    }
}

/// Latency of one interrupted call, ms (None: the phase was not reached
/// that many times, the call ran to its end).
fn trial(phase: Phase, stop_at: usize, call: impl FnOnce(&Progress) -> plumage::Result<()>) -> Option<f64> {
    let sink = StopAt { phase, stop_at, seen: Mutex::new((0, None)) };
    let progress = Progress::to(&sink);
    let result = call(&progress);
    let returned = Instant::now();
    let stopped = sink.seen.lock().unwrap().1?;
    assert!(result.is_err(), "stopped but returned OK");
    Some(returned.duration_since(stopped).as_secs_f64() * 1e3)
}

/// Records the gaps between consecutive reports (ms), by phase of the
/// earlier report, and never stops.
#[derive(Default)]
struct Gaps {
    last: Mutex<Option<(Phase, Instant)>>,
    gaps: Mutex<Vec<(Phase, f64)>>,
}

impl ProgressSink for Gaps {
    fn report(&self, phase: Phase, fraction: f32) -> bool {
        let now = Instant::now();
        let mut last = self.last.lock().unwrap();
        if let Some((p, t)) = *last {
            let gap = now.duration_since(t).as_secs_f64() * 1e3;
            if std::env::var_os("GAP_LOG").is_some() && gap > 1.5 {
                println!("  gap {gap:.2} ms before {phase:?} {fraction:.3} (after {p:?})");
            }
            self.gaps.lock().unwrap().push((p, gap));
        }
        *last = Some((phase, now));
        true
    }
}

fn gaps_of(name: &str, call: impl FnOnce(&Progress)) {
    let sink = Gaps::default();
    call(&Progress::to(&sink));
    let gaps = sink.gaps.into_inner().unwrap();
    for phase in [Phase::Preparing, Phase::Sampling, Phase::Ordering, Phase::Adjusting, Phase::Validating] {
        let ms: Vec<f64> = gaps.iter().filter(|g| g.0 == phase).map(|g| g.1).collect();
        if !ms.is_empty() {
            summary(&format!("{name}, {phase:?}"), ms);
        }
    }
}

fn summary(name: &str, mut ms: Vec<f64>) {
    if ms.is_empty() {
        println!("| {name} | 0 | | | |");
        return;
    }
    ms.sort_by(f64::total_cmp);
    let at = |q: f64| ms[((ms.len() - 1) as f64 * q).round() as usize];
    println!("| {name} | {} | {:.3} | {:.3} | {:.3} |", ms.len(), at(0.5), at(0.99), ms[ms.len() - 1]);
}

fn main() {
    let args: Vec<usize> = std::env::args().skip(1).filter_map(|a| a.parse().ok()).collect();
    let feathers = args.first().copied().unwrap_or(2000);
    let trials = args.get(1).copied().unwrap_or(40);
    let (rings, segments) = (96, 32);
    let body = shapes::swim_body(rings, segments);
    let mesh = MeshInput::new(&body.positions, &body.indices);
    let cfg = Config { target_feathers: feathers, threads: 1, ..Config::default() };
    let frame = shapes::swim_pose(rings, segments, 0.3);
    let mut sys = System::new(&cfg, &mesh).unwrap();
    println!("| call and phase | trials stopped | median ms | p99 ms | max ms |");
    println!("|---|---|---|---|---|");
    let mut all = Vec::new();
    let k = |t: usize| 1 + (t * 7) % 12;
    for phase in [Phase::Preparing, Phase::Sampling, Phase::Ordering, Phase::Adjusting] {
        let ms: Vec<f64> = (0..trials)
            .filter_map(|t| trial(phase, k(t), |p| System::new_with_progress(&cfg, &mesh, p).map(drop)))
            .collect();
        all.extend_from_slice(&ms);
        summary(&format!("create, {phase:?}"), ms);
    }
    for phase in [Phase::Ordering, Phase::Adjusting] {
        let ms: Vec<f64> =
            (0..trials).filter_map(|t| trial(phase, k(t), |p| sys.step_with_progress(&frame, p))).collect();
        all.extend_from_slice(&ms);
        summary(&format!("step, {phase:?}"), ms);
        let ms: Vec<f64> =
            (0..trials).filter_map(|t| trial(phase, k(t), |p| sys.evaluate_with_progress(&frame, p))).collect();
        all.extend_from_slice(&ms);
        summary(&format!("evaluate, {phase:?}"), ms);
    }
    let ms: Vec<f64> = (0..trials)
        .filter_map(|t| trial(Phase::Validating, k(t), |p| sys.validate_with_progress(p).map(drop)))
        .collect();
    all.extend_from_slice(&ms);
    summary("validate, Validating", ms);
    summary("every call and phase", all);

    println!();
    println!("Gaps between two reports of the callback (the library reports at most every 1 ms):");
    println!();
    println!("| call and phase | gaps | median ms | p99 ms | max ms |");
    println!("|---|---|---|---|---|");
    gaps_of("create", |p| drop(System::new_with_progress(&cfg, &mesh, p).unwrap()));
    gaps_of("step", |p| sys.step_with_progress(&frame, p).unwrap());
    gaps_of("evaluate", |p| sys.evaluate_with_progress(&frame, p).unwrap());
    gaps_of("validate", |p| {
        sys.validate_with_progress(p).unwrap();
    });
}
