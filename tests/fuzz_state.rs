//! Fuzz target: state blobs handed to `plumage_system_load_state`. Real
//! blobs (three modes, several frames, plus blobs of other systems) are
//! mutated: bit flips, byte sets, truncation, insertion, splices of two
//! blobs, edited length fields; most are then resealed with a valid header
//! and checksum so that the payload parser itself is exercised. A refused
//! blob must leave the system exactly as it was (saved state byte-identical);
//! an accepted one must step and validate with finite feathers. No call may
//! panic.
//!
//! Short run: `cargo test --release --test fuzz_state`; long run:
//! `PLUMAGE_FUZZ_CASES=100000 cargo test --release --test fuzz_state -- --nocapture`.

mod common;

use common::fuzz::{self, Handle, Rng, Tally};
use common::shapes::{Shape, cylinder};
use plumage::ffi::*;
use plumage::snapshot::Writer;

const HEADER: usize = 28;
const TRAILER: usize = 8;

struct Fixture {
    shape: Shape,
    systems: Vec<Handle>,
    /// Per system: its own blobs (frames 0..4).
    blobs: Vec<Vec<Vec<u8>>>,
    /// Blobs of systems that are not the fixture's (another seed or mesh).
    foreign: Vec<Vec<u8>>,
}

fn wave(shape: &Shape, k: usize) -> Vec<f32> {
    shape.positions.chunks(3).flat_map(|p| [p[0] + 0.15 * (p[2] + 0.5 * k as f32).sin(), p[1], p[2]]).collect()
}

fn fixture() -> Fixture {
    let shape = cylinder(1.0, 2.5, 12, 6);
    let d = fuzz::desc(&shape.positions, &shape.indices);
    let mut tally = Tally::default();
    let (mut systems, mut blobs) = (Vec::new(), Vec::new());
    for mode in 0..3 {
        let cfg = PlumageConfig { threads: 1, mode, target_feathers: 60, ..fuzz::default_config() };
        let h = fuzz::create(&mut tally, Some(&cfg), &d).expect("fixture system");
        let mut own = vec![fuzz::save(h.0)];
        for k in 1..=4 {
            let f = wave(&shape, k);
            assert_eq!(unsafe { plumage_system_step(h.0, f.as_ptr(), f.len() / 3) }, PLUMAGE_STATUS_OK);
            own.push(fuzz::save(h.0));
        }
        systems.push(h);
        blobs.push(own);
    }
    let mut foreign = Vec::new();
    let other = cylinder(1.0, 2.5, 13, 6);
    for (s, cfg) in [
        (&shape, PlumageConfig { threads: 1, seed: 99, target_feathers: 60, ..fuzz::default_config() }),
        (&other, PlumageConfig { threads: 1, target_feathers: 60, ..fuzz::default_config() }),
    ] {
        let h = fuzz::create(&mut tally, Some(&cfg), &fuzz::desc(&s.positions, &s.indices)).unwrap();
        foreign.push(fuzz::save(h.0));
    }
    Fixture { shape, systems, blobs, foreign }
}

/// `blob`'s payload under a fresh header (same fingerprint) and checksum.
fn reseal(blob: &[u8]) -> Vec<u8> {
    if blob.len() < HEADER + TRAILER {
        return blob.to_vec();
    }
    let fingerprint = u64::from_le_bytes(blob[12..20].try_into().unwrap());
    let mut w = Writer::new(fingerprint);
    blob[HEADER..blob.len() - TRAILER].iter().for_each(|&b| w.u8(b));
    w.finish()
}

fn mutate(rng: &mut Rng, f: &Fixture, which: usize) -> Vec<u8> {
    let own = &f.blobs[which];
    let mut b = if rng.chance(0.05) { rng.pick(&f.foreign).clone() } else { rng.pick(own).clone() };
    for _ in 0..1 + rng.below(4) {
        let n = b.len().max(1);
        match rng.below(8) {
            0 | 1 => {
                let i = rng.below(n) % b.len().max(1);
                if !b.is_empty() {
                    b[i] ^= 1 << rng.below(8);
                }
            }
            2 => {
                if !b.is_empty() {
                    let i = rng.below(b.len());
                    b[i] = rng.u64() as u8;
                }
            }
            3 => b.truncate(rng.below(n)),
            4 => {
                let i = rng.below(b.len() + 1);
                b.insert(i, rng.u64() as u8);
            }
            5 => {
                // Splice: the tail of another blob.
                let system = rng.below(f.blobs.len());
                let other = rng.pick(&f.blobs[system]);
                let (i, j) = (rng.below(b.len() + 1), rng.below(other.len() + 1));
                b.truncate(i);
                b.extend_from_slice(&other[j..]);
            }
            6 => {
                // An aligned u64 (a length or count) set to a nasty value.
                if b.len() >= HEADER + 8 {
                    let i = HEADER + 8 * rng.below((b.len() - HEADER) / 8);
                    let small = rng.u64() % 4096;
                    let v = *rng.pick(&[0u64, 1, u64::MAX, u32::MAX as u64, 1 << 40, small]);
                    b[i..i + 8].copy_from_slice(&v.to_le_bytes());
                }
            }
            _ => {
                // An aligned f32 set to a nasty value.
                if b.len() >= HEADER + 4 {
                    let i = HEADER + 4 * rng.below((b.len() - HEADER) / 4);
                    b[i..i + 4].copy_from_slice(&rng.nasty_f32().to_le_bytes());
                }
            }
        }
    }
    if rng.chance(0.7) { reseal(&b) } else { b }
}

#[test]
fn fuzz_state() {
    let f = fixture();
    fuzz::run("fuzz_state", 3000, |rng, tally| {
        let which = rng.below(f.systems.len());
        let sys = f.systems[which].0;
        let blob = mutate(rng, &f, which);
        let before = fuzz::save(sys);
        let st = unsafe { plumage_system_load_state(sys, blob.as_ptr(), blob.len()) };
        tally.saw("load_state", st);
        if st != PLUMAGE_STATUS_OK {
            assert_eq!(st, PLUMAGE_STATUS_INVALID_STATE, "{}", fuzz::thread_or(sys));
            assert!(fuzz::save(sys) == before, "a refused blob changed the system");
        } else {
            fuzz::assert_finite(sys, "after load");
            let frame = wave(&f.shape, 5);
            tally.saw("step", unsafe { plumage_system_step(sys, frame.as_ptr(), frame.len() / 3) });
            fuzz::assert_finite(sys, "after a step from a loaded blob");
            let mut v = std::mem::MaybeUninit::<PlumageValidation>::zeroed();
            unsafe { (*v.as_mut_ptr()).struct_size = std::mem::size_of::<PlumageValidation>() as u32 };
            tally.saw("validate", unsafe { plumage_system_validate(sys, v.as_mut_ptr()) });
            // Back to a known frame for the next case.
            let own = &f.blobs[which][0];
            assert_eq!(unsafe { plumage_system_load_state(sys, own.as_ptr(), own.len()) }, PLUMAGE_STATUS_OK);
        }
    });
}
