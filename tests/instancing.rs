//! Feathers for instancing (issue #32): the packed records and the template
//! card reconstruct the copied-out geometry, read through the C ABI and
//! expanded here the way `shaders/feather_instance.vert` does it, for 1 to
//! 4 shaft segments on the built-in swimmer and the Flamingo after a few
//! animated steps; and the list of changed feathers names every feather
//! whose record or triangles moved, so that the others are bit for bit as
//! before.

mod common;

use common::shapes::{Shape, swim_body, swim_pose};
use plumage::ffi::*;
use plumage::{Config, MeshInput, Preset, System};
use std::ptr::{null, null_mut};

const _: () = assert!(std::mem::size_of::<PlumageFeatherInstance>() <= 40);

/// A lighter built-in swimmer than the host's 96 × 32.
const RINGS: usize = 48;
const SEGMENTS: usize = 16;
const FPS: f64 = 30.0;

fn error_of(sys: *const PlumageSystem) -> String {
    let n = unsafe { plumage_system_last_error(sys, null_mut(), 0) };
    let mut buf = vec![0 as std::ffi::c_char; n.max(1)];
    unsafe { plumage_system_last_error(sys, buf.as_mut_ptr(), buf.len()) };
    unsafe { std::ffi::CStr::from_ptr(buf.as_ptr()) }.to_string_lossy().into_owned()
}

fn ok(status: u32, sys: *const PlumageSystem, call: &str) {
    assert_eq!(status, PLUMAGE_STATUS_OK, "{call}: {}", error_of(sys));
}

/// A system through the C ABI: `segments` shaft segments, the rest of the
/// defaults (`flow_source` as the host's built-in model when given).
fn create(body: &Shape, feathers: u32, segments: u32, flow_source: Option<[f32; 3]>) -> *mut PlumageSystem {
    let mut cfg = std::mem::MaybeUninit::<PlumageConfig>::uninit();
    unsafe { plumage_config_init(cfg.as_mut_ptr()) };
    let mut cfg = unsafe { cfg.assume_init() };
    cfg.target_feathers = feathers;
    cfg.shaft_segments = segments;
    cfg.threads = 2;
    cfg.seed = 7;
    if let Some(at) = flow_source {
        cfg.flow_source = at;
        cfg.flow_source_enabled = 1;
    }
    let mut d = std::mem::MaybeUninit::<PlumageMeshDesc>::uninit();
    unsafe { plumage_mesh_desc_init(d.as_mut_ptr()) };
    let mut d = unsafe { d.assume_init() };
    d.positions = body.positions.as_ptr();
    d.vertex_count = body.positions.len() / 3;
    d.indices = body.indices.as_ptr();
    d.triangle_count = body.indices.len() / 3;
    let mut sys = null_mut();
    ok(unsafe { plumage_system_create(&cfg, &d, &mut sys) }, null(), "plumage_system_create");
    sys
}

fn step(sys: *mut PlumageSystem, frame: &[f32]) {
    ok(unsafe { plumage_system_step(sys, frame.as_ptr(), frame.len() / 3) }, sys, "plumage_system_step");
}

fn instances(sys: *const PlumageSystem) -> Vec<PlumageFeatherInstance> {
    let mut n = 0usize;
    let st = unsafe { plumage_system_feather_instances(sys, null_mut(), 0, &mut n) };
    assert!(st == PLUMAGE_STATUS_BUFFER_TOO_SMALL || (st == PLUMAGE_STATUS_OK && n == 0), "{}", error_of(sys));
    let mut out = vec![PlumageFeatherInstance::default(); n];
    ok(unsafe { plumage_system_feather_instances(sys, out.as_mut_ptr(), n, &mut n) }, sys, "instances");
    out
}

/// The card as the host receives it.
struct Card {
    segments: usize,
    positions: Vec<f32>,
    indices: Vec<u32>,
    vertex_segments: Vec<u32>,
}

fn template(sys: *const PlumageSystem) -> Card {
    let mut t = std::mem::MaybeUninit::<PlumageFeatherTemplate>::uninit();
    unsafe { plumage_feather_template_init(t.as_mut_ptr()) };
    let mut t = unsafe { t.assume_init() };
    ok(unsafe { plumage_system_feather_template(sys, &mut t) }, sys, "template counts");
    let (nv, nt) = (t.vertex_count as usize, t.triangle_count as usize);
    let mut card = Card {
        segments: t.segments as usize,
        positions: vec![0.0; 3 * nv],
        indices: vec![0; 3 * nt],
        vertex_segments: vec![0; nv],
    };
    t.positions = card.positions.as_mut_ptr();
    t.positions_capacity = card.positions.len();
    t.indices = card.indices.as_mut_ptr();
    t.indices_capacity = card.indices.len();
    t.vertex_segments = card.vertex_segments.as_mut_ptr();
    t.vertex_segments_capacity = nv;
    ok(unsafe { plumage_system_feather_template(sys, &mut t) }, sys, "template");
    card
}

/// Positions, vertex counts and triangle indices of every feather.
struct Geometry {
    positions: Vec<f32>,
    indices: Vec<u32>,
    vertex_counts: Vec<u32>,
}

fn geometry(sys: *const PlumageSystem) -> Geometry {
    let mut g = std::mem::MaybeUninit::<PlumageFeatherGeometry>::uninit();
    unsafe { plumage_feather_geometry_init(g.as_mut_ptr()) };
    let mut g = unsafe { g.assume_init() };
    ok(unsafe { plumage_system_feather_geometry(sys, &mut g) }, sys, "geometry totals");
    let mut out = Geometry {
        positions: vec![0.0; 3 * g.vertex_count as usize],
        indices: vec![0; 3 * g.triangle_count as usize],
        vertex_counts: vec![0; g.feather_count as usize],
    };
    g.positions = out.positions.as_mut_ptr();
    g.positions_capacity = out.positions.len();
    g.indices = out.indices.as_mut_ptr();
    g.indices_capacity = out.indices.len();
    g.vertex_counts = out.vertex_counts.as_mut_ptr();
    g.vertex_counts_capacity = out.vertex_counts.len();
    ok(unsafe { plumage_system_feather_geometry(sys, &mut g) }, sys, "geometry");
    out
}

/// One record's template vertices in world space, by the convention of
/// `PlumageFeatherInstance` (the reference shader's steps, in f32).
fn place(r: &PlumageFeatherInstance, card: &Card) -> Vec<[f32; 3]> {
    let q = r.rotation.map(|c| c as f32 / 32767.0);
    let norm = q.iter().map(|c| c * c).sum::<f32>().sqrt();
    let [qx, qy, qz, qw] = q.map(|c| c / norm);
    let rotate = |p: [f32; 3]| {
        // v + 2w (u × v) + 2 u × (u × v), u = (qx, qy, qz).
        let u = [qx, qy, qz];
        let cross = |a: [f32; 3], b: [f32; 3]| {
            [a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]]
        };
        let t = cross(u, p).map(|c| 2.0 * c);
        let ut = cross(u, t);
        [0, 1, 2].map(|i| p[i] + qw * t[i] + ut[i])
    };
    let s = card.segments;
    let bend = |k: usize| r.bends[k] as f32 * PLUMAGE_INSTANCE_BEND_RANGE / 32767.0;
    (0..card.vertex_segments.len())
        .map(|v| {
            let (x, y) = (card.positions[3 * v], card.positions[3 * v + 1]);
            let k = card.vertex_segments[v] as usize;
            let (mut px, mut pz, mut angle) = (0.0f32, 0.0f32, 0.0f32);
            for j in 0..k {
                if j > 0 {
                    angle += bend(j - 1);
                }
                px += angle.cos() * r.length / s as f32;
                pz += angle.sin() * r.length / s as f32;
            }
            if k > 0 {
                angle += bend(k - 1);
            }
            let along = (x - k as f32 / s as f32) * r.length;
            let p = rotate([px + angle.cos() * along, y * r.width, pz + angle.sin() * along]);
            [0, 1, 2].map(|i| r.root[i] + p[i])
        })
        .collect()
}

/// The largest distance, in feather lengths, between the records' placed
/// cards and the copied-out geometry (feathers left out must sit at their
/// root exactly); and the number of feathers left out.
fn reconstruction_error(sys: *const PlumageSystem) -> (f32, usize) {
    let (records, card, g) = (instances(sys), template(sys), geometry(sys));
    assert_eq!(records.len(), g.vertex_counts.len());
    let nv = card.vertex_segments.len();
    let mut worst = 0.0f32;
    let mut left_out = 0;
    for (f, r) in records.iter().enumerate() {
        assert_eq!(g.vertex_counts[f] as usize, nv, "every feather has the card's vertices");
        // The card's triangles are every feather's, offset.
        let tris = card.indices.len();
        assert!(g.indices[f * tris..(f + 1) * tris].iter().zip(&card.indices).all(|(a, b)| *a == b + (f * nv) as u32));
        for (v, p) in place(r, &card).iter().enumerate() {
            let at = &g.positions[3 * (f * nv + v)..3 * (f * nv + v) + 3];
            let d = ((p[0] - at[0]).powi(2) + (p[1] - at[1]).powi(2) + (p[2] - at[2]).powi(2)).sqrt();
            if r.length > 0.0 {
                worst = worst.max(d / r.length);
            } else {
                assert_eq!(p, &r.root, "a feather left out is all at its root");
                assert_eq!(at, &r.root);
            }
        }
        left_out += usize::from(r.length == 0.0);
        assert_eq!(r.reserved, 0);
        assert!(r.rotation[3] >= 0);
    }
    (worst, left_out)
}

#[test]
fn records_reconstruct_the_geometry_on_the_swimmer() {
    let body = swim_body(RINGS, SEGMENTS);
    for segments in 1..=4u32 {
        let sys = create(&body, 800, segments, Some([0.0; 3]));
        let mut errors = vec![reconstruction_error(sys).0];
        for k in [12usize, 13, 14, 15] {
            step(sys, &swim_pose(RINGS, SEGMENTS, k as f64 / FPS));
            errors.push(reconstruction_error(sys).0);
        }
        let card = template(sys);
        println!(
            "swimmer, S = {segments}: {} vertices and {} triangles a card; largest error {:.2e} lengths (create, then 4 steps: {:?})",
            card.vertex_segments.len(),
            card.indices.len() / 3,
            errors.iter().copied().fold(0.0, f32::max),
            errors.iter().map(|e| format!("{e:.1e}")).collect::<Vec<_>>()
        );
        assert_eq!(card.segments, segments as usize);
        assert!(errors.iter().all(|&e| e < 1e-4), "S = {segments}: {errors:?}");
        unsafe { plumage_system_destroy(sys) };
    }
}

#[test]
fn records_reconstruct_the_geometry_on_the_flamingo() {
    let Some((rest, frames)) = common::gltf_mesh::morph_clip("Flamingo.glb", 30.0) else { return };
    for segments in 1..=4u32 {
        let sys = create(&rest, 1000, segments, Some([0.0, 0.0, 100.4]));
        let mut worst = reconstruction_error(sys).0;
        let mut left_out = 0;
        for frame in &frames[..3] {
            step(sys, frame);
            let (e, out) = reconstruction_error(sys);
            worst = worst.max(e);
            left_out = out;
        }
        println!("flamingo, S = {segments}: largest error {worst:.2e} lengths ({left_out} feathers left out)");
        assert!(worst < 1e-4, "S = {segments}: {worst}");
        unsafe { plumage_system_destroy(sys) };
    }
}

/// A record's 36 bytes (it has no padding).
fn bytes(r: &PlumageFeatherInstance) -> [u8; 36] {
    // SAFETY: a 36-byte plain-old-data struct without padding bytes.
    unsafe { std::mem::transmute::<PlumageFeatherInstance, [u8; 36]>(*r) }
}

/// Per feather: its record's bytes and its vertices' bit patterns.
fn feather_bits(records: &[PlumageFeatherInstance], g: &Geometry, nv: usize) -> Vec<([u8; 36], Vec<u32>)> {
    let vertices = g.positions.chunks(3 * nv);
    records.iter().zip(vertices).map(|(r, xyz)| (bytes(r), xyz.iter().map(|x| x.to_bits()).collect())).collect()
}

/// Whether two float slices are the same bit for bit.
fn same_bits(a: &[f32], b: &[f32]) -> bool {
    a.len() == b.len() && a.iter().zip(b).all(|(x, y)| x.to_bits() == y.to_bits())
}

fn changed(sys: *const PlumageSystem) -> (Vec<u32>, u32) {
    let mut n = 0usize;
    let mut all = 7u32;
    let st = unsafe { plumage_system_changed_feathers(sys, null_mut(), 0, &mut n, &mut all) };
    if n == 0 {
        ok(st, sys, "changed (empty)");
        assert_eq!(all, 0);
        return (vec![], 0);
    }
    assert_eq!(st, PLUMAGE_STATUS_BUFFER_TOO_SMALL);
    assert_eq!(all, 7, "out_all is written on success only");
    let mut out = vec![0u32; n];
    ok(unsafe { plumage_system_changed_feathers(sys, out.as_mut_ptr(), n, &mut n, &mut all) }, sys, "changed");
    (out, all)
}

/// The swim with the front half of the body held at rest (bit for bit):
/// only the feathers near the moving half can change.
fn half_swim(k: usize, rest: &[f32]) -> Vec<f32> {
    let moving = swim_pose(RINGS, SEGMENTS, k as f64 / FPS);
    rest.chunks(3)
        .zip(moving.chunks(3))
        .flat_map(|(r, m)| if r[0] < 2.0 { [r[0], r[1], r[2]] } else { [m[0], m[1], m[2]] })
        .collect()
}

/// Every feather not listed after a step has its record and its triangles
/// exactly as before the step; every listed one differs in its record or
/// its triangles. Through the C ABI, on the swimmer with its front half
/// held still, and on the whole swim.
#[test]
fn unlisted_feathers_are_bit_identical_after_a_step() {
    let body = swim_body(RINGS, SEGMENTS);
    for segments in [1u32, 4] {
        let sys = create(&body, 800, segments, Some([0.0; 3]));
        let (all, flag) = changed(sys);
        let count = instances(sys).len();
        assert_eq!((all.len(), flag), (count, 1), "create lists every feather");
        assert!(all.iter().enumerate().all(|(i, &f)| f as usize == i));
        let nv = template(sys).vertex_segments.len();
        let mut before = feather_bits(&instances(sys), &geometry(sys), nv);
        let mut shares = vec![];
        for k in 10..22 {
            let frame = if k < 16 { half_swim(k, &body.positions) } else { swim_pose(RINGS, SEGMENTS, k as f64 / FPS) };
            step(sys, &frame);
            let after = feather_bits(&instances(sys), &geometry(sys), nv);
            let (list, flag) = changed(sys);
            assert_eq!(flag, 0);
            assert!(list.windows(2).all(|w| w[0] < w[1]), "increasing");
            let mut listed = vec![false; count];
            list.iter().for_each(|&f| listed[f as usize] = true);
            for f in 0..count {
                if listed[f] {
                    assert!(before[f] != after[f], "S = {segments}, frame {k}: feather {f} listed but unchanged");
                } else {
                    assert!(before[f] == after[f], "S = {segments}, frame {k}: feather {f} changed but not listed");
                }
            }
            shares.push(format!("{:.1} %", 100.0 * list.len() as f64 / count as f64));
            before = after;
        }
        println!(
            "S = {segments}, {count} feathers: listed per step (6 half-held steps, then 6 whole swim steps): {shares:?}"
        );
        // A step with the same positions changes nothing.
        let same = swim_pose(RINGS, SEGMENTS, 21.0 / FPS);
        step(sys, &same);
        let (settled, _) = changed(sys);
        println!("S = {segments}: a step to the same positions lists {} feathers (settling ones)", settled.len());
        unsafe { plumage_system_destroy(sys) };
    }
}

/// The safe API: a listed feather's record or triangles differ, or it was
/// readjusted; evaluate compares with the previous result; a load lists
/// everything. And the shares of feathers listed and reposed a step on the
/// built-in swimmer, default coat and kite.
#[test]
fn changed_lists_through_the_safe_api_and_their_shares() {
    let body = swim_body(RINGS, SEGMENTS);
    for (name, preset) in [("default", Preset::Feathers), ("kite", Preset::Kite)] {
        let cfg = Config {
            target_feathers: 800,
            threads: 2,
            seed: 7,
            flow_source: Some(glam::Vec3::ZERO),
            ..Config::preset(preset)
        };
        let mut sys = System::new(&cfg, &MeshInput::new(&body.positions, &body.indices)).expect("create");
        let n = sys.feather_count();
        assert!(sys.changed_feathers().all && sys.changed_feathers().indices.len() == n);
        let saved = sys.save_state();
        let (mut listed, mut reposed, mut listed_half, mut reposed_half) = (vec![], vec![], vec![], vec![]);
        let mut previous = (sys.feather_instances(), sys.feather_mesh().positions);
        for k in 1..=20usize {
            let half = k > 10;
            let frame = if half { half_swim(k, &body.positions) } else { swim_pose(RINGS, SEGMENTS, k as f64 / FPS) };
            sys.step(&frame).unwrap();
            let now = (sys.feather_instances(), sys.feather_mesh().positions);
            let c = sys.changed_feathers();
            assert!(!c.all);
            let nv = now.1.len() / n;
            let mut is_listed = vec![false; n];
            c.indices.iter().for_each(|&f| is_listed[f as usize] = true);
            for (f, &listed) in is_listed.iter().enumerate() {
                let (a, b) = (&previous.0[f], &now.0[f]);
                let same = same_bits(
                    &[a.root, [a.length, a.width, 0.0]].concat(),
                    &[b.root, [b.length, b.width, 0.0]].concat(),
                ) && (a.rotation, a.bends) == (b.rotation, b.bends)
                    && same_bits(
                        previous.1[f * nv..(f + 1) * nv].as_flattened(),
                        now.1[f * nv..(f + 1) * nv].as_flattened(),
                    );
                if listed {
                    assert!(!same || sys.readjusted()[f], "{name}, step {k}: feather {f}");
                } else {
                    assert!(same, "{name}, step {k}: feather {f} changed but not listed");
                }
            }
            let share = |x: usize| 100.0 * x as f64 / n as f64;
            let (l, r) = if half { (&mut listed_half, &mut reposed_half) } else { (&mut listed, &mut reposed) };
            l.push(share(c.indices.len()));
            r.push(share(c.reposed));
            previous = now;
        }
        let summary = |v: &[f64]| {
            let mean = v.iter().sum::<f64>() / v.len() as f64;
            format!(
                "mean {mean:.1} % (min {:.1}, max {:.1})",
                v.iter().copied().fold(f64::MAX, f64::min),
                v.iter().copied().fold(0.0, f64::max)
            )
        };
        println!(
            "{name}, {n} feathers: whole swim, steps 1-10: listed {}, of them reposed {}; front half held, steps 11-20: listed {}, reposed {}",
            summary(&listed),
            summary(&reposed),
            summary(&listed_half),
            summary(&reposed_half)
        );
        // An interrupted step keeps the list of the last step.
        let kept = sys.changed_feathers().indices.to_vec();
        let stop = Stop;
        let far = swim_pose(RINGS, SEGMENTS, 1.0);
        assert!(sys.step_with_progress(&far, &plumage::progress::Progress::to(&stop)).is_err());
        assert_eq!(sys.changed_feathers().indices, &kept[..]);
        // Evaluate compares with the previous result.
        sys.evaluate(&far).unwrap();
        assert!(!sys.changed_feathers().all);
        sys.load_state(&saved).unwrap();
        let c = sys.changed_feathers();
        assert!(c.all && c.indices.len() == n);
    }
}

/// A progress sink that asks every call to stop.
struct Stop;

impl plumage::progress::ProgressSink for Stop {
    fn report(&self, _: plumage::progress::Phase, _: f32) -> bool {
        false
    }
}

/// The contract of the three calls: NULLs, short buffers (named, nothing
/// written), old struct sizes, and the template agreeing with the geometry.
#[test]
fn instancing_calls_follow_the_conventions() {
    let body = swim_body(RINGS, SEGMENTS);
    let sys = create(&body, 300, 4, None);
    let mut n = 0usize;
    assert_eq!(unsafe { plumage_system_feather_instances(null(), null_mut(), 0, &mut n) }, PLUMAGE_STATUS_NULL_POINTER);
    assert_eq!(
        unsafe { plumage_system_feather_instances(sys, null_mut(), 0, null_mut()) },
        PLUMAGE_STATUS_NULL_POINTER
    );
    assert_eq!(
        unsafe { plumage_system_feather_instances(sys, null_mut(), 0, &mut n) },
        PLUMAGE_STATUS_BUFFER_TOO_SMALL
    );
    let mut short = vec![PlumageFeatherInstance { reserved: 9, ..Default::default() }; n - 1];
    let mut m = 0usize;
    assert_eq!(
        unsafe { plumage_system_feather_instances(sys, short.as_mut_ptr(), n - 1, &mut m) },
        PLUMAGE_STATUS_BUFFER_TOO_SMALL
    );
    assert_eq!(m, n);
    assert!(short.iter().all(|r| r.reserved == 9), "nothing written");
    assert_eq!(
        unsafe { plumage_system_changed_feathers(sys, null_mut(), 0, null_mut(), null_mut()) },
        PLUMAGE_STATUS_NULL_POINTER
    );
    assert_eq!(
        unsafe { plumage_system_changed_feathers(null(), null_mut(), 0, &mut m, null_mut()) },
        PLUMAGE_STATUS_NULL_POINTER
    );
    assert_eq!(unsafe { plumage_system_feather_template(sys, null_mut()) }, PLUMAGE_STATUS_NULL_POINTER);

    // The template: counts with no buffers, a short buffer named, an old struct size refused.
    let mut t = std::mem::MaybeUninit::<PlumageFeatherTemplate>::uninit();
    unsafe { plumage_feather_template_init(t.as_mut_ptr()) };
    let mut t = unsafe { t.assume_init() };
    assert_eq!(t.struct_size as usize, std::mem::size_of::<PlumageFeatherTemplate>());
    ok(unsafe { plumage_system_feather_template(sys, &mut t) }, sys, "template counts");
    assert_eq!((t.segments, t.vertex_count, t.triangle_count), (4, 13, 14));
    assert!((t.vane_split - 0.4).abs() < 1e-6);
    let mut uvs = vec![-1.0f32; 2 * 13 - 1];
    let mut positions = vec![-1.0f32; 3 * 13];
    t.uvs = uvs.as_mut_ptr();
    t.uvs_capacity = uvs.len();
    t.positions = positions.as_mut_ptr();
    t.positions_capacity = positions.len();
    assert_eq!(unsafe { plumage_system_feather_template(sys, &mut t) }, PLUMAGE_STATUS_BUFFER_TOO_SMALL);
    assert!(error_of(sys).contains("PlumageFeatherTemplate.uvs"), "{}", error_of(sys));
    assert!(positions.iter().all(|&p| p == -1.0));
    let mut uvs = vec![0.0f32; 2 * 13];
    t.uvs = uvs.as_mut_ptr();
    t.uvs_capacity = uvs.len();
    ok(unsafe { plumage_system_feather_template(sys, &mut t) }, sys, "template");
    let mut tiny = PlumageFeatherTemplate { struct_size: 8, ..t };
    assert_eq!(unsafe { plumage_system_feather_template(sys, &mut tiny) }, PLUMAGE_STATUS_UNSUPPORTED_STRUCT_SIZE);
    // UVs are the geometry's first feather's; positions are (u, v − 0.5, 0).
    let mut g = std::mem::MaybeUninit::<PlumageFeatherGeometry>::uninit();
    unsafe { plumage_feather_geometry_init(g.as_mut_ptr()) };
    let mut g = unsafe { g.assume_init() };
    ok(unsafe { plumage_system_feather_geometry(sys, &mut g) }, sys, "geometry totals");
    let mut all_uvs = vec![0.0f32; 2 * g.vertex_count as usize];
    g.uvs = all_uvs.as_mut_ptr();
    g.uvs_capacity = all_uvs.len();
    ok(unsafe { plumage_system_feather_geometry(sys, &mut g) }, sys, "geometry");
    assert_eq!(&all_uvs[..26], &uvs[..]);
    for v in 0..13 {
        assert_eq!(positions[3 * v], uvs[2 * v]);
        assert!((positions[3 * v + 1] - (uvs[2 * v + 1] - 0.5)).abs() < 1e-6);
        assert_eq!(positions[3 * v + 2], 0.0);
    }
    unsafe { plumage_system_destroy(sys) };
}
