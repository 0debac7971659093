//! The last-error rule (issue 32), over the whole ABI: the message of a
//! handle (or, without a usable handle, of the thread) describes the most
//! recent call. Each row makes its call fail, then succeed: after the
//! failure the message is set, after the success it is empty, whatever
//! came before (a refused size query included).

mod common;

use common::shapes::swim_body;
use plumage::ffi::*;
use std::ptr::{null, null_mut};

fn message(sys: *const PlumageSystem) -> String {
    let mut buf = vec![0u8; 1024];
    unsafe { plumage_system_last_error(sys, buf.as_mut_ptr() as *mut _, buf.len()) };
    String::from_utf8_lossy(&buf[..buf.iter().position(|&b| b == 0).unwrap_or(0)]).into_owned()
}

type Call<'a> = Box<dyn Fn(*mut PlumageSystem) -> u32 + 'a>;

/// One entry point: a call that fails and one that succeeds.
struct Row<'a> {
    name: &'static str,
    fails: Call<'a>,
    succeeds: Call<'a>,
}

fn row<'a>(
    name: &'static str,
    fails: impl Fn(*mut PlumageSystem) -> u32 + 'a,
    succeeds: impl Fn(*mut PlumageSystem) -> u32 + 'a,
) -> Row<'a> {
    Row { name, fails: Box::new(fails), succeeds: Box::new(succeeds) }
}

fn stats<T: 'static>(
    init: unsafe extern "C" fn(*mut T),
    get: unsafe extern "C" fn(*const PlumageSystem, *mut T) -> u32,
) -> (Call<'static>, Call<'static>) {
    let fails: Call = Box::new(move |sys| unsafe {
        let mut out = std::mem::MaybeUninit::<T>::zeroed();
        get(sys, out.as_mut_ptr()) // struct_size 0: refused
    });
    let succeeds: Call = Box::new(move |sys| unsafe {
        let mut out = std::mem::MaybeUninit::<T>::zeroed();
        init(out.as_mut_ptr());
        get(sys, out.as_mut_ptr())
    });
    (fails, succeeds)
}

#[test]
fn every_call_sets_the_message_on_failure_and_empties_it_on_success() {
    let shape = swim_body(24, 32);
    let d = common::fuzz::desc(&shape.positions, &shape.indices);
    let mut cfg = std::mem::MaybeUninit::<PlumageConfig>::uninit();
    unsafe { plumage_config_init(cfg.as_mut_ptr()) };
    let mut cfg = unsafe { cfg.assume_init() };
    cfg.target_feathers = 200;
    cfg.threads = 1;
    cfg.checkpoint_interval = 1;
    let mut sys = null_mut();
    assert_eq!(unsafe { plumage_system_create(&cfg, &d, &mut sys) }, PLUMAGE_STATUS_OK);
    let frame: Vec<f32> = shape.positions.iter().map(|x| x * 1.01).collect();
    let n = shape.positions.len() / 3;
    let mut state_len = 0usize;
    unsafe { plumage_system_save_state(sys, null_mut(), 0, &mut state_len) };
    let mut state = vec![0u8; state_len];
    assert_eq!(
        unsafe { plumage_system_save_state(sys, state.as_mut_ptr(), state_len, &mut state_len) },
        PLUMAGE_STATUS_OK
    );
    let state = &state;
    let frame = &frame;

    let mut rows = vec![
        row(
            "step",
            |s| unsafe { plumage_system_step(s, frame.as_ptr(), n - 1) },
            |s| unsafe { plumage_system_step(s, frame.as_ptr(), n) },
        ),
        row(
            "evaluate",
            |s| unsafe { plumage_system_evaluate(s, null(), n) },
            |s| unsafe { plumage_system_evaluate(s, frame.as_ptr(), n) },
        ),
        row(
            "feather_count",
            |s| unsafe { plumage_system_feather_count(s, null_mut()) },
            |s| unsafe { plumage_system_feather_count(s, &mut 0) },
        ),
        row(
            "vertex_count",
            |s| unsafe { plumage_system_vertex_count(s, null_mut()) },
            |s| unsafe { plumage_system_vertex_count(s, &mut 0) },
        ),
        row(
            "feathers",
            |s| unsafe { plumage_system_feathers(s, null_mut(), 0, &mut 0) },
            |s| unsafe {
                let mut len = 0;
                plumage_system_feathers(s, null_mut(), 0, &mut len);
                let mut buf = vec![PlumageFeather::default(); len];
                plumage_system_feathers(s, buf.as_mut_ptr(), len, &mut len)
            },
        ),
        row(
            "feather_triangles",
            |s| unsafe { plumage_system_feather_triangles(s, null_mut(), 0, &mut 0) },
            |s| unsafe {
                let mut len = 0;
                plumage_system_feather_triangles(s, null_mut(), 0, &mut len);
                let mut buf = vec![0f32; len];
                plumage_system_feather_triangles(s, buf.as_mut_ptr(), len, &mut len)
            },
        ),
        row(
            "feather_geometry",
            |s| unsafe {
                let mut g = std::mem::MaybeUninit::<PlumageFeatherGeometry>::zeroed();
                plumage_system_feather_geometry(s, g.as_mut_ptr())
            },
            |s| unsafe {
                let mut g = std::mem::MaybeUninit::<PlumageFeatherGeometry>::zeroed();
                plumage_feather_geometry_init(g.as_mut_ptr());
                plumage_system_feather_geometry(s, g.as_mut_ptr())
            },
        ),
        row(
            "feather_instances",
            |s| unsafe { plumage_system_feather_instances(s, null_mut(), 0, &mut 0) },
            |s| unsafe {
                let mut len = 0;
                plumage_system_feather_instances(s, null_mut(), 0, &mut len);
                let mut buf = vec![std::mem::zeroed::<PlumageFeatherInstance>(); len];
                plumage_system_feather_instances(s, buf.as_mut_ptr(), len, &mut len)
            },
        ),
        row(
            "feather_template",
            |s| unsafe {
                let mut t = std::mem::MaybeUninit::<PlumageFeatherTemplate>::zeroed();
                plumage_system_feather_template(s, t.as_mut_ptr())
            },
            |s| unsafe {
                let mut t = std::mem::MaybeUninit::<PlumageFeatherTemplate>::zeroed();
                plumage_feather_template_init(t.as_mut_ptr());
                plumage_system_feather_template(s, t.as_mut_ptr())
            },
        ),
        row(
            "changed_feathers",
            |s| unsafe { plumage_system_changed_feathers(s, null_mut(), 0, null_mut(), null_mut()) },
            |s| unsafe {
                let (mut len, mut all) = (0usize, 0u32);
                plumage_system_changed_feathers(s, null_mut(), 0, &mut len, &mut all);
                let mut buf = vec![0u32; len];
                plumage_system_changed_feathers(s, buf.as_mut_ptr(), len, &mut len, &mut all)
            },
        ),
        row(
            "validate_part",
            |s| unsafe {
                let mut v = std::mem::MaybeUninit::<PlumageValidation>::zeroed();
                plumage_validation_init(v.as_mut_ptr());
                plumage_system_validate_part(s, usize::MAX, 1, v.as_mut_ptr())
            },
            |s| unsafe {
                let mut v = std::mem::MaybeUninit::<PlumageValidation>::zeroed();
                plumage_validation_init(v.as_mut_ptr());
                plumage_system_validate_part(s, 0, 10, v.as_mut_ptr())
            },
        ),
        row(
            "part_stats",
            |s| unsafe {
                let mut v = std::mem::MaybeUninit::<PlumagePartStats>::zeroed();
                plumage_part_stats_init(v.as_mut_ptr());
                plumage_system_part_stats(s, usize::MAX, 1, v.as_mut_ptr())
            },
            |s| unsafe {
                let mut v = std::mem::MaybeUninit::<PlumagePartStats>::zeroed();
                plumage_part_stats_init(v.as_mut_ptr());
                plumage_system_part_stats(s, 0, 10, v.as_mut_ptr())
            },
        ),
        row(
            "save_state",
            |s| unsafe { plumage_system_save_state(s, null_mut(), 0, &mut 0) },
            |s| unsafe {
                let mut len = 0;
                plumage_system_save_state(s, null_mut(), 0, &mut len);
                let mut buf = vec![0u8; len];
                plumage_system_save_state(s, buf.as_mut_ptr(), len, &mut len)
            },
        ),
        row(
            "load_state",
            |s| unsafe { plumage_system_load_state(s, state.as_ptr(), state.len() / 2) },
            |s| unsafe { plumage_system_load_state(s, state.as_ptr(), state.len()) },
        ),
        row(
            "seek",
            |s| unsafe { plumage_system_seek(s, 0, null_mut()) },
            |s| unsafe { plumage_system_seek(s, 0, &mut 0) },
        ),
    ];
    for (name, (fails, succeeds)) in [
        ("sampling_stats", stats(plumage_sampling_stats_init, plumage_system_sampling_stats)),
        ("ordering_stats", stats(plumage_ordering_stats_init, plumage_system_ordering_stats)),
        ("frame_stats", stats(plumage_frame_stats_init, plumage_system_frame_stats)),
        ("memory", stats(plumage_memory_init, plumage_system_memory)),
        ("validate", stats(plumage_validation_init, plumage_system_validate)),
    ] {
        rows.push(Row { name, fails, succeeds });
    }

    let mut failures = Vec::new();
    for r in &rows {
        let status = (r.fails)(sys);
        let after_failure = message(sys);
        if status == PLUMAGE_STATUS_OK || after_failure.is_empty() {
            failures.push(format!("{}: failing call gave {status} with message {after_failure:?}", r.name));
        }
        let status = (r.succeeds)(sys);
        let after_success = message(sys);
        if status != PLUMAGE_STATUS_OK || !after_success.is_empty() {
            failures.push(format!("{}: succeeding call gave {status} and left {after_success:?}", r.name));
        }
        // The reader changes nothing: asked twice, the same (empty) answer.
        assert_eq!(message(sys), after_success);
    }

    // Without a usable system: the calling thread's message.
    let status = unsafe { plumage_system_create(&cfg, null(), &mut null_mut()) };
    assert_ne!(status, PLUMAGE_STATUS_OK);
    assert!(!message(null()).is_empty(), "a refused create sets the thread's message");
    let mut second = null_mut();
    assert_eq!(unsafe { plumage_system_create(&cfg, &d, &mut second) }, PLUMAGE_STATUS_OK);
    assert_eq!(message(null()), "", "a successful create empties it");
    assert_eq!(unsafe { plumage_system_feather_count(null(), &mut 0) }, PLUMAGE_STATUS_NULL_POINTER);
    assert!(message(null()).contains("NULL"));
    let mut preset = std::mem::MaybeUninit::<PlumageConfig>::uninit();
    assert_eq!(unsafe { plumage_config_init_preset(preset.as_mut_ptr(), PLUMAGE_PRESET_KITE) }, PLUMAGE_STATUS_OK);
    assert_eq!(message(null()), "", "the preset init is a call without a system too");
    assert_eq!(unsafe { plumage_system_destroy(second) }, PLUMAGE_STATUS_OK);

    assert!(failures.is_empty(), "{}", failures.join("\n"));
    // A row for every system call of the header but create, destroy and
    // last_error: a new entry point fails this until it has its row.
    let header = std::fs::read_to_string(concat!(env!("CARGO_MANIFEST_DIR"), "/include/plumage.h")).unwrap();
    let mut calls: Vec<&str> = header
        .split(|c: char| !(c.is_alphanumeric() || c == '_'))
        .filter(|w| w.starts_with("plumage_system_"))
        .filter(|w| !["plumage_system_create", "plumage_system_destroy", "plumage_system_last_error"].contains(w))
        .filter(|w| header.contains(&format!("{w}(")))
        .collect();
    calls.sort_unstable();
    calls.dedup();
    let mut named: Vec<String> = rows.iter().map(|r| format!("plumage_system_{}", r.name)).collect();
    named.sort_unstable();
    assert_eq!(calls, named, "a row per system call besides create, destroy and last_error");
    assert_eq!(unsafe { plumage_system_destroy(sys) }, PLUMAGE_STATUS_OK);
}
