//! State snapshots through the safe API: saving a frame and resuming from
//! it gives byte-identical later frames in every mode; damaged, truncated
//! and foreign blobs are refused with `InvalidState` and leave the system
//! exactly as it was; no blob, however hostile, makes the library panic.

mod common;

use common::gltf_mesh::morph_clip;
use common::shapes::{Shape, uv_sphere};
use plumage::snapshot::Writer;
use plumage::stats::{FrameReport, OrderingReport};
use plumage::{Config, ErrorKind, MeshInput, Mode, System};
use proptest::prelude::*;
use std::sync::{Mutex, OnceLock};

/// Size of the blob header (magic, version, fingerprint, payload length)
/// and trailer (checksum), as laid out by `plumage::snapshot`.
const HEADER: usize = 28;
const TRAILER: usize = 8;

/// Frame `k` of an animation that really reorders feathers: a bulge
/// travelling around the body, a twist about z growing with height and
/// time, and a ripple along z. Distances between neighbours change
/// unevenly, so priorities flip and feathers readjust.
fn frame(rest: &[f32], k: usize) -> Vec<f32> {
    let t = k as f32;
    let (lo, hi) = rest.chunks(3).fold((f32::MAX, f32::MIN), |(lo, hi), p| (lo.min(p[2]), hi.max(p[2])));
    let h = (hi - lo).max(1e-6);
    rest.chunks(3)
        .flat_map(|p| {
            let (x, y, z) = (p[0], p[1], p[2]);
            let u = (z - lo) / h;
            let s = 1.0 + 0.2 * (3.0 * x / h * 2.0 + 0.5 * t).sin();
            let a = 0.12 * t * u;
            let (c, sn) = (a.cos(), a.sin());
            [s * (c * x - sn * y), s * (sn * x + c * y), z + 0.05 * h * (4.0 * y / h + 0.3 * t).sin()]
        })
        .collect()
}

/// What a host sees after a call: the feathers and their triangles as
/// bytes, which feathers were readjusted, the frame and ordering reports
/// without their timings, the frame count, and the saved state's bytes
/// (byte-reproducible, so equal states save equal blobs).
#[derive(Clone, Debug, PartialEq)]
struct Observed {
    bytes: Vec<u8>,
    state: Vec<u8>,
    readjusted: Vec<bool>,
    frame: FrameReport,
    ordering: OrderingReport,
    frames_stepped: u64,
}

fn observe(sys: &System) -> Observed {
    let mut bytes = Vec::new();
    let mut put = |x: u32| bytes.extend_from_slice(&x.to_le_bytes());
    for f in sys.feathers() {
        let floats = f.barycentric.iter().chain(&f.root).chain(&f.normal).chain(&f.direction);
        floats.chain(&[f.pitch, f.roll, f.length, f.width, f.thickness]).for_each(|x| put(x.to_bits()));
        [f.order_index, f.triangle, f.id as u32, (f.id >> 32) as u32].into_iter().for_each(&mut put);
    }
    sys.feather_triangles().iter().flatten().for_each(|x| put(x.to_bits()));
    let frame = FrameReport {
        reorder_seconds: 0.0,
        adjust_seconds: 0.0,
        step_seconds: 0.0,
        neighbourhood_seconds: 0.0,
        ..sys.frame_report().unwrap()
    };
    let ordering = OrderingReport { seconds: 0.0, ..sys.ordering_report().unwrap() };
    let (readjusted, frames_stepped) = (sys.readjusted().to_vec(), sys.frames_stepped());
    Observed { bytes, state: sys.save_state(), readjusted, frame, ordering, frames_stepped }
}

fn create(shape: &Shape, config: &Config) -> System {
    System::new(config, &MeshInput::new(&shape.positions, &shape.indices)).expect("system is created")
}

fn config(mode: Mode, recompute: bool, target: usize, threads: usize) -> Config {
    Config { seed: 7, threads, mode, target_feathers: target, recompute_neighbourhoods: recompute, ..Config::default() }
}

/// Steps frames `from..=to`, observing after each.
fn run(sys: &mut System, rest: &[f32], from: usize, to: usize) -> Vec<Observed> {
    (from..=to)
        .map(|k| {
            sys.step(&frame(rest, k)).expect("step");
            observe(sys)
        })
        .collect()
}

/// Save at frame 4, continue to 10; load, continue again: identical
/// feathers, triangles and reports. A second system (another thread count)
/// resumes from the same blob identically too, and the blob of a loaded
/// system is the blob it was loaded from, at every frame.
fn resume_is_exact(mode: Mode, recompute: bool) {
    let shape = uv_sphere(16, 24);
    let mut sys = create(&shape, &config(mode, recompute, 600, 2));
    let rest = &shape.positions;
    run(&mut sys, rest, 1, 4);
    let at_save = observe(&sys);
    let blob = sys.save_state();
    let first = run(&mut sys, rest, 5, 10);

    sys.load_state(&blob).expect("own blob loads");
    assert_eq!(observe(&sys), at_save, "load restores the saved frame's exports");
    assert_eq!(sys.save_state(), blob, "a loaded system saves the same blob");
    let second = run(&mut sys, rest, 5, 10);
    for (k, (a, b)) in first.iter().zip(&second).enumerate() {
        assert_eq!(a, b, "{mode:?} (recompute {recompute}): frame {} differs after resuming", k + 5);
    }

    let mut other = create(&shape, &config(mode, recompute, 600, 1));
    other.load_state(&blob).expect("a twin with another thread count accepts the blob");
    assert_eq!(run(&mut other, rest, 5, 10), first, "{mode:?}: another system resumes identically");

    // Every frame's blob passes the load checks and survives a round trip.
    let mut scratch = create(&shape, &config(mode, recompute, 600, 1));
    for k in 11..=16 {
        sys.step(&frame(rest, k)).unwrap();
        let blob = sys.save_state();
        scratch.load_state(&blob).unwrap_or_else(|e| panic!("{mode:?}: blob of frame {k} refused: {e}"));
        assert_eq!(scratch.save_state(), blob, "{mode:?}: frame {k}");
        assert_eq!(observe(&scratch), observe(&sys), "{mode:?}: frame {k}");
    }

    // The animation must really exercise the frame update.
    let adjusted: usize = first.iter().map(|o| o.frame.adjusted).sum();
    assert!(adjusted > 0, "{mode:?}: no feather readjusted");
    if mode == Mode::Incremental {
        let changes: usize = first.iter().map(|o| o.frame.priority_changes).sum();
        assert!(changes > 0, "incremental (recompute {recompute}): no priority changed");
    }
}

#[test]
fn resume_is_exact_incremental() {
    resume_is_exact(Mode::Incremental, true);
}

#[test]
fn resume_is_exact_incremental_fixed_neighbourhoods() {
    resume_is_exact(Mode::Incremental, false);
}

#[test]
fn resume_is_exact_legacy() {
    resume_is_exact(Mode::Legacy, true);
}

#[test]
fn resume_is_exact_rebuild() {
    resume_is_exact(Mode::Rebuild, true);
}

/// Two identical runs save identical bytes at every frame, whatever the
/// thread count and whatever the run's timings: the blob holds nothing
/// run-dependent. The blob size per feather is reported.
#[test]
fn identical_runs_save_identical_blobs() {
    let shape = uv_sphere(16, 24);
    let blobs = |threads: usize| -> Vec<Vec<u8>> {
        let mut sys = create(&shape, &config(Mode::Incremental, true, 600, threads));
        let mut out = vec![sys.save_state()];
        for k in 1..=6 {
            sys.step(&frame(&shape.positions, k)).unwrap();
            out.push(sys.save_state());
        }
        let n = sys.feather_count();
        let last = out.last().unwrap().len();
        eprintln!(
            "{n} feathers, {} welded vertices: state blob {last} bytes, {:.0} bytes per feather",
            sys.mesh().positions.len(),
            last as f64 / n as f64
        );
        out
    };
    let first = blobs(1);
    assert_eq!(blobs(1), first, "a second run at one thread saves other bytes");
    assert_eq!(blobs(2), first, "a run at two threads saves other bytes");
    assert!(first.windows(2).all(|w| w[0] != w[1]), "the frames must differ for the test to mean anything");
}

/// Loading an earlier frame after evaluate, and evaluate after a load, keep
/// the frame count semantics (evaluate keeps it, load restores it).
#[test]
fn load_restores_the_frame_count() {
    let shape = uv_sphere(10, 14);
    let mut sys = create(&shape, &config(Mode::Incremental, true, 120, 1));
    let blob0 = sys.save_state();
    run(&mut sys, &shape.positions, 1, 3);
    sys.evaluate(&frame(&shape.positions, 7)).unwrap();
    assert_eq!(sys.frames_stepped(), 3);
    sys.load_state(&blob0).unwrap();
    assert_eq!(sys.frames_stepped(), 0);
    let fresh = create(&shape, &config(Mode::Incremental, true, 120, 1));
    assert_eq!(observe(&sys), observe(&fresh));
}

/// A small system at frame 2 with the blob of its frame 1 (so that a blob
/// accepted by mistake would show), for the refusal tests.
fn small() -> (Shape, Config, System, Vec<u8>) {
    let shape = uv_sphere(8, 12);
    let cfg = config(Mode::Incremental, true, 60, 1);
    let mut sys = create(&shape, &cfg);
    run(&mut sys, &shape.positions, 1, 1);
    let blob = sys.save_state();
    run(&mut sys, &shape.positions, 2, 2);
    (shape, cfg, sys, blob)
}

/// The system refused everything since `before`: its exports and its
/// saved state's bytes are unchanged and its next step equals a twin's that never saw a refusal.
fn assert_unchanged(sys: &mut System, before: &Observed, shape: &Shape, cfg: &Config) {
    assert_eq!(&observe(sys), before);
    let mut twin = create(shape, cfg);
    run(&mut twin, &shape.positions, 1, 2);
    assert_eq!(run(sys, &shape.positions, 3, 3), run(&mut twin, &shape.positions, 3, 3));
}

fn refused(sys: &mut System, blob: &[u8]) -> bool {
    sys.load_state(blob).is_err_and(|e| e.kind() == ErrorKind::InvalidState)
}

#[test]
fn truncated_and_padded_blobs_are_refused() {
    let (shape, cfg, mut sys, blob) = small();
    let before = observe(&sys);
    for len in 0..blob.len() {
        assert!(refused(&mut sys, &blob[..len]), "prefix of {len} bytes accepted");
    }
    let mut padded = blob.clone();
    padded.push(0);
    assert!(refused(&mut sys, &padded));
    assert_unchanged(&mut sys, &before, &shape, &cfg);
}

#[test]
fn corrupt_blobs_are_refused() {
    let (shape, cfg, mut sys, blob) = small();
    let before = observe(&sys);
    let stride = (blob.len() / 500).max(1);
    let positions = (0..HEADER).chain((HEADER..blob.len()).step_by(stride)).chain(blob.len() - TRAILER..blob.len());
    for i in positions {
        for bit in [0x01u8, 0x80] {
            let mut bad = blob.clone();
            bad[i] ^= bit;
            assert!(refused(&mut sys, &bad), "flipped bit {bit:#x} of byte {i} accepted");
        }
    }
    assert_unchanged(&mut sys, &before, &shape, &cfg);
}

#[test]
fn foreign_blobs_are_refused() {
    let (shape, cfg, mut sys, _) = small();
    let before = observe(&sys);
    let blob_of = |shape: &Shape, cfg: &Config| create(shape, cfg).save_state();
    let others = [
        ("another seed", blob_of(&shape, &Config { seed: 8, ..cfg.clone() })),
        ("another mesh", blob_of(&uv_sphere(9, 12), &cfg)),
        ("another mode", blob_of(&shape, &Config { mode: Mode::Legacy, ..cfg.clone() })),
        ("another γ", blob_of(&shape, &Config { gamma: 0.61, ..cfg.clone() })),
        ("fixed neighbourhoods", blob_of(&shape, &Config { recompute_neighbourhoods: false, ..cfg.clone() })),
    ];
    for (what, blob) in &others {
        let err = sys.load_state(blob).expect_err(what);
        assert_eq!(err.kind(), ErrorKind::InvalidState, "{what}");
        assert!(err.message().contains("another system"), "{what}: {}", err.message());
    }
    assert_unchanged(&mut sys, &before, &shape, &cfg);
}

/// `blob`'s payload after `edit`, under a fresh header and checksum: what a
/// hostile or buggy host could hand in past the integrity checks.
fn resealed(blob: &[u8], edit: impl FnOnce(&mut Vec<u8>)) -> Vec<u8> {
    let fingerprint = u64::from_le_bytes(blob[12..20].try_into().unwrap());
    let mut payload = blob[HEADER..blob.len() - TRAILER].to_vec();
    edit(&mut payload);
    let mut w = Writer::new(fingerprint);
    payload.iter().for_each(|&b| w.u8(b));
    w.finish()
}

#[test]
fn inconsistent_payloads_are_refused() {
    let (shape, cfg, mut sys, blob) = small();
    let before = observe(&sys);
    assert_eq!(resealed(&blob, |_| {}), blob, "resealing an untouched payload gives the same blob");
    let vertices = sys.mesh().positions.len();
    // Payload: frame index, positions (count + 3 f32 each), poses (count + 2 f32 each), ...
    let first_position = 8 + 8;
    let first_pitch = first_position + 12 * vertices + 8;
    let put = |at: usize, x: f32| move |p: &mut Vec<u8>| p[at..at + 4].copy_from_slice(&x.to_le_bytes());
    let cases: Vec<(&str, Vec<u8>)> = vec![
        ("NaN position", resealed(&blob, put(first_position, f32::NAN))),
        ("infinite position", resealed(&blob, put(first_position + 4, f32::INFINITY))),
        ("pitch beyond its limit", resealed(&blob, put(first_pitch, 10.0))),
        ("NaN roll", resealed(&blob, put(first_pitch + 4, f32::NAN))),
        (
            "missing last byte",
            resealed(&blob, |p| {
                p.pop();
            }),
        ),
        ("trailing byte", resealed(&blob, |p| p.push(0))),
        ("wrong vertex count", resealed(&blob, |p| p[8] ^= 1)),
        ("last word overwritten", resealed(&blob, |p| p.iter_mut().rev().take(4).for_each(|b| *b = 0xFF))),
    ];
    for (what, bad) in &cases {
        let err = sys.load_state(bad).expect_err(what);
        assert_eq!(err.kind(), ErrorKind::InvalidState, "{what}: {}", err.message());
    }
    assert_unchanged(&mut sys, &before, &shape, &cfg);
}

/// A shared small system for the property tests, reset to its blob after
/// each case.
struct Fixture {
    sys: System,
    blob: Vec<u8>,
    rest: Vec<f32>,
}

fn fixture() -> &'static Mutex<Fixture> {
    static FIXTURE: OnceLock<Mutex<Fixture>> = OnceLock::new();
    FIXTURE.get_or_init(|| {
        let (shape, _, sys, blob) = small();
        Mutex::new(Fixture { sys, blob, rest: shape.positions })
    })
}

/// Loads `bytes`; when accepted, the system must go on working (two steps
/// and a validation, no panic). Then restores the fixture.
fn feed(bytes: &[u8]) -> Result<(), ErrorKind> {
    let mut f = fixture().lock().unwrap_or_else(|e| e.into_inner());
    let result = f.sys.load_state(bytes).map_err(|e| e.kind());
    if result.is_ok() {
        let rest = f.rest.clone();
        run(&mut f.sys, &rest, 3, 4);
        f.sys.validate();
    }
    let blob = f.blob.clone();
    f.sys.load_state(&blob).expect("the fixture's own blob loads");
    result
}

#[derive(Clone, Debug)]
enum Mutation {
    Set(usize, u8),
    Truncate(usize),
    Insert(usize, u8),
}

fn mutations() -> impl Strategy<Value = Vec<Mutation>> {
    let one = prop_oneof![
        4 => (any::<usize>(), any::<u8>()).prop_map(|(i, b)| Mutation::Set(i, b)),
        1 => any::<usize>().prop_map(Mutation::Truncate),
        1 => (any::<usize>(), any::<u8>()).prop_map(|(i, b)| Mutation::Insert(i, b)),
    ];
    prop::collection::vec(one, 1..6)
}

fn apply(bytes: &mut Vec<u8>, mutations: &[Mutation]) {
    for m in mutations {
        let n = bytes.len().max(1);
        match *m {
            Mutation::Set(i, b) if !bytes.is_empty() => bytes[i % n] = b,
            Mutation::Truncate(i) => bytes.truncate(i % n),
            Mutation::Insert(i, b) => bytes.insert(i % (bytes.len() + 1), b),
            _ => {}
        }
    }
}

proptest! {
    #![proptest_config(ProptestConfig { rng_seed: proptest::test_runner::RngSeed::Fixed(0x0070_6c75_6d61_6765), cases: 200, ..ProptestConfig::default() })]

    #[test]
    fn random_bytes_are_refused(bytes in prop::collection::vec(any::<u8>(), 0..2048)) {
        prop_assert_eq!(feed(&bytes), Err(ErrorKind::InvalidState));
    }

    #[test]
    fn mutated_blobs_are_refused(mutations in mutations()) {
        let mut bytes = fixture().lock().unwrap_or_else(|e| e.into_inner()).blob.clone();
        let original = bytes.clone();
        apply(&mut bytes, &mutations);
        let result = feed(&bytes);
        if bytes != original {
            prop_assert_eq!(result, Err(ErrorKind::InvalidState));
        }
    }

    /// Mutations past the integrity checks (fresh checksum): the payload
    /// checks alone must stop them, or the system must keep working.
    #[test]
    fn resealed_mutations_never_panic(mutations in mutations()) {
        let blob = fixture().lock().unwrap_or_else(|e| e.into_inner()).blob.clone();
        let bad = resealed(&blob, |p| apply(p, &mutations));
        if let Err(kind) = feed(&bad) {
            prop_assert_eq!(kind, ErrorKind::InvalidState);
        }
    }
}

/// The flamingo's flying clip with about 2000 feathers: resuming at frame
/// 4 of its real animation is exact; the blob size is reported.
#[test]
fn flamingo_resume_is_exact() {
    let Some((shape, clip)) = morph_clip("Flamingo.glb", 30.0) else { return };
    assert!(clip.len() >= 10, "the clip has {} frames", clip.len());
    let cfg = Config { flow_axis: glam::Vec3::NEG_Z, ..config(Mode::Incremental, true, 2000, 2) };
    let mut sys = create(&shape, &cfg);
    let steps = |sys: &mut System, frames: &[Vec<f32>]| -> Vec<Observed> {
        frames
            .iter()
            .map(|f| {
                sys.step(f).expect("step");
                observe(sys)
            })
            .collect()
    };
    steps(&mut sys, &clip[..4]);
    let blob = sys.save_state();
    eprintln!(
        "flamingo: {} feathers, {} welded vertices, state blob {} bytes ({:.0} bytes per feather)",
        sys.feather_count(),
        sys.mesh().positions.len(),
        blob.len(),
        blob.len() as f64 / sys.feather_count().max(1) as f64
    );
    let first = steps(&mut sys, &clip[4..10]);
    sys.load_state(&blob).unwrap();
    assert_eq!(steps(&mut sys, &clip[4..10]), first);
    let changes: usize = first.iter().map(|o| o.frame.priority_changes).sum();
    assert!(changes > 0, "the clip changes priorities");
}
