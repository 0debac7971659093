//! Reliability of the safe API (DESIGN.md, Standards): random meshes and
//! random deformations, NaN injection, and determinism across thread
//! counts and runs.

mod common;

use common::shapes::grid;
use plumage::{Config, ErrorKind, MeshInput, Mode, System};
use proptest::prelude::*;

fn all_finite(sys: &System) -> bool {
    sys.feathers().iter().all(|f| {
        f.root.iter().chain(&f.normal).chain(&f.direction).all(|x| x.is_finite())
            && [f.pitch, f.roll, f.length, f.width, f.thickness].iter().all(|x| x.is_finite())
    }) && sys.feather_triangles().iter().flatten().all(|x| x.is_finite())
}

/// A random soup: vertices in a box, triangles over random indices (some
/// degenerate, some repeated, some non-manifold).
fn soup() -> impl Strategy<Value = (Vec<f32>, Vec<u32>)> {
    (4usize..40).prop_flat_map(|n| {
        (
            proptest::collection::vec(-5.0f32..5.0, 3 * n),
            proptest::collection::vec(0..n as u32, 3..3 * 60).prop_map(|mut v| {
                v.truncate(v.len() / 3 * 3);
                v
            }),
        )
    })
}

proptest! {
    #![proptest_config(ProptestConfig { rng_seed: proptest::test_runner::RngSeed::Fixed(0x0070_6c75_6d61_6765), cases: 48, ..ProptestConfig::default() })]

    #[test]
    fn random_meshes_and_frames_never_panic_nor_produce_nan(
        (positions, indices) in soup(),
        wobble in proptest::collection::vec(-0.5f32..0.5, 8),
        nan_at in 0usize..1000,
        mode in 0usize..3,
    ) {
        let mode = [Mode::Incremental, Mode::Legacy, Mode::Rebuild][mode];
        let cfg = Config { target_feathers: 60, threads: 1, mode, ..Config::default() };
        let Ok(mut sys) = System::new(&cfg, &MeshInput::new(&positions, &indices)) else { return Ok(()) };
        prop_assert!(all_finite(&sys));
        prop_assert!(sys.validate().is_some());
        for (k, w) in wobble.iter().enumerate() {
            let frame: Vec<f32> = positions.iter().enumerate().map(|(i, x)| x + w * ((i * 7 + k) as f32).sin()).collect();
            if k == 3 {
                let mut bad = frame.clone();
                let at = nan_at % bad.len();
                bad[at] = f32::NAN;
                prop_assert_eq!(sys.step(&bad).unwrap_err().kind(), ErrorKind::NonFinite);
            }
            sys.step(&frame).unwrap();
            prop_assert!(all_finite(&sys));
            let v = sys.validate().unwrap();
            prop_assert!(v.coverage.is_finite() && v.mean_pitch_deg.is_finite());
        }
    }
}

/// The bytes of every feather record and triangle.
fn feather_bytes(sys: &System) -> Vec<u8> {
    let mut out = Vec::new();
    for f in sys.feathers() {
        out.extend_from_slice(&f.id.to_le_bytes());
        out.extend_from_slice(&f.order_index.to_le_bytes());
        for x in f.root.iter().chain(&f.normal).chain(&f.direction).chain(&[f.pitch, f.roll]) {
            out.extend_from_slice(&x.to_bits().to_le_bytes());
        }
    }
    for x in sys.feather_triangles().iter().flatten() {
        out.extend_from_slice(&x.to_bits().to_le_bytes());
    }
    out
}

/// A wavy plate rippling over 10 frames, feathered at `threads`; the feather
/// bytes after creation and after each frame.
fn ripple_run(threads: usize, mode: Mode) -> Vec<Vec<u8>> {
    let plate = grid(8.0, 8.0, 32, 32, 0.0, true);
    let cfg = Config { target_feathers: 900, threads, mode, seed: 5, ..Config::default() };
    let mut sys = System::new(&cfg, &MeshInput::new(&plate.positions, &plate.indices)).unwrap();
    assert_eq!(sys.threads(), threads);
    let mut out = vec![feather_bytes(&sys)];
    for k in 1..=10 {
        let t = k as f32 * 0.3;
        let frame: Vec<f32> = plate
            .positions
            .chunks(3)
            .flat_map(|p| [p[0], p[1], 0.4 * (0.8 * p[0] + t).sin() * (0.5 * p[1]).cos()])
            .collect();
        sys.step(&frame).unwrap();
        out.push(feather_bytes(&sys));
    }
    out
}

#[test]
fn feathers_are_byte_identical_at_1_2_and_4_threads_and_across_runs() {
    for mode in [Mode::Incremental, Mode::Legacy, Mode::Rebuild] {
        let one = ripple_run(1, mode);
        assert!(one[0].len() > 1000, "the plate has feathers");
        assert_eq!(one, ripple_run(1, mode), "{mode:?}: two runs at one thread");
        for threads in [2, 4] {
            let other = ripple_run(threads, mode);
            for (k, (a, b)) in one.iter().zip(&other).enumerate() {
                assert!(a == b, "{mode:?}: frame {k} differs between 1 and {threads} threads");
            }
        }
    }
}

#[test]
fn a_frame_with_the_wrong_vertex_count_or_nan_changes_nothing() {
    let plate = grid(4.0, 4.0, 16, 16, 0.0, true);
    let cfg = Config { target_feathers: 200, threads: 1, ..Config::default() };
    let mut sys = System::new(&cfg, &MeshInput::new(&plate.positions, &plate.indices)).unwrap();
    let before = feather_bytes(&sys);
    assert_eq!(sys.step(&plate.positions[3..]).unwrap_err().kind(), ErrorKind::VertexCountMismatch);
    let mut inf = plate.positions.clone();
    inf[10] = f32::INFINITY;
    assert_eq!(sys.step(&inf).unwrap_err().kind(), ErrorKind::NonFinite);
    assert_eq!(sys.evaluate(&inf).unwrap_err().kind(), ErrorKind::NonFinite);
    assert_eq!(feather_bytes(&sys), before);
    assert_eq!(sys.frames_stepped(), 0);
}

mod interruption {
    use super::*;
    use plumage::progress::{Phase, Progress, ProgressSink};
    use std::sync::Mutex;

    /// Records every report; asks to stop after `allow` of them.
    struct Recorder {
        seen: Mutex<Vec<(Phase, f32)>>,
        allow: usize,
    }

    impl ProgressSink for Recorder {
        fn report(&self, phase: Phase, fraction: f32) -> bool {
            let mut seen = self.seen.lock().unwrap();
            seen.push((phase, fraction));
            seen.len() <= self.allow
        }
    }

    fn plate() -> common::shapes::Shape {
        grid(12.0, 12.0, 48, 48, 0.0, true)
    }

    fn wave(shape: &common::shapes::Shape, t: f32) -> Vec<f32> {
        shape.positions.chunks(3).flat_map(|p| [p[0], p[1], 0.5 * (0.7 * p[0] + t).sin()]).collect()
    }

    #[test]
    fn progress_is_reported_inside_sampling_and_adjustment() {
        let shape = plate();
        let cfg = Config { target_feathers: 4000, threads: 1, ..Config::default() };
        let rec = Recorder { seen: Mutex::new(Vec::new()), allow: usize::MAX };
        System::new_with_progress(&cfg, &MeshInput::new(&shape.positions, &shape.indices), &Progress::to(&rec))
            .unwrap();
        let seen = rec.seen.lock().unwrap();
        let inside = |phase: Phase| seen.iter().filter(|(p, f)| *p == phase && *f > 0.0 && *f < 1.0).count();
        println!(
            "reports: {} in all, {} inside sampling, {} inside adjusting",
            seen.len(),
            inside(Phase::Sampling),
            inside(Phase::Adjusting)
        );
        assert!(inside(Phase::Sampling) >= 3, "sampling reports from inside its loop");
        assert!(inside(Phase::Adjusting) >= 3, "adjustment reports from inside its levels");
        assert!(seen.iter().all(|(_, f)| (0.0..=1.0).contains(f)));
    }

    #[test]
    fn a_step_stopped_anywhere_leaves_the_system_as_it_was() {
        let shape = plate();
        let cfg = Config { target_feathers: 1500, threads: 2, ..Config::default() };
        let mesh = MeshInput::new(&shape.positions, &shape.indices);
        let mut twin = System::new(&cfg, &mesh).unwrap();
        twin.step(&wave(&shape, 0.5)).unwrap();
        let mut stopped_somewhere = 0;
        for allow in [0, 1, 2, 4, 8, 16, 32, 64] {
            let mut sys = System::new(&cfg, &mesh).unwrap();
            let before = feather_bytes(&sys);
            let readjusted_before = sys.readjusted().to_vec();
            let rec = Recorder { seen: Mutex::new(Vec::new()), allow };
            if let Err(e) = sys.step_with_progress(&wave(&shape, 0.5), &Progress::to(&rec)) {
                assert_eq!(e.kind(), ErrorKind::Interrupted);
                assert_eq!(feather_bytes(&sys), before, "stopped after {allow} reports: unchanged");
                assert_eq!(sys.readjusted(), &readjusted_before[..], "stopped after {allow}: same readjusted flags");
                assert_eq!(sys.frames_stepped(), 0);
                stopped_somewhere += 1;
                sys.step(&wave(&shape, 0.5)).unwrap();
            }
            assert_eq!(feather_bytes(&sys), feather_bytes(&twin), "after {allow}: the same as never stopped");
        }
        assert!(stopped_somewhere >= 3, "the step was stopped at several points ({stopped_somewhere})");
    }

    #[test]
    fn a_stopped_create_creates_nothing() {
        let shape = plate();
        let cfg = Config { target_feathers: 1500, threads: 1, ..Config::default() };
        for allow in [0, 3, 20] {
            let rec = Recorder { seen: Mutex::new(Vec::new()), allow };
            let r =
                System::new_with_progress(&cfg, &MeshInput::new(&shape.positions, &shape.indices), &Progress::to(&rec));
            assert_eq!(r.unwrap_err().kind(), ErrorKind::Interrupted, "stopped after {allow} reports");
        }
    }
}
