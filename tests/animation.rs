//! Animation (paper §3.3, DESIGN.md §5): a frame touches as few feathers as
//! it can and stays collision-free.

mod common;

use common::shapes::{Shape, grid};
use plumage::{Config, MeshInput, Mode, System};

fn plate_config(target: usize) -> Config {
    Config { target_feathers: target, threads: 2, seed: 11, flow_axis: glam::Vec3::X, ..Config::default() }
}

fn create(shape: &Shape, config: &Config) -> System {
    System::new(config, &MeshInput::new(&shape.positions, &shape.indices)).expect("create")
}

fn map_points(shape: &Shape, f: impl Fn([f32; 3]) -> [f32; 3]) -> Vec<f32> {
    shape.positions.chunks(3).flat_map(|p| f([p[0], p[1], p[2]])).collect()
}

/// Rotation about the z axis by `a` then about x by `b`, then a translation.
fn rigid(p: [f32; 3], a: f32, b: f32, t: [f32; 3]) -> [f32; 3] {
    let (sa, ca) = a.sin_cos();
    let (sb, cb) = b.sin_cos();
    let q = [ca * p[0] - sa * p[1], sa * p[0] + ca * p[1], p[2]];
    let r = [q[0], cb * q[1] - sb * q[2], sb * q[1] + cb * q[2]];
    [r[0] + t[0], r[1] + t[1], r[2] + t[2]]
}

/// Points before the hinge line x = `hinge` fold up about it by `angle`;
/// the rest stays.
fn fold(shape: &Shape, hinge: f32, angle: f32) -> Vec<f32> {
    map_points(shape, |p| {
        if p[0] >= hinge {
            return p;
        }
        let d = hinge - p[0];
        [hinge - d * angle.cos(), p[1], p[2] + d * angle.sin()]
    })
}

#[test]
fn a_rigidly_moving_body_readjusts_nothing() {
    let plate = grid(10.0, 10.0, 30, 30, 0.0, true);
    let mut sys = create(&plate, &plate_config(800));
    let rest = sys.validate().unwrap();
    let rest_pitch: Vec<f32> = sys.feathers().iter().map(|f| f.pitch).collect();
    for k in 1..=6 {
        let s = k as f32;
        let frame = map_points(&plate, |p| rigid(p, 0.2 * s, 0.1 * s, [s, -2.0 * s, 0.5 * s]));
        sys.step(&frame).unwrap();
        let report = sys.frame_report().unwrap();
        assert_eq!(report.adjusted, 0, "frame {k}: a rigid motion readjusts no feather");
        assert_eq!(sys.pose_changes().pops, 0, "frame {k}: a rigid motion pops no feather");
        assert_eq!(sys.pose_changes().largest, 0.0, "frame {k}: poses relative to the roots are unchanged");
        let v = sys.validate().unwrap();
        assert_eq!(v.intersecting_pairs, rest.intersecting_pairs, "frame {k}");
        assert_eq!(v.body_penetrations, rest.body_penetrations, "frame {k}");
    }
    let pitch: Vec<f32> = sys.feathers().iter().map(|f| f.pitch).collect();
    assert_eq!(pitch, rest_pitch, "feathers keep their pitch relative to their own frame");
    assert_eq!(rest.intersecting_pairs, 0, "the plate is collision-free at rest");
}

#[test]
fn a_local_bend_readjusts_only_feathers_near_it() {
    // Feathers point +x and lie on the ones ahead of them, so the region
    // behind (small x) is on top: folding it must not disturb the rest.
    let plate = grid(10.0, 10.0, 40, 40, 0.0, true);
    let mut sys = create(&plate, &plate_config(1200));
    let n = sys.feather_count();
    let spacing = sys.sampling_report().unwrap().spacing;
    let rest_x: Vec<f32> = sys.feathers().iter().map(|f| f.root[0]).collect();
    let hinge = 3.0f32;
    for k in 1..=4 {
        let frame = fold(&plate, hinge, 0.12 * k as f32);
        sys.step(&frame).unwrap();
        let touched: Vec<usize> = (0..n).filter(|&i| sys.readjusted()[i]).collect();
        assert!(!touched.is_empty(), "frame {k}: the bend readjusts something");
        let farthest = touched.iter().map(|&i| rest_x[i]).fold(f32::MIN, f32::max);
        println!(
            "frame {k}: {} of {n} readjusted, farthest at x = {farthest:.2} (hinge {hinge}, d = {spacing:.2})",
            touched.len()
        );
        assert!(farthest < hinge + 4.0 * spacing, "frame {k}: a feather at x = {farthest} is far from the bend");
        let v = sys.validate().unwrap();
        assert_eq!(v.intersecting_pairs, 0, "frame {k}");
    }
}

#[test]
fn a_slow_bend_is_caught_once_it_adds_up() {
    // The region before x = 3 folds up a little more every frame: each
    // step alone moves the feathers across the hinge far less than θs·L
    // relative to each other, but the motion adds up until they readjust.
    let plate = grid(10.0, 10.0, 40, 40, 0.0, true);
    let mut sys = create(&plate, &plate_config(1200));
    let hinge = 3.0f32;
    let mut adjusted = Vec::new();
    for k in 1..=30 {
        let frame = fold(&plate, hinge, 0.004 * k as f32);
        sys.step(&frame).unwrap();
        adjusted.push(sys.frame_report().unwrap().adjusted);
        assert_eq!(sys.validate().unwrap().intersecting_pairs, 0, "frame {k}");
    }
    println!("adjusted per frame under a slow bend: {adjusted:?}");
    assert_eq!(adjusted[0], 0, "one small step alone readjusts nothing");
    assert!(adjusted.iter().any(|&a| a > 0), "the accumulated bend is caught");
}

/// Two sheets side by side, the second sliding towards the first until
/// their feathers overlap: the first sheet's feathers (pointing +x) reach
/// over the second's roots.
fn two_sheets_closing(recompute: bool) -> (usize, usize) {
    let a = grid(6.0, 6.0, 24, 24, 0.0, true);
    let mut shape = a.clone();
    let gap0 = 8.0f32;
    let mut b = a.clone();
    for p in b.positions.chunks_mut(3) {
        p[0] += 6.0 + gap0;
    }
    shape.append(&b);
    let split = a.vertex_count();
    let cfg = Config { recompute_neighbourhoods: recompute, ..plate_config(700) };
    let mut sys = create(&shape, &cfg);
    let mut worst = 0;
    let frames = 8;
    let spacing = sys.sampling_report().unwrap().spacing;
    for k in 1..=frames {
        // The gap closes to a fifth of the spacing.
        let gap = gap0 + (0.2 * spacing - gap0) * k as f32 / frames as f32;
        let frame: Vec<f32> = shape
            .positions
            .chunks(3)
            .enumerate()
            .flat_map(|(v, p)| if v < split { [p[0], p[1], p[2]] } else { [p[0] - gap0 + gap, p[1], p[2]] })
            .collect();
        sys.step(&frame).unwrap();
        worst = worst.max(sys.validate().unwrap().intersecting_pairs);
    }
    (worst, sys.feather_count())
}

#[test]
fn sheets_brought_into_contact_see_each_other_with_recomputed_neighbourhoods() {
    let (with, n) = two_sheets_closing(true);
    let (without, _) = two_sheets_closing(false);
    println!("two sheets, {n} feathers: {with} intersecting pairs with recomputation, {without} without");
    assert_eq!(with, 0, "recomputed neighbourhoods keep the sheets collision-free");
    assert!(without > 0, "fixed neighbourhoods miss the contact (the paper's Fig. 8 limitation)");
}

#[test]
fn modes_differ_in_what_they_touch() {
    let plate = grid(10.0, 10.0, 30, 30, 0.0, true);
    let bend = |k: usize| {
        map_points(&plate, |p| {
            let a = 0.05 * k as f32;
            [p[0], p[1], p[2] + a * (p[0] - 5.0).powi(2) * 0.1]
        })
    };
    let mut counts = Vec::new();
    for mode in [Mode::Incremental, Mode::Legacy, Mode::Rebuild] {
        let mut sys = create(&plate, &Config { mode, ..plate_config(600) });
        let n = sys.feather_count();
        sys.step(&bend(1)).unwrap();
        let r = sys.frame_report().unwrap();
        if mode == Mode::Rebuild {
            assert_eq!(r.adjusted, n, "rebuild readjusts everything");
        }
        if mode == Mode::Legacy {
            assert_eq!(r.priority_changes, 0, "legacy never reorders");
        }
        counts.push(r.adjusted);
    }
    println!("adjusted per mode (incremental, legacy, rebuild): {counts:?}");
}

#[test]
fn a_bend_pops_what_it_snaps_and_the_figure_follows_the_threshold() {
    let plate = grid(10.0, 10.0, 40, 40, 0.0, true);
    let frame = fold(&plate, 3.0, 0.5);
    let mut changes = Vec::new();
    for threshold in [0.02f32, 0.2] {
        let mut sys = create(&plate, &Config { pop_threshold: threshold, ..plate_config(1200) });
        assert_eq!(sys.pose_changes().pops, 0, "create pops nothing");
        sys.step(&frame).unwrap();
        let c = sys.pose_changes();
        assert!(c.pops <= sys.feather_count() && c.largest >= 0.0);
        changes.push(c);
    }
    // The same step: the same largest change, fewer pops past the higher threshold.
    assert_eq!(changes[0].largest, changes[1].largest);
    assert!(changes[0].pops > 0 && changes[0].pops >= changes[1].pops, "{changes:?}");
}
