//! The busy guard (issue 36): a call that overlaps a mutating call on the
//! same system (from another thread, or from the running call's own
//! progress callback) returns `PLUMAGE_STATUS_BUSY` without touching the
//! system, destroy included; read-only calls run side by side.

mod common;

use common::shapes::swim_body;
use plumage::ffi::*;
use std::ffi::c_void;
use std::sync::atomic::{AtomicBool, AtomicU32, AtomicUsize, Ordering};
use std::sync::{Arc, Barrier};

/// What the progress callback does once, from inside the running call.
struct Probe {
    sys: AtomicUsize,
    /// Statuses seen by the calls made from inside (or beside) the step.
    step: AtomicU32,
    destroy: AtomicU32,
    count: AtomicU32,
    /// When set, the callback waits for `other` to finish its calls.
    other: Option<Arc<Barrier>>,
    fired: AtomicBool,
}

unsafe extern "C" fn probe_callback(user: *mut c_void, _phase: u32, _fraction: f32) -> i32 {
    let probe = unsafe { &*(user as *const Probe) };
    let sys = probe.sys.load(Ordering::SeqCst) as *mut PlumageSystem;
    if sys.is_null() || probe.fired.swap(true, Ordering::SeqCst) {
        return 0;
    }
    match &probe.other {
        // The other thread makes its calls while this one is inside.
        Some(barrier) => {
            barrier.wait();
            barrier.wait();
        }
        None => unsafe {
            let pos = [0.0f32; 3];
            probe.step.store(plumage_system_step(sys, pos.as_ptr(), 1), Ordering::SeqCst);
            let mut n = 0usize;
            probe.count.store(plumage_system_feather_count(sys, &mut n), Ordering::SeqCst);
            probe.destroy.store(plumage_system_destroy(sys), Ordering::SeqCst);
        },
    }
    0
}

fn create(probe: &Probe, threads: u32) -> (*mut PlumageSystem, Vec<f32>) {
    let shape = swim_body(24, 32);
    let mut cfg = std::mem::MaybeUninit::<PlumageConfig>::uninit();
    unsafe { plumage_config_init(cfg.as_mut_ptr()) };
    let mut cfg = unsafe { cfg.assume_init() };
    cfg.target_feathers = 300;
    cfg.threads = threads;
    cfg.progress = Some(probe_callback);
    cfg.progress_user_data = probe as *const Probe as *mut c_void;
    let d = common::fuzz::desc(&shape.positions, &shape.indices);
    let mut sys = std::ptr::null_mut();
    assert_eq!(unsafe { plumage_system_create(&cfg, &d, &mut sys) }, PLUMAGE_STATUS_OK);
    (sys, shape.positions)
}

fn new_probe(other: Option<Arc<Barrier>>) -> Probe {
    Probe {
        sys: AtomicUsize::new(0),
        step: AtomicU32::new(u32::MAX),
        destroy: AtomicU32::new(u32::MAX),
        count: AtomicU32::new(u32::MAX),
        other,
        fired: AtomicBool::new(false),
    }
}

fn last_error(sys: *const PlumageSystem) -> String {
    let mut buf = vec![0u8; 512];
    unsafe { plumage_system_last_error(sys, buf.as_mut_ptr() as *mut _, buf.len()) };
    String::from_utf8_lossy(&buf[..buf.iter().position(|&b| b == 0).unwrap_or(0)]).into_owned()
}

#[test]
fn calls_from_the_running_calls_callback_are_refused() {
    for threads in [1, 2] {
        let probe = new_probe(None);
        let (sys, rest) = create(&probe, threads);
        let before = common::fuzz::save(sys);
        probe.sys.store(sys as usize, Ordering::SeqCst);
        let moved: Vec<f32> = rest.iter().map(|x| x * 1.01).collect();
        assert_eq!(unsafe { plumage_system_step(sys, moved.as_ptr(), moved.len() / 3) }, PLUMAGE_STATUS_OK);
        assert!(probe.fired.load(Ordering::SeqCst), "the callback ran");
        assert_eq!(probe.step.load(Ordering::SeqCst), PLUMAGE_STATUS_BUSY, "step inside step");
        assert_eq!(probe.count.load(Ordering::SeqCst), PLUMAGE_STATUS_BUSY, "a query inside step");
        assert_eq!(probe.destroy.load(Ordering::SeqCst), PLUMAGE_STATUS_BUSY, "destroy inside step");
        // The system lived through it and stepped; after the call, it takes calls again.
        assert_ne!(common::fuzz::save(sys), before);
        probe.sys.store(0, Ordering::SeqCst);
        let mut n = 0usize;
        assert_eq!(unsafe { plumage_system_feather_count(sys, &mut n) }, PLUMAGE_STATUS_OK);
        assert!(n > 0);
        assert_eq!(unsafe { plumage_system_destroy(sys) }, PLUMAGE_STATUS_OK);
    }
}

#[test]
fn another_thread_is_refused_while_a_step_runs() {
    let barrier = Arc::new(Barrier::new(2));
    let probe = new_probe(Some(barrier.clone()));
    let (sys, rest) = create(&probe, 2);
    probe.sys.store(sys as usize, Ordering::SeqCst);
    let addr = sys as usize;
    let other = std::thread::spawn(move || {
        let sys = addr as *mut PlumageSystem;
        barrier.wait();
        let pos = [0.0f32; 3];
        let mut n = 0usize;
        let statuses = unsafe {
            [
                plumage_system_step(sys, pos.as_ptr(), 1),
                plumage_system_evaluate(sys, pos.as_ptr(), 1),
                plumage_system_feather_count(sys, &mut n),
                plumage_system_destroy(sys),
            ]
        };
        let message = last_error(sys);
        barrier.wait();
        (statuses, message)
    });
    let moved: Vec<f32> = rest.iter().map(|x| x * 0.99).collect();
    assert_eq!(unsafe { plumage_system_step(sys, moved.as_ptr(), moved.len() / 3) }, PLUMAGE_STATUS_OK);
    let (statuses, message) = other.join().unwrap();
    assert_eq!(statuses, [PLUMAGE_STATUS_BUSY; 4]);
    assert!(message.contains("another call is running"), "{message}");
    let name = unsafe { std::ffi::CStr::from_ptr(plumage_status_name(PLUMAGE_STATUS_BUSY)) };
    assert_eq!(name.to_str().unwrap(), "BUSY");
    probe.sys.store(0, Ordering::SeqCst);
    assert_eq!(unsafe { plumage_system_destroy(sys) }, PLUMAGE_STATUS_OK);
}

#[test]
fn read_only_calls_run_side_by_side() {
    let probe = new_probe(None);
    let (sys, _) = create(&probe, 1);
    let addr = sys as usize;
    let readers: Vec<_> = (0..4)
        .map(|_| {
            std::thread::spawn(move || {
                let sys = addr as *const PlumageSystem;
                (0..2000)
                    .map(|_| {
                        let mut n = 0usize;
                        unsafe { plumage_system_feather_count(sys, &mut n) }
                    })
                    .filter(|&s| s != PLUMAGE_STATUS_OK)
                    .count()
            })
        })
        .collect();
    let refused: usize = readers.into_iter().map(|r| r.join().unwrap()).sum();
    assert_eq!(refused, 0, "read-only calls refused one another");
    assert_eq!(unsafe { plumage_system_destroy(sys) }, PLUMAGE_STATUS_OK);
}
