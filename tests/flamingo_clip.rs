//! The flamingo's whole flying clip at 30 fps, about 2000 feathers flowing
//! from the beak, in the three modes (DESIGN.md §5, §6): rebuild is
//! collision-free on every frame; incremental keeps intersecting pairs and
//! body penetrations within 0.2 % of the feathers on every frame, tracks
//! rebuild's mean pitch within 2° and drifts less than legacy (the paper's
//! Fig. 6 effect); the paper's rule (drift tolerance θs) is run beside it.
//! Scrubbing the clip forwards, backwards and forwards again keeps the
//! incremental coat as clear and as close to rebuild as one pass.

mod common;

use plumage::{Config, MeshInput, Mode, Preset, System};

struct Run {
    name: &'static str,
    intersecting: Vec<usize>,
    penetrations: Vec<usize>,
    pitch: Vec<f64>,
    tip: Vec<f64>,
    adjusted: Vec<usize>,
    feathers: usize,
}

/// Where the Flamingo's beak tip is, in model units.
const BEAK: glam::Vec3 = glam::Vec3::new(0.0, 0.0, 100.4);

fn run(name: &'static str, cfg: Config, rest: &common::shapes::Shape, frames: &[Vec<f32>]) -> Run {
    let cfg = Config { target_feathers: 2000, threads: 2, flow_source: Some(BEAK), ..cfg };
    let mut sys = System::new(&cfg, &MeshInput::new(&rest.positions, &rest.indices)).expect("create");
    let mut out = Run {
        name,
        intersecting: vec![],
        penetrations: vec![],
        pitch: vec![],
        tip: vec![],
        adjusted: vec![],
        feathers: sys.feather_count(),
    };
    for frame in frames {
        sys.step(frame).expect("step");
        let v = sys.validate().unwrap();
        out.intersecting.push(v.intersecting_pairs);
        out.penetrations.push(v.body_penetrations);
        out.pitch.push(v.mean_pitch_deg);
        out.tip.push(v.tip_height_median);
        out.adjusted.push(sys.frame_report().unwrap().adjusted);
    }
    out
}

fn mean(v: &[f64]) -> f64 {
    v.iter().sum::<f64>() / v.len().max(1) as f64
}

/// The four runs over the clip from `base` (a preset), printed.
fn clip_runs(base: &Config, rest: &common::shapes::Shape, frames: &[Vec<f32>]) -> [Run; 4] {
    let mode = |mode| Config { mode, ..base.clone() };
    let inc = run("incremental", mode(Mode::Incremental), rest, frames);
    let reb = run("rebuild", mode(Mode::Rebuild), rest, frames);
    let leg = run("legacy", mode(Mode::Legacy), rest, frames);
    let paper = run("paper's rule", Config { drift_tolerance: 0.05, ..mode(Mode::Incremental) }, rest, frames);
    println!(
        "flamingo clip: {} frames, {} feathers, {} shaft segments",
        frames.len(),
        inc.feathers,
        base.shaft_segments
    );
    for r in [&inc, &paper, &reb, &leg] {
        println!(
            "{:>12}: max intersecting pairs {}, max body penetrations {}, mean adjusted {:.1}, mean pitch {:.2}° (first {:.2}°, last {:.2}°, drift vs rebuild {:+.2}°), mean tip height {:.3} (drift vs rebuild {:+.3})",
            r.name,
            r.intersecting.iter().max().unwrap(),
            r.penetrations.iter().max().unwrap(),
            mean(&r.adjusted.iter().map(|&a| a as f64).collect::<Vec<_>>()),
            mean(&r.pitch),
            r.pitch[0],
            r.pitch.last().unwrap(),
            mean(&r.pitch) - mean(&reb.pitch),
            mean(&r.tip),
            mean(&r.tip) - mean(&reb.tip),
        );
    }
    [inc, reb, leg, paper]
}

fn most(v: &[usize]) -> usize {
    *v.iter().max().unwrap()
}

fn adjusted(r: &Run) -> f64 {
    mean(&r.adjusted.iter().map(|&a| a as f64).collect::<Vec<_>>())
}

/// The paper's kite (`Preset::Kite`): incremental within 0.2 % in pairs
/// and penetrations, as is the paper's rule, fewer readjusted than it,
/// within 2° of rebuild's mean pitch and closer to it than legacy (the
/// paper's Fig. 6 effect).
#[test]
fn incremental_tracks_rebuild_over_the_whole_clip() {
    let Some((rest, frames)) = common::gltf_mesh::morph_clip("Flamingo.glb", 30.0) else { return };
    let [inc, reb, leg, paper] = clip_runs(&Config::preset(Preset::Kite), &rest, &frames);
    let n = inc.feathers;
    assert_eq!((most(&reb.intersecting), most(&reb.penetrations)), (0, 0), "rebuild is collision-free on every frame");
    let allowed = n / 500; // 0.2 %
    for r in [&inc, &paper] {
        let (pairs, penetrations) = (most(&r.intersecting), most(&r.penetrations));
        assert!(pairs <= allowed && penetrations <= allowed, "{}: {pairs} pairs, {penetrations} penetrations", r.name);
    }
    assert!(adjusted(&inc) < adjusted(&paper), "exact checks readjust fewer feathers than the paper's rule");
    let gap = (mean(&inc.pitch) - mean(&reb.pitch)).abs();
    assert!(gap <= 2.0, "incremental mean pitch is {gap:.2}° from rebuild's on average");
    let legacy_gap = (mean(&leg.pitch) - mean(&reb.pitch)).abs();
    assert!(gap < legacy_gap, "incremental ({gap:.2}°) drifts less than legacy ({legacy_gap:.2}°)");
}

/// The default bent feather: incremental as clear as the kite's (0.2 %),
/// the paper's rule within 1 % (it checks nothing exactly, and bent
/// feathers lie closer on what is beneath them), incremental within 2° of
/// rebuild's mean pitch and within 0.05 lengths of its tip height. Its
/// tips drift above rebuild's (settled feathers that a retreating obstacle
/// leaves clear are not re-solved) further than legacy's, which stays
/// closer by leaving collisions: BENCHMARKS.md, issue #30.
#[test]
fn the_default_coat_tracks_rebuild_over_the_whole_clip() {
    let Some((rest, frames)) = common::gltf_mesh::morph_clip("Flamingo.glb", 30.0) else { return };
    let [inc, reb, _leg, paper] = clip_runs(&Config::default(), &rest, &frames);
    let n = inc.feathers;
    assert_eq!((most(&reb.intersecting), most(&reb.penetrations)), (0, 0), "rebuild is collision-free on every frame");
    for (r, allowed) in [(&inc, n / 500), (&paper, n / 100)] {
        let (pairs, penetrations) = (most(&r.intersecting), most(&r.penetrations));
        assert!(pairs <= allowed && penetrations <= allowed, "{}: {pairs} pairs, {penetrations} penetrations", r.name);
    }
    assert!(adjusted(&inc) < adjusted(&paper), "exact checks readjust fewer feathers than the paper's rule");
    let gap = (mean(&inc.pitch) - mean(&reb.pitch)).abs();
    assert!(gap <= 2.0, "incremental mean pitch is {gap:.2}° from rebuild's on average");
    let tip_gap = mean(&inc.tip) - mean(&reb.tip);
    assert!(tip_gap.abs() <= 0.05, "incremental tips stand {tip_gap:.3} lengths off rebuild's on average");
}

/// An animator scrubbing: the clip forwards, backwards, then forwards
/// again (126 frames). Incremental stays within 0.2 % of the feathers in
/// pairs and penetrations on every frame, and on each pass its mean pitch
/// stays within 2° of rebuild's, so the drift does not build up with the
/// frames stepped.
#[test]
fn scrubbing_back_and_forth_stays_collision_free_and_close_to_rebuild() {
    let Some((rest, frames)) = common::gltf_mesh::morph_clip("Flamingo.glb", 30.0) else { return };
    let passes: Vec<Vec<f32>> = frames.iter().chain(frames.iter().rev()).chain(frames.iter()).cloned().collect();
    let inc = run("incremental", Config { mode: Mode::Incremental, ..Config::default() }, &rest, &passes);
    let reb = run("rebuild", Config { mode: Mode::Rebuild, ..Config::default() }, &rest, &passes);
    let allowed = inc.feathers / 500; // 0.2 %
    let most = |v: &[usize]| *v.iter().max().unwrap();
    let (pairs, penetrations) = (most(&inc.intersecting), most(&inc.penetrations));
    assert!(pairs <= allowed && penetrations <= allowed, "scrubbing: {pairs} pairs, {penetrations} penetrations");
    for (k, (a, b)) in inc.pitch.chunks(frames.len()).zip(reb.pitch.chunks(frames.len())).enumerate() {
        let gap = mean(a) - mean(b);
        println!("pass {k}: incremental mean pitch {:.2}°, rebuild {:.2}°, drift {gap:+.2}°", mean(a), mean(b));
        assert!(gap.abs() <= 2.0, "pass {k}: incremental mean pitch is {gap:.2}° from rebuild's");
    }
}
