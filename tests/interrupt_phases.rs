//! Progress and interruption in every phase, through the C ABI as a host
//! uses them: the config's progress callback stops a call inside one phase
//! (create: preparing, sampling, ordering, adjusting; step and evaluate:
//! ordering, adjusting; validate: validating). The call must return
//! `PLUMAGE_STATUS_INTERRUPTED`, and leave the system exactly as it was:
//! its saved state hashes the same before and after, and the next call
//! gives what it would have given had the stopped one never been made.
//! Save and load are not interruptible: they are linear in the blob
//! (figures printed by `save_and_load_are_linear_in_the_blob`).

mod common;

use common::fuzz::{Handle, default_config, desc, save, status_name, thread_or};
use common::shapes::{Shape, grid};
use plumage::ffi::*;
use std::collections::hash_map::DefaultHasher;
use std::ffi::c_void;
use std::hash::{Hash, Hasher};
use std::ptr::null;
use std::sync::Mutex;
use std::time::Instant;

/// What the callback sees and when it stops.
struct Stopper {
    /// Stop at the first report of this phase (`u32::MAX`: never).
    phase: u32,
    /// Only at a report strictly inside the phase (0 < fraction < 1).
    inside: bool,
    seen: Mutex<Vec<(u32, f32)>>,
    stopped_at: Mutex<Option<(u32, f32)>>,
}

impl Stopper {
    fn new(phase: u32, inside: bool) -> Box<Self> {
        Box::new(Self { phase, inside, seen: Mutex::new(Vec::new()), stopped_at: Mutex::new(None) })
    }
    fn rearm(&mut self, phase: u32, inside: bool) {
        self.phase = phase;
        self.inside = inside;
        self.seen.lock().unwrap().clear();
        *self.stopped_at.lock().unwrap() = None;
    }
    fn stopped_at(&self) -> Option<(u32, f32)> {
        *self.stopped_at.lock().unwrap()
    }
}

unsafe extern "C" fn callback(user: *mut c_void, phase: u32, fraction: f32) -> i32 {
    let s = unsafe { &*(user as *const Stopper) };
    s.seen.lock().unwrap().push((phase, fraction));
    let hit = phase == s.phase && (!s.inside || (fraction > 0.0 && fraction < 1.0));
    if hit {
        *s.stopped_at.lock().unwrap() = Some((phase, fraction));
    }
    i32::from(hit)
}

fn hash(bytes: &[u8]) -> u64 {
    let mut h = DefaultHasher::new();
    bytes.hash(&mut h);
    h.finish()
}

/// A plate of 4 608 triangles: enough work for reports inside each phase.
fn plate() -> Shape {
    grid(12.0, 12.0, 48, 48, 0.0, true)
}

fn wave(shape: &Shape, t: f32) -> Vec<f32> {
    shape.positions.chunks(3).flat_map(|p| [p[0], p[1], 0.5 * (0.7 * p[0] + t).sin()]).collect()
}

fn config(stopper: Option<&Stopper>, threads: u32) -> PlumageConfig {
    let mut c = default_config();
    c.target_feathers = 3000;
    c.threads = threads;
    // Every feather whose surroundings moved at all is readjusted (not
    // only those that drifted past the default 17°), so a step's
    // adjustment lasts well past the progress reports' 1 ms throttle and a
    // report falls strictly inside it: with the default, a frame of the
    // wave readjusted so few feathers that it sometimes did not.
    c.drift_tolerance = 0.0;
    if let Some(s) = stopper {
        c.progress = Some(callback);
        c.progress_user_data = s as *const Stopper as *mut c_void;
    }
    c
}

fn create(cfg: &PlumageConfig, shape: &Shape) -> (u32, *mut PlumageSystem) {
    let d = desc(&shape.positions, &shape.indices);
    let mut out: *mut PlumageSystem = std::ptr::dangling_mut();
    let st = unsafe { plumage_system_create(cfg, &d, &mut out) };
    (st, out)
}

const PHASE_NAMES: [&str; 5] = ["preparing", "sampling", "ordering", "adjusting", "validating"];

#[test]
fn create_stopped_in_each_phase_creates_nothing() {
    let shape = plate();
    // Preparing is short (welding and the surface): stopped at its first
    // report. The others are stopped strictly inside.
    for (phase, inside) in [
        (PLUMAGE_PHASE_PREPARING, false),
        (PLUMAGE_PHASE_SAMPLING, true),
        (PLUMAGE_PHASE_ORDERING, false),
        (PLUMAGE_PHASE_ADJUSTING, true),
    ] {
        let stopper = Stopper::new(phase, inside);
        let (st, out) = create(&config(Some(&stopper), 1), &shape);
        let name = PHASE_NAMES[phase as usize];
        assert_eq!(
            st,
            PLUMAGE_STATUS_INTERRUPTED,
            "create stopped in {name}: {} ({})",
            status_name(st),
            thread_or(null())
        );
        assert!(out.is_null(), "a stopped create leaves *out NULL");
        let (p, f) = stopper.stopped_at().expect("the callback stopped it");
        assert_eq!(p, phase);
        println!("create stopped in {name} at {f:.3}");
        let seen = stopper.seen.lock().unwrap();
        assert!(seen.iter().all(|&(p, f)| p <= PLUMAGE_PHASE_VALIDATING && (0.0..=1.0).contains(&f)));
    }
}

/// Step or evaluate stopped inside `phase`: interrupted, the saved state's
/// hash unchanged, the same call then gives the twin's bytes.
fn frame_call_stopped(evaluate: bool, threads: u32) {
    let shape = plate();
    let mut stopper = Stopper::new(u32::MAX, false);
    let (st, sys) = create(&config(Some(&stopper), threads), &shape);
    assert_eq!(st, PLUMAGE_STATUS_OK, "{}", thread_or(null()));
    let sys = Handle(sys);
    let (st, twin) = create(&config(None, threads), &shape);
    assert_eq!(st, PLUMAGE_STATUS_OK);
    let twin = Handle(twin);
    let call = |h: *mut PlumageSystem, f: &[f32]| unsafe {
        if evaluate {
            plumage_system_evaluate(h, f.as_ptr(), f.len() / 3)
        } else {
            plumage_system_step(h, f.as_ptr(), f.len() / 3)
        }
    };
    let what = if evaluate { "evaluate" } else { "step" };
    for (k, (phase, inside)) in
        [(PLUMAGE_PHASE_ORDERING, false), (PLUMAGE_PHASE_ADJUSTING, true)].into_iter().enumerate()
    {
        let frame = wave(&shape, 0.4 * (k + 1) as f32);
        let before = hash(&save(sys.0));
        assert_eq!(before, hash(&save(twin.0)), "{what}: in step with the twin before frame {k}");
        stopper.rearm(phase, inside);
        let st = call(sys.0, &frame);
        let name = PHASE_NAMES[phase as usize];
        assert_eq!(
            st,
            PLUMAGE_STATUS_INTERRUPTED,
            "{what} stopped in {name}: {} (reports seen: {:?})",
            status_name(st),
            stopper.seen.lock().unwrap()
        );
        assert_eq!(stopper.stopped_at().map(|s| s.0), Some(phase));
        assert_eq!(hash(&save(sys.0)), before, "{what} stopped in {name}: the saved state is unchanged");
        stopper.rearm(u32::MAX, false);
        assert_eq!(call(sys.0, &frame), PLUMAGE_STATUS_OK, "{}", thread_or(sys.0));
        assert_eq!(call(twin.0, &frame), PLUMAGE_STATUS_OK);
        assert_eq!(save(sys.0), save(twin.0), "{what} after a stop in {name}: as if never stopped");
    }
}

#[test]
fn step_stopped_in_each_phase_changes_nothing() {
    frame_call_stopped(false, 1);
    frame_call_stopped(false, 2);
}

#[test]
fn evaluate_stopped_in_each_phase_changes_nothing() {
    frame_call_stopped(true, 1);
}

#[test]
fn validate_stopped_inside_changes_nothing() {
    let shape = plate();
    let mut stopper = Stopper::new(u32::MAX, false);
    let (st, sys) = create(&config(Some(&stopper), 2), &shape);
    assert_eq!(st, PLUMAGE_STATUS_OK, "{}", thread_or(null()));
    let sys = Handle(sys);
    let before = hash(&save(sys.0));
    let mut v = std::mem::MaybeUninit::<PlumageValidation>::uninit();
    unsafe { plumage_validation_init(v.as_mut_ptr()) };
    let mut v = unsafe { v.assume_init() };
    v.coverage = -7.0;
    stopper.rearm(PLUMAGE_PHASE_VALIDATING, true);
    let st = unsafe { plumage_system_validate(sys.0, &mut v) };
    assert_eq!(st, PLUMAGE_STATUS_INTERRUPTED, "{} ({})", status_name(st), thread_or(sys.0));
    assert_eq!(v.coverage, -7.0, "a stopped validation writes no result");
    assert_eq!(hash(&save(sys.0)), before);
    // Unstopped, it reports its phase and gives the result.
    stopper.rearm(u32::MAX, false);
    assert_eq!(unsafe { plumage_system_validate(sys.0, &mut v) }, PLUMAGE_STATUS_OK);
    assert!(v.coverage > 0.5, "coverage {}", v.coverage);
    let seen = stopper.seen.lock().unwrap();
    assert!(seen.iter().any(|&(p, _)| p == PLUMAGE_PHASE_VALIDATING), "validate reports its phase");
    assert_eq!(hash(&save(sys.0)), before);
}

#[test]
fn save_and_load_are_linear_in_the_blob() {
    // Not interruptible: time and memory in proportion to the blob, printed
    // here (no callback is called by either).
    let shape = plate();
    let stopper = Stopper::new(u32::MAX, false);
    let (st, sys) = create(&config(Some(&stopper), 1), &shape);
    assert_eq!(st, PLUMAGE_STATUS_OK);
    let sys = Handle(sys);
    stopper.seen.lock().unwrap().clear();
    let t = Instant::now();
    let blob = save(sys.0);
    let save_s = t.elapsed().as_secs_f64();
    let t = Instant::now();
    let st = unsafe { plumage_system_load_state(sys.0, blob.as_ptr(), blob.len()) };
    let load_s = t.elapsed().as_secs_f64();
    assert_eq!(st, PLUMAGE_STATUS_OK, "{}", thread_or(sys.0));
    assert_eq!(save(sys.0), blob);
    assert!(stopper.seen.lock().unwrap().is_empty(), "save and load report nothing");
    let mut n = 0usize;
    unsafe { plumage_system_feather_count(sys.0, &mut n) };
    println!("{n} feathers: blob {} bytes, save {save_s:.4} s, load {load_s:.4} s", blob.len());
}
