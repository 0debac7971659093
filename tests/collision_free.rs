//! Collision-free coats at rest through the whole pipeline (sampling,
//! ordering, adjustment), judged by the exact validation of DESIGN.md §6:
//! a sphere, a torus whose hint field circles the ring (a cyclic flow), and
//! the three shared models with a flow from the head (`Config::flow_source`).
//!
//! Intersecting pairs and body penetrations must be exactly 0. Coverage
//! (over the visible skin: the bird's belly passes through its wings, and
//! the skin buried there carries neither roots nor probes) is asserted a
//! little below the level reached today; the target is 0.95, met by
//! the sphere (0.988), the torus (0.989) and the Fox (0.962), not yet by
//! the Flamingo (0.904) or the bird (0.872). What is left bare there: the rims of thin wings and the thin
//! legs (a flat feather over a wing lies parallel to the rim's normal, and
//! the probes' rays there leave the coat between the two skins' feathers),
//! feathers pitched up on thin limbs and at wing roots, and feathers
//! shortened in creases.

mod common;

use common::gltf_mesh::load_model;
use common::shapes::Shape;
use glam::Vec3;
use plumage::stats::ValidationReport;
use plumage::{Config, MeshInput, Preset, System};

fn dress(shape: &Shape, hints: Option<&[f32]>, config: &Config) -> (System, ValidationReport) {
    let mut mesh = MeshInput::new(&shape.positions, &shape.indices);
    mesh.orientations = hints;
    let system = System::new(config, &mesh).expect("create");
    let report = system.validate().expect("validation figures");
    (system, report)
}

fn assert_collision_free(name: &str, system: &System, v: &ValidationReport, min_coverage: f64) {
    eprintln!(
        "{name}: {} feathers, {} clamped or shortened, {v:?}",
        system.feather_count(),
        system.frame_report().map_or(0, |r| r.clamped)
    );
    assert_eq!(v.intersecting_pairs, 0, "{name}: {v:?}");
    assert_eq!(v.body_penetrations, 0, "{name}: {v:?}");
    assert!(v.coverage >= min_coverage, "{name}: coverage {} below {min_coverage}", v.coverage);
}

fn sphere(rings: usize, segments: usize, radius: f32) -> Shape {
    let mut s = Shape::default();
    for i in 0..=rings {
        let theta = std::f32::consts::PI * i as f32 / rings as f32;
        for j in 0..segments {
            let phi = std::f32::consts::TAU * j as f32 / segments as f32;
            s.positions.extend_from_slice(&[
                radius * theta.sin() * phi.cos(),
                radius * theta.sin() * phi.sin(),
                radius * theta.cos(),
            ]);
        }
    }
    for i in 0..rings {
        for j in 0..segments {
            let a = (i * segments + j) as u32;
            let b = (i * segments + (j + 1) % segments) as u32;
            let (c, d) = (a + segments as u32, b + segments as u32);
            s.indices.extend_from_slice(&[a, c, d, a, d, b]);
        }
    }
    s
}

/// A torus (ring radius `big`, tube radius `small`) and a hint field along
/// the ring.
fn torus(big: f32, small: f32, nu: usize, nv: usize) -> (Shape, Vec<f32>) {
    let (mut s, mut hints) = (Shape::default(), Vec::new());
    for i in 0..nu {
        let u = std::f32::consts::TAU * i as f32 / nu as f32;
        for j in 0..nv {
            let v = std::f32::consts::TAU * j as f32 / nv as f32;
            let r = big + small * v.cos();
            s.positions.extend_from_slice(&[r * u.cos(), r * u.sin(), small * v.sin()]);
            hints.extend_from_slice(&[-u.sin(), u.cos(), 0.0]);
        }
    }
    for i in 0..nu {
        for j in 0..nv {
            let a = (i * nv + j) as u32;
            let b = (((i + 1) % nu) * nv + j) as u32;
            let c = (((i + 1) % nu) * nv + (j + 1) % nv) as u32;
            let d = (i * nv + (j + 1) % nv) as u32;
            s.indices.extend_from_slice(&[a, b, c, a, c, d]);
        }
    }
    (s, hints)
}

#[test]
fn sphere_at_rest_is_collision_free_and_covered() {
    let config = Config { target_feathers: 2000, threads: 2, ..Config::default() };
    let (system, v) = dress(&sphere(40, 80, 10.0), None, &config);
    assert_collision_free("sphere", &system, &v, 0.98);
}

#[test]
fn torus_with_a_cyclic_flow_is_collision_free() {
    let (shape, hints) = torus(10.0, 3.0, 120, 40);
    let config = Config { target_feathers: 4000, threads: 2, ..Config::default() };
    let (system, v) = dress(&shape, Some(&hints), &config);
    // Bent feathers lying along the tube cover a little less of it than
    // kites standing off it did (0.984 against above 0.985).
    assert_collision_free("torus", &system, &v, 0.98);
}

/// The three shared models at the sizes of the issue, each with its flow
/// starting at the head (the vertex nearest the given point).
#[test]
fn shared_models_at_rest_are_collision_free() {
    let models = [
        ("Flamingo.glb", 2000, Vec3::new(0.0, 0.0, 100.4), 0.9),
        ("Fox.glb", 4000, Vec3::new(0.0, 1.36, 1.69), 0.955),
        // The bird's seed 1 coat covers 0.872 since the spacing search's
        // first guess changed (#20; 0.880 before): over seeds 1 to 6 the
        // host measured a mean of 0.885 before and 0.887 after (0.877 to
        // 0.905), so this seed moved by chance, not the coats as a whole.
        ("bird.glb", 800, Vec3::new(0.0, -0.02, -0.21), 0.87),
    ];
    for (file, feathers, head, min_coverage) in models {
        let Some(shape) = load_model(file) else { continue };
        let config = Config { target_feathers: feathers, threads: 2, flow_source: Some(head), ..Config::default() };
        let (system, v) = dress(&shape, None, &config);
        assert_collision_free(file, &system, &v, min_coverage);
    }
}

/// Skin the caller marks bare (spacing multiplier 0) carries no feathers
/// and no coverage probes: a sphere feathered on its upper half only is
/// judged on that half.
#[test]
fn bare_skin_is_left_out_of_coverage() {
    let shape = sphere(30, 60, 10.0);
    let feathered_above =
        |z: f32| shape.positions.chunks(3).map(|p| if p[2] > z { 1.0 } else { 0.0 }).collect::<Vec<f32>>();
    let config = Config { target_feathers: 600, threads: 2, ..Config::default() };
    let upper = feathered_above(0.0);
    let mut mesh = MeshInput::new(&shape.positions, &shape.indices);
    mesh.spacing_scale = Some(&upper);
    let half = System::new(&config, &mesh).expect("create");
    let v = half.validate().expect("figures");
    assert!(half.feathers().iter().all(|f| f.root[2] > -1.0), "a root on the bare half");
    // Counting the bare half would put coverage near 0.5.
    assert_collision_free("upper half", &half, &v, 0.9);
    assert!(v.probes > 0 && v.buried_probes == 0, "{v:?}");
}

/// Fluffiness lifts every feather, so the mean pitch rises with it (the
/// default bent feather and the kite); a collision allowance lets kites
/// sink into their obstacles, so it falls (it acts in the kite's fine-pitch
/// step; a bent feather's drape keeps its clearance).
#[test]
fn fluffiness_raises_mean_pitch_and_a_collision_allowance_lowers_it() {
    let shape = sphere(30, 60, 10.0);
    for preset in [Preset::Feathers, Preset::Kite] {
        let pitch = |fluffiness: f32, collision_allowance: f32| {
            let base = Config::preset(preset);
            let config = Config { target_feathers: 800, threads: 2, fluffiness, collision_allowance, ..base };
            dress(&shape, None, &config).1.mean_pitch_deg
        };
        let base = pitch(0.0, 0.0);
        let fluffed: Vec<f64> = [0.05, 0.1, 0.2].iter().map(|&f| pitch(f, 0.0)).collect();
        eprintln!("{preset:?}: mean pitch: base {base:.2}, fluffiness 0.05/0.1/0.2 {fluffed:.2?}");
        assert!(base < fluffed[0] && fluffed[0] < fluffed[1] && fluffed[1] < fluffed[2], "{base} {fluffed:?}");
        if preset == Preset::Kite {
            let sunk = pitch(0.0, 0.5);
            eprintln!("collision allowance 0.5: {sunk:.2}");
            assert!(sunk < base, "{sunk} vs {base}");
        }
    }
}
