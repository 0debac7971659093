//! The adjuster's exact checks answer as the exhaustive checker does,
//! feather by feather (`System::audit_exact_checks`): every check of one
//! feather against a neighbour and against the body, on the coat as it
//! lies and nudged into and out of contact, at the default (bent) feather
//! and the kite: on every frame of the Flamingo's clip, of the bird's wing
//! beat and of the first second of the Fox's clip (skinned), on a few
//! frames of the built-in swim and of a strip folding onto itself, and on
//! the Fox and the bird bent out of their rest pose. A shortcut that rules
//! out a pair or a skin face unsoundly, or a nearest-skin search that
//! stops early, makes a disagreement here; each run must also meet both
//! answers, so the audit cannot pass by testing only clear coats.

mod common;

use common::gltf_mesh::{load_model, morph_clip, skinned_clip};
use common::shapes::{Shape, swim_body, swim_pose, thin_box};
use plumage::validation::CheckAudit;
use plumage::{Config, MeshInput, Preset, System};

/// The audits of a coat dressed on `rest` and stepped through `frames`
/// (the rest pose first).
fn audits(cfg: &Config, rest: &Shape, frames: &[Vec<f32>]) -> Vec<CheckAudit> {
    let mut sys = System::new(cfg, &MeshInput::new(&rest.positions, &rest.indices)).expect("create");
    let mut out = vec![sys.audit_exact_checks()];
    for frame in frames {
        sys.step(frame).expect("step");
        out.push(sys.audit_exact_checks());
    }
    out
}

/// Both presets at `feathers` feathers: no disagreement on any frame, and
/// both answers met, for pairs and for the body.
fn assert_checks_agree(name: &str, feathers: usize, rest: &Shape, frames: &[Vec<f32>]) {
    for (preset, base) in [("default", Config::default()), ("kite", Config::preset(Preset::Kite))] {
        let cfg = Config { target_feathers: feathers, threads: 2, seed: 3, ..base };
        let runs = audits(&cfg, rest, frames);
        let total = runs.iter().fold(CheckAudit::default(), |a, &b| a + b);
        eprintln!("{name} {preset}: {total:?}");
        for (k, a) in runs.iter().enumerate() {
            assert_eq!(a.pair_disagreements, 0, "{name} {preset} frame {k}: {a:?}");
            assert_eq!(a.body_disagreements, 0, "{name} {preset} frame {k}: {a:?}");
        }
        assert!(total.pairs_meeting > 0 && total.pairs_meeting < total.pair_checks, "{name} {preset}: {total:?}");
        assert!(
            total.bodies_penetrating > 0 && total.bodies_penetrating < total.body_checks,
            "{name} {preset}: {total:?}"
        );
    }
}

/// `shape` bent about the z axis by an angle growing along x, and twisted,
/// by `amount` (a non-rigid motion of a whole model).
fn warped(shape: &Shape, amount: f32) -> Vec<f32> {
    let (lo, hi) = shape.positions.chunks(3).fold((f32::MAX, f32::MIN), |(lo, hi), p| (lo.min(p[0]), hi.max(p[0])));
    let span = (hi - lo).max(1e-6);
    shape
        .positions
        .chunks(3)
        .flat_map(|p| {
            let u = (p[0] - lo) / span;
            let (bend, twist) = (amount * 0.6 * u * u, amount * 0.4 * u);
            let (s, c) = bend.sin_cos();
            let (x, y) = (c * p[0] - s * p[1], s * p[0] + c * p[1]);
            let (st, ct) = twist.sin_cos();
            [x, ct * y - st * p[2], st * y + ct * p[2]]
        })
        .collect()
}

#[test]
fn checks_agree_on_the_built_in_swim() {
    let (rings, segments) = (32, 24);
    let body = swim_body(rings, segments);
    let frames: Vec<Vec<f32>> = (1..=4).map(|k| swim_pose(rings, segments, 0.2 * k as f64)).collect();
    assert_checks_agree("built-in swim", 700, &body, &frames);
}

#[test]
fn checks_agree_on_the_flamingo_clip() {
    let Some((rest, clip)) = morph_clip("Flamingo.glb", 30.0) else { return };
    assert_checks_agree("Flamingo", 700, &rest, &clip);
}

#[test]
fn checks_agree_on_the_fox_and_the_bird_clips() {
    // Skinned, their first clip (the host's default): every frame of the
    // bird's wing beat, and the Fox's first second.
    for (file, frames) in [("bird.glb", 21), ("Fox.glb", 31)] {
        let Some((rest, clip)) = skinned_clip(file, 30.0, frames) else { continue };
        // The skinning is read right: the body moves over the clip, by
        // less than its size, and keeps about its size.
        let size = |p: &[f32]| {
            let (lo, hi) = p.chunks(3).fold(([f32::MAX; 3], [f32::MIN; 3]), |(lo, hi), v| {
                (std::array::from_fn(|k| lo[k].min(v[k])), std::array::from_fn(|k| hi[k].max(v[k])))
            });
            (0..3).map(|k| (hi[k] - lo[k]).powi(2)).sum::<f32>().sqrt()
        };
        let moved = |p: &[f32]| {
            let each = rest.positions.chunks(3).zip(p.chunks(3));
            each.map(|(a, b)| (0..3).map(|k| (a[k] - b[k]).powi(2)).sum::<f32>().sqrt()).fold(0.0f32, f32::max)
        };
        let most = clip.iter().map(|p| moved(p)).fold(0.0f32, f32::max);
        let diagonal = size(&rest.positions);
        let sizes = clip.iter().map(|p| size(p) / diagonal);
        let (smallest, largest) = sizes.fold((f32::MAX, 0.0f32), |(lo, hi), s| (lo.min(s), hi.max(s)));
        eprintln!("{file}: diagonal {diagonal} (frames {smallest}..{largest} of it), most moved {most}");
        assert!(most > 0.02 * diagonal && most < diagonal, "{file}: moved {most} of a diagonal {diagonal}");
        assert!(smallest > 0.5 && largest < 1.5, "{file}: the size changed");
        assert_checks_agree(file, 700, &rest, &clip);
    }
}

#[test]
fn checks_agree_on_a_folding_strip() {
    // A thin strip folded about its middle, the far half closing onto the
    // near one: skin and feathers from both halves come together.
    let (w, h) = (4.0f32, 1.0f32);
    let strip = thin_box(w, h, 0.05, 40, 10);
    let frames: Vec<Vec<f32>> = (1..=4)
        .map(|k| {
            let angle = 0.6 * k as f32;
            let (s, c) = angle.sin_cos();
            strip
                .positions
                .chunks(3)
                .flat_map(|p| {
                    let x = p[0] - 0.5 * w;
                    if x <= 0.0 { [p[0], p[1], p[2]] } else { [0.5 * w + c * x - s * p[2], p[1], s * x + c * p[2]] }
                })
                .collect()
        })
        .collect();
    assert_checks_agree("folding strip", 600, &strip, &frames);
}

#[test]
fn checks_agree_on_the_fox_and_the_bird_bent_out_of_rest() {
    for file in ["Fox.glb", "bird.glb"] {
        let Some(rest) = load_model(file) else { continue };
        let frames: Vec<Vec<f32>> = (1..=3).map(|k| warped(&rest, 0.1 * k as f32)).collect();
        assert_checks_agree(file, 700, &rest, &frames);
    }
}
