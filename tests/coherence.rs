//! Temporal coherence (issue #19): the incremental mode settles feathers
//! over frames instead of snapping them to a newly solved pose, so it pops
//! less than the legacy and rebuild modes, stays collision-free, and over
//! a long loop neither fluffs up nor sinks against rebuild's coat.

mod common;

use common::shapes::{Shape, swim_body, swim_pose};
use plumage::{Config, MeshInput, Mode, System};

/// A lighter built-in swimmer than the host's 96 × 32.
const RINGS: usize = 48;
const SEGMENTS: usize = 16;
const FPS: f64 = 30.0;

fn config(feathers: usize, mode: Mode, shaft_segments: u32) -> Config {
    Config {
        target_feathers: feathers,
        mode,
        shaft_segments,
        threads: 2,
        seed: 7,
        // The head pole, as the host's built-in model: feathers run head to tail.
        flow_source: Some(glam::Vec3::ZERO),
        ..Config::default()
    }
}

fn create(body: &Shape, config: &Config) -> System {
    System::new(config, &MeshInput::new(&body.positions, &body.indices)).expect("create")
}

fn frame(k: usize) -> Vec<f32> {
    swim_pose(RINGS, SEGMENTS, k as f64 / FPS)
}

/// Pops summed over `frames` steps of the swim, and the worst frame's
/// intersecting pairs and body penetrations (validated every
/// `validate_every` frames and at the last).
fn swim(config: &Config, frames: usize, validate_every: usize) -> (usize, usize, usize) {
    let body = swim_body(RINGS, SEGMENTS);
    let mut sys = create(&body, config);
    let (mut pops, mut pairs, mut penetrations) = (0, 0, 0);
    for k in 0..frames {
        sys.step(&frame(k)).unwrap();
        pops += sys.pose_changes().pops;
        if k % validate_every == 0 || k + 1 == frames {
            let v = sys.validate().unwrap();
            pairs = pairs.max(v.intersecting_pairs);
            penetrations = penetrations.max(v.body_penetrations);
        }
    }
    (pops, pairs, penetrations)
}

#[test]
fn settling_pops_less_than_legacy_and_rebuild_on_the_swim() {
    for segments in [1u32, 4] {
        let feathers = 500;
        let frames = 45;
        let run = |mode: Mode, settle_rate: Option<f32>| {
            let mut c = config(feathers, mode, segments);
            if let Some(rate) = settle_rate {
                c.settle_rate = rate;
            }
            swim(&c, frames, 5)
        };
        let settled = run(Mode::Incremental, None);
        let at_once = run(Mode::Incremental, Some(0.0));
        let legacy = run(Mode::Legacy, None);
        let rebuild = run(Mode::Rebuild, None);
        println!(
            "S = {segments}, {frames} frames: pops settled {}, settle_rate 0 {}, legacy {}, rebuild {}; worst pairs and penetrations settled {:?}",
            settled.0,
            at_once.0,
            legacy.0,
            rebuild.0,
            (settled.1, settled.2)
        );
        assert_eq!((settled.1, settled.2), (0, 0), "S = {segments}: collision-free every validated frame");
        assert!(settled.0 < at_once.0, "S = {segments}: settling must pop less than snapping");
        assert!(settled.0 <= legacy.0, "S = {segments}: at most legacy's pops");
        assert!(3 * settled.0 <= rebuild.0, "S = {segments}: at most a third of rebuild's pops");
    }
}

/// The built-in swim looped for 600 frames: the mean pitch stays within
/// 2° of rebuild's (the coat solved from scratch at the same frame).
#[test]
fn a_long_loop_neither_fluffs_up_nor_sinks() {
    let body = swim_body(RINGS, SEGMENTS);
    let feathers = 300;
    let mut sys = create(&body, &config(feathers, Mode::Incremental, 1));
    let mut worst: f64 = 0.0;
    let mut pops = 0;
    for k in 0..600 {
        let positions = frame(k);
        sys.step(&positions).unwrap();
        pops += sys.pose_changes().pops;
        if (k + 1) % 150 == 0 {
            let mut reference = create(&body, &config(feathers, Mode::Rebuild, 1));
            reference.step(&positions).unwrap();
            let (mine, theirs) = (sys.validate().unwrap(), reference.validate().unwrap());
            let diff = mine.mean_pitch_deg - theirs.mean_pitch_deg;
            println!(
                "frame {}: mean pitch {:.2}° (rebuild {:.2}°), pairs {}, penetrations {}",
                k + 1,
                mine.mean_pitch_deg,
                theirs.mean_pitch_deg,
                mine.intersecting_pairs,
                mine.body_penetrations
            );
            assert!(diff.abs() <= 2.0, "frame {}: mean pitch {diff:+.2}° off rebuild's", k + 1);
            assert_eq!((mine.intersecting_pairs, mine.body_penetrations), (0, 0), "frame {}", k + 1);
            worst = worst.max(diff.abs());
        }
    }
    println!(
        "600 frames: {pops} pops ({:.3} % a frame), worst mean pitch gap {worst:.2}°",
        100.0 * pops as f64 / (600.0 * sys.feather_count() as f64)
    );
}

/// Scrubbing gives what playback gives: with checkpoints every 5 frames,
/// frames reached out of order (12, 3, 20, 12) by seeking and replaying
/// from the returned frame give byte-identical feathers and state blobs to
/// stepping straight through; two identical runs save identical blobs; the
/// blob size a feather is reported.
#[test]
fn frames_reached_out_of_order_are_the_playback_frames() {
    for segments in [1u32, 4] {
        let body = swim_body(RINGS, SEGMENTS);
        let cfg = Config { checkpoint_interval: 5, checkpoint_cap: 3, ..config(300, Mode::Incremental, segments) };
        // Playback: the triangles and the blob after every step.
        let mut playback = create(&body, &cfg);
        let mut twin = create(&body, &cfg);
        let mut frames = vec![(playback.feather_triangles().to_vec(), playback.save_state())];
        for k in 0..20 {
            playback.step(&frame(k)).unwrap();
            twin.step(&frame(k)).unwrap();
            assert_eq!(playback.save_state(), twin.save_state(), "S = {segments}: identical runs, identical blobs");
            frames.push((playback.feather_triangles().to_vec(), playback.save_state()));
        }
        // The cap keeps the one after create and the newest three.
        assert_eq!(playback.checkpoint_frames(), [0, 10, 15, 20], "S = {segments}");
        let blob = &frames[20].1;
        println!(
            "S = {segments}: state blob {} bytes for {} feathers, {:.0} bytes a feather",
            blob.len(),
            playback.feather_count(),
            blob.len() as f64 / playback.feather_count() as f64
        );
        // Scrubbing: a fresh system, stepped to 8, then 12, 3, 20, 12.
        let mut scrub = create(&body, &Config { checkpoint_cap: 8, ..cfg.clone() });
        for k in 0..8 {
            scrub.step(&frame(k)).unwrap();
        }
        for target in [12u64, 3, 20, 12] {
            let from = scrub.seek(target).unwrap();
            assert!(from <= target, "S = {segments}: seek({target}) returned {from}");
            for k in from..target {
                scrub.step(&frame(k as usize)).unwrap();
            }
            assert_eq!(scrub.frames_stepped(), target);
            let (triangles, state) = &frames[target as usize];
            assert!(
                scrub.feather_triangles() == &triangles[..],
                "S = {segments}: frame {target} differs from playback"
            );
            assert_eq!(&scrub.save_state(), state, "S = {segments}: frame {target}'s state differs from playback");
        }
        // Back to 3 goes through the checkpoint after create (frames 0 and 5 kept, then 10, ...).
        assert_eq!(scrub.seek(3).unwrap(), 0, "S = {segments}");
        // After an evaluate the coat is off the playback: a seek reloads.
        scrub.evaluate(&frame(2)).unwrap();
        assert_eq!(scrub.seek(4).unwrap(), 0, "S = {segments}");
        let off = Config { checkpoint_interval: 0, ..cfg.clone() };
        assert!(create(&body, &off).seek(3).is_err(), "checkpoints off: seek refused");
    }
}
