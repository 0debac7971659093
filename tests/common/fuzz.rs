//! A seeded random harness for the fuzz targets (`tests/fuzz_*.rs`), on
//! stable Rust. Each case draws from its own generator, seeded from the run
//! seed and the case index, so that any case can be replayed alone.
//!
//! Environment:
//! - `PLUMAGE_FUZZ_CASES=N`: cases per target (default: a short run of a
//!   few seconds, the one `./scripts/test.sh` does);
//! - `PLUMAGE_FUZZ_SEED=S`: the run seed (default fixed, so the short run is
//!   the same every time);
//! - `PLUMAGE_FUZZ_CASE=I`: replay case I only (printed when a case fails);
//! - `PLUMAGE_FUZZ_SECONDS=T`: stop after the case running at T seconds
//!   (a long run that fits a time budget; the count run is printed).
//!
//! The C ABI is driven as a host would drive it, and every call's status
//! must be a named one other than `PANIC`: a caught panic is a crash found.

use plumage::ffi::*;
use std::collections::BTreeMap;
use std::ffi::CStr;
use std::panic::{AssertUnwindSafe, catch_unwind, resume_unwind};
use std::ptr::{null, null_mut};
use std::time::Instant;

/// splitmix64: small, fast, and the same on every platform.
pub struct Rng(u64);

impl Rng {
    pub fn new(seed: u64) -> Self {
        Self(seed)
    }
    pub fn u64(&mut self) -> u64 {
        self.0 = self.0.wrapping_add(0x9E37_79B9_7F4A_7C15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        z ^ (z >> 31)
    }
    /// Uniform in `0..n` (n > 0).
    pub fn below(&mut self, n: usize) -> usize {
        (self.u64() % n as u64) as usize
    }
    /// Uniform in [0, 1).
    pub fn unit(&mut self) -> f32 {
        (self.u64() >> 40) as f32 / (1u64 << 24) as f32
    }
    /// Uniform in [lo, hi).
    pub fn range(&mut self, lo: f32, hi: f32) -> f32 {
        lo + (hi - lo) * self.unit()
    }
    /// True with probability `p`.
    pub fn chance(&mut self, p: f32) -> bool {
        self.unit() < p
    }
    /// 10^x for x uniform in [lo, hi).
    pub fn log_uniform(&mut self, lo: f32, hi: f32) -> f32 {
        10f32.powf(self.range(lo, hi))
    }
    pub fn pick<'a, T>(&mut self, items: &'a [T]) -> &'a T {
        &items[self.below(items.len())]
    }
    /// A float that breaks things: NaN, infinities, zeros, extremes,
    /// denormals, or an ordinary value.
    pub fn nasty_f32(&mut self) -> f32 {
        match self.below(12) {
            0 => f32::NAN,
            1 => f32::INFINITY,
            2 => f32::NEG_INFINITY,
            3 => 0.0,
            4 => -0.0,
            5 => f32::MAX,
            6 => f32::MIN_POSITIVE / 4.0,
            7 => -self.log_uniform(-3.0, 3.0),
            8 => self.log_uniform(-38.0, 38.0),
            9 => 1e9 * self.range(0.9, 1.1),
            _ => self.range(-2.0, 2.0),
        }
    }
}

/// What a target reports about one case: the statuses it saw.
#[derive(Default)]
pub struct Tally {
    pub statuses: BTreeMap<String, u64>,
}

impl Tally {
    /// Records `status` of `call`; a `PANIC` is a crash found.
    pub fn saw(&mut self, call: &str, status: u32) {
        let n = status_name(status);
        assert_ne!(n, "UNKNOWN_STATUS", "{call} returned an unnamed status {status}");
        assert_ne!(status, PLUMAGE_STATUS_PANIC, "{call} panicked inside the library: {}", thread_or(null()));
        *self.statuses.entry(format!("{call}:{n}")).or_default() += 1;
    }
}

pub fn status_name(status: u32) -> String {
    unsafe { CStr::from_ptr(plumage_status_name(status)) }.to_string_lossy().into_owned()
}

/// The last error of `sys` (or of the thread when NULL).
pub fn thread_or(sys: *const PlumageSystem) -> String {
    let n = unsafe { plumage_system_last_error(sys, null_mut(), 0) };
    let mut buf = vec![0 as std::ffi::c_char; n.max(1)];
    unsafe { plumage_system_last_error(sys, buf.as_mut_ptr(), buf.len()) };
    unsafe { CStr::from_ptr(buf.as_ptr()) }.to_string_lossy().into_owned()
}

fn env_u64(name: &str) -> Option<u64> {
    std::env::var(name).ok().map(|v| v.trim().parse().unwrap_or_else(|_| panic!("{name}={v} is not a number")))
}

/// Peak resident set of this process, KiB (Linux; 0 elsewhere).
pub fn peak_rss_kib() -> u64 {
    std::fs::read_to_string("/proc/self/status")
        .ok()
        .and_then(|s| s.lines().find(|l| l.starts_with("VmHWM:")).map(|l| l.to_string()))
        .and_then(|l| l.split_whitespace().nth(1).and_then(|v| v.parse().ok()))
        .unwrap_or(0)
}

/// Runs `case` for every case index of the run (see the module notes) and
/// prints the tally: cases, statuses seen, the slowest case, peak memory.
pub fn run(target: &str, default_cases: u64, mut case: impl FnMut(&mut Rng, &mut Tally)) {
    let seed = env_u64("PLUMAGE_FUZZ_SEED").unwrap_or(0x0070_6C75_6D61_6765);
    let only = env_u64("PLUMAGE_FUZZ_CASE");
    let cases = env_u64("PLUMAGE_FUZZ_CASES").unwrap_or(default_cases).max(only.map_or(0, |o| o + 1));
    let mut tally = Tally::default();
    let start = Instant::now();
    let (mut slowest, mut slowest_case) = (0.0f64, 0u64);
    let mut ran = 0u64;
    let budget = env_u64("PLUMAGE_FUZZ_SECONDS").map(|s| s as f64);
    for i in 0..cases {
        if budget.is_some_and(|b| start.elapsed().as_secs_f64() > b) {
            break;
        }
        if only.is_some_and(|o| o != i) {
            continue;
        }
        let mut rng = Rng::new(seed ^ i.wrapping_mul(0xD1B5_4A32_D192_ED03));
        let rss_before = peak_rss_kib();
        let t = Instant::now();
        if let Err(payload) = catch_unwind(AssertUnwindSafe(|| case(&mut rng, &mut tally))) {
            eprintln!(
                "{target}: case {i} failed; replay it with PLUMAGE_FUZZ_SEED={seed} PLUMAGE_FUZZ_CASE={i} cargo test --release --test {target}"
            );
            resume_unwind(payload);
        }
        let s = t.elapsed().as_secs_f64();
        if s > 2.0 {
            eprintln!("{target}: case {i} took {s:.1} s");
        }
        // The process's peak only rises: name the case that raised it by
        // more than 256 MiB (a long run's peak otherwise names no input).
        let rss_after = peak_rss_kib();
        if rss_after > rss_before + (256 << 10) {
            eprintln!("{target}: case {i} raised the peak RSS from {} to {} MiB", rss_before >> 10, rss_after >> 10);
        }
        if s > slowest {
            (slowest, slowest_case) = (s, i);
        }
        ran += 1;
    }
    eprintln!(
        "{target}: {ran} cases, seed {seed}, {:.1} s, slowest case {slowest_case} ({:.3} s), peak RSS {} KiB",
        start.elapsed().as_secs_f64(),
        slowest,
        peak_rss_kib()
    );
    for (k, v) in &tally.statuses {
        eprintln!("  {k}: {v}");
    }
}

/// A mesh descriptor over `positions` and `indices` (counts from the slices).
pub fn desc(positions: &[f32], indices: &[u32]) -> PlumageMeshDesc {
    let mut d = std::mem::MaybeUninit::<PlumageMeshDesc>::uninit();
    unsafe { plumage_mesh_desc_init(d.as_mut_ptr()) };
    let mut d = unsafe { d.assume_init() };
    d.positions = positions.as_ptr();
    d.vertex_count = positions.len() / 3;
    d.indices = indices.as_ptr();
    d.triangle_count = indices.len() / 3;
    d
}

pub fn default_config() -> PlumageConfig {
    let mut c = std::mem::MaybeUninit::<PlumageConfig>::uninit();
    unsafe { plumage_config_init(c.as_mut_ptr()) };
    unsafe { c.assume_init() }
}

/// The saved state of `sys`.
pub fn save(sys: *const PlumageSystem) -> Vec<u8> {
    let mut n = 0usize;
    let st = unsafe { plumage_system_save_state(sys, null_mut(), 0, &mut n) };
    assert!(st == PLUMAGE_STATUS_BUFFER_TOO_SMALL || st == PLUMAGE_STATUS_OK, "save_state: {}", status_name(st));
    let mut buf = vec![0u8; n];
    let st = unsafe { plumage_system_save_state(sys, buf.as_mut_ptr(), n, &mut n) };
    assert_eq!(st, PLUMAGE_STATUS_OK, "save_state: {}", thread_or(sys));
    buf
}

/// The feather triangles of `sys` (18 floats a feather).
pub fn triangles(sys: *const PlumageSystem) -> Vec<f32> {
    let mut n = 0usize;
    unsafe { plumage_system_feather_triangles(sys, null_mut(), 0, &mut n) };
    let mut buf = vec![0f32; n];
    let st = unsafe { plumage_system_feather_triangles(sys, buf.as_mut_ptr(), n, &mut n) };
    assert_eq!(st, PLUMAGE_STATUS_OK, "feather_triangles: {}", thread_or(sys));
    buf
}

/// Everything a host reads of a live system must be finite.
pub fn assert_finite(sys: *const PlumageSystem, what: &str) {
    let t = triangles(sys);
    if let Some(k) = t.iter().position(|x| !x.is_finite()) {
        panic!("{what}: feather triangle coordinate {k} of {} is {}", t.len(), t[k]);
    }
}

/// Owns a system handle; destroys it on drop (also when a check fails).
pub struct Handle(pub *mut PlumageSystem);

impl Drop for Handle {
    fn drop(&mut self) {
        unsafe { plumage_system_destroy(self.0) };
    }
}

/// Creates a system, recording the status; `None` when refused (then `*out`
/// must have stayed NULL).
pub fn create(tally: &mut Tally, cfg: Option<&PlumageConfig>, d: &PlumageMeshDesc) -> Option<Handle> {
    let mut out: *mut PlumageSystem = std::ptr::dangling_mut();
    let st = unsafe { plumage_system_create(cfg.map_or(null(), |c| c as *const _), d, &mut out) };
    tally.saw("create", st);
    if st == PLUMAGE_STATUS_OK {
        assert!(!out.is_null());
        Some(Handle(out))
    } else {
        assert!(out.is_null(), "a refused create must leave *out NULL");
        assert!(!thread_or(null()).is_empty(), "a refused create leaves a message");
        None
    }
}
