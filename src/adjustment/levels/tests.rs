use super::super::settle::SETTLED_TIP_GAP;
use super::*;
use crate::csr::CsrView;
use crate::feather::tip_position;
use crate::ordering::{NeighbourParams, Neighbourhoods};
use crate::rng::Rng;
use crate::validation::FeatherBoxes;

/// Two feathers on a flat skin, both pointing along +X: A (first in the
/// order) with its root at `a_x`, B at the origin, each the other's
/// candidate.
struct TwoFeathers {
    frames: [RootFrame; 2],
    shapes: [FeatherShape; 2],
    body: BodyIndex,
    params: AdjustParams,
}

impl TwoFeathers {
    fn new(segments: u32, a_x: impl Fn(&FeatherShape) -> f32) -> Self {
        let frame_at = |x: f32| RootFrame::from_normal_and_direction(Vec3::new(x, 0.0, 0.0), Vec3::Z, Vec3::X).unwrap();
        let shape = FeatherShape::for_spacing(1.0).with_segments(segments);
        let corners = [(-5.0, -5.0), (25.0, -5.0), (25.0, 5.0), (-5.0, 5.0)].map(|(x, y)| Vec3::new(x, y, -0.05));
        Self {
            frames: [frame_at(a_x(&shape)), frame_at(0.0)],
            shapes: [shape; 2],
            body: BodyIndex::from_mesh(&corners, &[[0, 1, 2], [0, 2, 3]]),
            params: AdjustParams::default(),
        }
    }

    /// Adjusts the selected feathers with `adjuster`, settling at `rate`.
    fn run(&self, adjuster: &mut Adjuster, poses: &mut [FeatherPose], selection: Selection<'_>, rate: f32) {
        let (offsets, indices) = ([0u32, 1, 2], [1u32, 0]);
        adjuster.adjust_in_order(
            &OrderedRun {
                frames: &self.frames,
                shapes: &self.shapes,
                order: &[0, 1],
                rank: &[0, 1],
                candidates: CsrView::new(&offsets, &indices),
                body: &self.body,
                params: &self.params,
                steps: AdjustSteps::Full,
                settle_rate: rate,
            },
            poses,
            selection,
        );
    }

    /// Whether B's triangles meet A's.
    fn meet(&self, poses: &[FeatherPose]) -> bool {
        let b = feather_triangles(&self.frames[1], &self.shapes[1], poses[1]);
        FeatherBoxes::new(&b).intersects(&feather_triangles(&self.frames[0], &self.shapes[0], poses[0]))
    }
}

/// An obstacle feather rises and falls back under the feather lying on
/// it: the feather above lifts at once, then settles over several
/// frames by at most the settle rate a frame, to the pose solved
/// without the limit, and never meets the obstacle (exact test), for
/// the kite and a bent shaft.
#[test]
fn a_feather_lifts_at_once_and_settles_over_frames() {
    for segments in [1u32, 4] {
        // A (earlier in the order) lies under B, one unit ahead of B's root.
        let scene = TwoFeathers::new(segments, |_| 1.0);
        let mut poses = vec![FeatherPose::default(); 2];
        let mut adjuster = Adjuster::new();
        scene.run(&mut adjuster, &mut poses, Selection::All, 0.0);
        let (a_rest, b_rest) = (poses[0], poses[1]);
        let rate = 0.03;
        let only_b = [false, true];
        // A rises: B lifts at once, clear of it.
        poses[0].pitch = a_rest.pitch + 0.3;
        assert!(scene.meet(&poses), "S = {segments}: the risen obstacle must reach B where it lay");
        scene.run(&mut adjuster, &mut poses, Selection::Subset(&only_b), rate);
        assert!(!scene.meet(&poses), "S = {segments}: B lifts clear at once");
        // Lifted at once: by more than the settle rate allows (a kite
        // pitches up; a bent feather may bend up instead).
        let lifted = crate::feather::pose_change(&b_rest, &poses[1]);
        assert!(lifted > 2.0 * rate, "S = {segments}: B moved by only {lifted} from {b_rest:?} to {:?}", poses[1]);
        // A falls back: B settles frame by frame to its pose solved at once.
        poses[0] = a_rest;
        let mut solved = poses.clone();
        scene.run(&mut Adjuster::new(), &mut solved, Selection::Subset(&only_b), 0.0);
        let mut frames_to_settle = 0;
        while poses[1] != solved[1] {
            let before = poses[1];
            scene.run(&mut adjuster, &mut poses, Selection::Subset(&only_b), rate);
            assert!(!scene.meet(&poses), "S = {segments}: B never passes through A");
            let change = crate::feather::pose_change(&before, &poses[1]);
            assert!(change <= rate + 1e-6, "S = {segments}: B moved by {change} in one frame");
            // Settling goes on until the pose, or (a bent feather) until
            // its tip is within the settled gap of the solved tip.
            let tip_high = super::super::settle::tip_above(&scene.frames[1], &scene.shapes[1], poses[1], solved[1]);
            if adjuster.settling()[1] {
                assert!(poses[1] != solved[1]);
            } else {
                assert!(poses[1] == solved[1] || (segments > 1 && !tip_high), "S = {segments}: stopped settling early");
            }
            frames_to_settle += 1;
            assert!(frames_to_settle < 200, "S = {segments}: B never settles");
        }
        println!(
            "S = {segments}: B from {:.3} lifted to {lifted:.3}, back to {:.3} in {frames_to_settle} frames",
            b_rest.pitch, solved[1].pitch
        );
        assert!(frames_to_settle >= 3, "S = {segments}: settled in {frames_to_settle} frames");
    }
}

/// A settling feather stops settling (is no longer a seed of the next
/// frame) once its tip is within [`SETTLED_TIP_GAP`] of its solved
/// pose's tip, before it reaches that pose.
#[test]
fn a_feather_stops_settling_when_its_tip_is_close_to_the_solved_one() {
    let scene = TwoFeathers::new(1, |_| 1.0);
    let mut poses = vec![FeatherPose::default(); 2];
    let mut adjuster = Adjuster::new();
    scene.run(&mut adjuster, &mut poses, Selection::All, 0.0);
    let a_rest = poses[0];
    poses[0].pitch += 0.3;
    scene.run(&mut adjuster, &mut poses, Selection::Subset(&[false, true]), 0.0);
    poses[0] = a_rest;
    let mut solved = poses.clone();
    scene.run(&mut Adjuster::new(), &mut solved, Selection::Subset(&[false, true]), 0.0);
    let (frame, shape) = (&scene.frames[1], &scene.shapes[1]);
    let tip = |p: FeatherPose| (tip_position(frame, shape, p) - frame.position).dot(frame.normal) / shape.length;
    let mut stopped_short = false;
    for _ in 0..400 {
        scene.run(&mut adjuster, &mut poses, Selection::Subset(&[false, true]), 0.002);
        let gap = tip(poses[1]) - tip(solved[1]);
        assert_eq!(adjuster.settling()[1], poses[1] != solved[1] && gap > SETTLED_TIP_GAP, "gap {gap}");
        stopped_short |= poses[1] != solved[1] && !adjuster.settling()[1];
        if poses[1] == solved[1] {
            break;
        }
    }
    assert!(stopped_short, "B must stop settling before it reaches its solved pose");
}

/// An obstacle rises a little every frame under a bent feather lying on
/// it: the feather is repaired from its last pose (its joints lift as
/// little as it takes) rather than draped afresh, so it follows the
/// obstacle smoothly: no frame changes it by more than a few times the
/// obstacle's rise, and it never meets the obstacle.
#[test]
fn a_bent_feather_follows_a_slowly_rising_obstacle_without_popping() {
    // A (earlier in the order) grows from under B's first quarter and
    // rises under B's outer segments.
    let scene = TwoFeathers::new(4, |shape| 0.25 * shape.length);
    let mut poses = vec![FeatherPose::default(); 2];
    let mut adjuster = Adjuster::new();
    scene.run(&mut adjuster, &mut poses, Selection::All, 0.0);
    let rise = 0.02;
    let (mut worst, mut lifted) = (0.0f32, 0);
    for _ in 0..25 {
        let before = poses[1];
        poses[0].pitch += rise;
        let was_met = scene.meet(&poses);
        scene.run(&mut adjuster, &mut poses, Selection::Subset(&[false, true]), 0.035);
        assert!(!scene.meet(&poses), "B clear of the risen obstacle");
        lifted += usize::from(was_met);
        worst = worst.max(crate::feather::pose_change(&before, &poses[1]));
    }
    println!("worst change a frame {:.2}°, {lifted} frames lifted", worst.to_degrees());
    // B keeps a clearance above A (a tenth of its thickness), so not every
    // rise of A reaches it.
    assert!(lifted >= 4, "the obstacle must push B up again and again ({lifted})");
    assert!(worst <= 4.0 * rise, "B changed by {:.2}° in one frame", worst.to_degrees());
}

/// `w × h` roots about a unit apart on a gently waving patch, pointing
/// along x.
fn wavy_patch(rng: &mut Rng, w: usize, h: usize) -> Vec<RootFrame> {
    (0..w * h)
        .map(|k| {
            let (x, y) = ((k % w) as f32 + 0.3 * rng.next_f32(), (k / w) as f32 + 0.3 * rng.next_f32());
            let normal = Vec3::new(0.1 * (x * 0.7).sin(), 0.1 * (y * 0.5).cos(), 1.0);
            RootFrame::from_normal_and_direction(Vec3::new(x, y, 0.0), normal, Vec3::new(1.0, 0.2, 0.0)).unwrap()
        })
        .collect()
}

/// An order with the tips first (the feathers farther along x are
/// earlier), and its ranks.
fn tips_first(frames: &[RootFrame]) -> (Vec<u32>, Vec<u32>) {
    let n = frames.len();
    let mut order: Vec<u32> = (0..n as u32).collect();
    order.sort_by(|&a, &b| frames[b as usize].position.x.total_cmp(&frames[a as usize].position.x).then(a.cmp(&b)));
    let mut rank = vec![0u32; n];
    for (k, &i) in order.iter().enumerate() {
        rank[i as usize] = k as u32;
    }
    (order, rank)
}

/// A sparse run gives the poses, adjusted and verified flags of a run
/// by levels over the same symmetric candidates, on one thread or several;
/// so does a verifying run's walk along the order, whose checks made ahead
/// (on the other threads as they come, or all before the walk) stand only
/// while no obstacle changed and are redone only against the obstacles
/// changed since.
#[test]
fn a_sparse_run_matches_the_levels() {
    let mut rng = Rng::new(7);
    let frames = wavy_patch(&mut rng, 14, 10);
    let n = frames.len();
    let shapes = vec![FeatherShape::for_spacing(1.0); n];
    let reach: Vec<f32> = shapes.iter().map(|s| s.length).collect();
    let mut nb = Neighbourhoods::new();
    nb.rebuild(&frames, &reach, &NeighbourParams::default());
    let candidates = nb.obstacle_csr();
    let (order, rank) = tips_first(&frames);
    let body = BodyIndex::from_mesh(
        &[
            Vec3::new(-5.0, -5.0, -0.05),
            Vec3::new(25.0, -5.0, -0.05),
            Vec3::new(25.0, 20.0, -0.05),
            Vec3::new(-5.0, 20.0, -0.05),
        ],
        &[[0, 1, 2], [0, 2, 3]],
    );
    let params = AdjustParams::default();
    let mut start = vec![FeatherPose::default(); n];
    let mut adjuster = Adjuster::new();
    let ordered = OrderedRun {
        frames: &frames,
        shapes: &shapes,
        order: &order,
        rank: &rank,
        candidates,
        body: &body,
        params: &params,
        steps: AdjustSteps::Full,
        settle_rate: 0.0,
    };
    // The earlier candidates alone, as a frame's obstacle rows hold them
    // (a relation that is not symmetric).
    let mut earlier_offsets = vec![0u32];
    let mut earlier_indices = Vec::new();
    for i in 0..n {
        earlier_indices.extend(candidates.row(i).iter().filter(|&&j| rank[j as usize] < rank[i]));
        earlier_offsets.push(earlier_indices.len() as u32);
    }
    let earlier_only = OrderedRun { candidates: CsrView::new(&earlier_offsets, &earlier_indices), ..ordered };
    let all = adjuster.adjust_in_order(&ordered, &mut start, Selection::All);
    assert_eq!(all.adjusted, n);
    let threads = [1, 3].map(|t| rayon::ThreadPoolBuilder::new().num_threads(t).build().unwrap());
    let mut checked = 0;
    for round in 0..8 {
        // Disturb some poses, then readjust a few seeds and check others.
        let mut poses = start.clone();
        for p in poses.iter_mut() {
            if rng.next_f32() < 0.15 {
                p.pitch += 0.8 * rng.next_f32() - 0.4;
                p.roll += 0.4 * rng.next_f32() - 0.2;
            }
        }
        let seeds: Vec<bool> = (0..n).map(|_| rng.next_f32() < 0.03 + 0.04 * round as f32).collect();
        // Few suspects, or (as in a frame where the whole body moves) all.
        let share = if round % 2 == 0 { 0.1 } else { 1.0 };
        let suspects: Vec<bool> = (0..n).map(|_| rng.next_f32() < share).collect();
        let threshold = 0.05 + 0.1 * round as f32;
        for selection in [
            Selection::Verify { seeds: &seeds, suspects: &suspects, threshold },
            Selection::Propagate { seeds: &seeds, threshold },
        ] {
            let run_ahead = |run: &OrderedRun<'_>, sparse: bool, pairs_only: bool, by_levels: bool, first: bool| {
                let mut adjuster =
                    Adjuster { by_levels, checks_ahead_first: first, pairs_only: Some(pairs_only), ..Adjuster::new() };
                let mut poses = poses.clone();
                let stats = adjuster.ordered_run(run, &mut poses, selection, &|_| true, sparse).unwrap();
                (poses, adjuster.adjusted().to_vec(), adjuster.verified().to_vec(), stats.adjusted, stats.verified)
            };
            let run_on = |run: &OrderedRun<'_>, sparse: bool, pairs_only: bool, by_levels: bool| {
                run_ahead(run, sparse, pairs_only, by_levels, false)
            };
            let run = |sparse: bool, pairs_only: bool| run_on(&ordered, sparse, pairs_only, true);
            if matches!(selection, Selection::Verify { .. }) {
                // Verifying, the walk along the order over the obstacle
                // rows' transpose, checking ahead on the other threads or
                // all first: the result of the levels, over the full rows
                // or the earlier candidates alone.
                for rows in [&ordered, &earlier_only] {
                    let by_levels = run_on(rows, false, false, true);
                    for t in &threads {
                        assert_eq!(t.install(|| run_on(rows, false, false, false)), by_levels, "round {round}");
                    }
                    assert_eq!(run_ahead(rows, false, false, false, true), by_levels, "round {round}");
                }
            }
            for pairs_only in [false, true] {
                // By levels on three threads and on one.
                let by_levels = threads[1].install(|| run(false, pairs_only));
                assert_eq!(by_levels, threads[0].install(|| run(false, pairs_only)), "round {round}");
                let sparse = run(true, pairs_only);
                checked += by_levels.3 + by_levels.4;
                assert_eq!(by_levels.0, sparse.0, "round {round}");
                assert_eq!(by_levels.1, sparse.1, "round {round}");
                assert_eq!(by_levels.2, sparse.2, "round {round}");
                assert_eq!((by_levels.3, by_levels.4), (sparse.3, sparse.4), "round {round}");
            }
        }
    }
    assert!(checked > n, "too little was adjusted or checked: {checked}");
}

/// A verifying walk over a patch of bent feathers that settle (lowered,
/// repaired in place and solved afresh while the walk sets its changes
/// aside) gives the poses, adjusted and verified flags of the levels, on
/// one thread and three, with its checks made ahead as they come or all
/// before it.
#[test]
fn a_verifying_walk_of_bent_feathers_matches_the_levels() {
    let mut rng = Rng::new(11);
    let frames = wavy_patch(&mut rng, 12, 9);
    let n = frames.len();
    let shapes = vec![FeatherShape::for_spacing(1.0).with_segments(4); n];
    let reach: Vec<f32> = shapes.iter().map(|s| s.length).collect();
    let mut nb = Neighbourhoods::new();
    nb.rebuild(&frames, &reach, &NeighbourParams::default());
    let (order, rank) = tips_first(&frames);
    let corners = [(-5.0, -5.0), (25.0, -5.0), (25.0, 20.0), (-5.0, 20.0)].map(|(x, y)| Vec3::new(x, y, -0.05));
    let body = BodyIndex::from_mesh(&corners, &[[0, 1, 2], [0, 2, 3]]);
    let params = AdjustParams::default();
    let run = OrderedRun {
        frames: &frames,
        shapes: &shapes,
        order: &order,
        rank: &rank,
        candidates: nb.obstacle_csr(),
        body: &body,
        params: &params,
        steps: AdjustSteps::Full,
        settle_rate: 0.035,
    };
    let mut start = vec![FeatherPose::default(); n];
    Adjuster::new().adjust_in_order(&run, &mut start, Selection::All);
    let threads = [1, 3].map(|t| rayon::ThreadPoolBuilder::new().num_threads(t).build().unwrap());
    let (mut kept, mut solved) = (0, 0);
    for round in 0..6 {
        // Some feathers pushed down into what lies under them, some
        // lifted off it; a few seeds.
        let mut poses = start.clone();
        for p in poses.iter_mut() {
            if rng.next_f32() < 0.3 {
                p.pitch += 0.3 * rng.next_f32() - 0.15;
                p.bends[0] += 0.2 * rng.next_f32() - 0.1;
            }
        }
        let seeds: Vec<bool> = (0..n).map(|_| rng.next_f32() < 0.05 + 0.03 * round as f32).collect();
        let suspects = vec![true; n];
        let selection = Selection::Verify { seeds: &seeds, suspects: &suspects, threshold: 0.02 };
        let walk = |by_levels: bool, checks_ahead_first: bool| {
            let mut adjuster = Adjuster { by_levels, checks_ahead_first, ..Adjuster::new() };
            let mut poses = poses.clone();
            let stats = adjuster.ordered_run(&run, &mut poses, selection, &|_| true, false).unwrap();
            (poses, adjuster.adjusted().to_vec(), adjuster.verified().to_vec(), stats.kept_in_place, stats.draped)
        };
        let by_levels = walk(true, false);
        for t in &threads {
            assert_eq!(t.install(|| walk(false, false)), by_levels, "round {round}");
        }
        assert_eq!(walk(false, true), by_levels, "round {round}");
        kept += by_levels.3;
        solved += by_levels.4;
    }
    // The walk met feathers kept in place and feathers solved afresh.
    assert!(kept > 10 && solved > 0, "kept in place {kept}, solved {solved}");
}

/// A bent feather of a verifying run is kept where it lies: once its
/// obstacle sinks away it comes down a step of at most the settle rate a
/// frame (never meeting the obstacle, exact test) and stops with room
/// beneath it; once the obstacle rises a little into it, it is lifted in
/// place by a small change rather than draped afresh. Neither is counted
/// as a drape. A kite in the same scene is solved afresh instead.
#[test]
fn a_bent_feather_is_lowered_and_repaired_in_place() {
    let scene = TwoFeathers::new(4, |_| 1.0);
    let mut poses = vec![FeatherPose::default(); 2];
    let mut adjuster = Adjuster::new();
    scene.run(&mut adjuster, &mut poses, Selection::All, 0.0);
    let rest = poses.clone();
    let rate = 0.035;
    let (seeds, none) = ([false, true], [false, false]);
    let verify = |threshold| Selection::Verify { seeds: &seeds, suspects: &none, threshold };
    // B stands raised (as if its obstacle had sunk away): it comes down a
    // step a frame.
    poses[1].pitch = rest[1].pitch + 0.3;
    assert!(!scene.meet(&poses));
    let mut steps = 0;
    loop {
        let before = poses[1];
        scene.run(&mut adjuster, &mut poses, verify(0.3), rate);
        assert!(adjuster.adjusted()[1], "a seed is visited");
        assert!(!scene.meet(&poses), "B never meets A on the way down");
        let change = crate::feather::pose_change(&before, &poses[1]);
        assert!(change <= rate + 1e-6, "B moved by {change} in one frame");
        if poses[1] == before {
            break;
        }
        assert!(poses[1].pitch <= before.pitch, "B only comes down");
        steps += 1;
        assert!(steps < 100, "B never comes to rest");
    }
    assert!(steps >= 5, "B came down in {steps} steps");
    // It has come well down from where it stood.
    assert!(
        poses[1].pitch < rest[1].pitch + 0.3 - 4.0 * rate,
        "B came down from {} to {}",
        rest[1].pitch + 0.3,
        poses[1].pitch
    );
    // A rises a little into B: B is lifted in place, by a small change.
    let lying = poses.clone();
    poses[0].pitch += 0.03;
    assert!(scene.meet(&poses), "the risen obstacle must reach B where it lies");
    scene.run(&mut adjuster, &mut poses, verify(0.3), rate);
    assert!(!scene.meet(&poses), "B is lifted clear of A");
    let change = crate::feather::pose_change(&lying[1], &poses[1]);
    assert!(
        change > 0.0 && change <= super::visit::REPAIR_MOST + 1e-6,
        "B was lifted by {change}: not a repair in place"
    );
    // A kite seed is solved afresh and settles toward that pose.
    let kites = TwoFeathers::new(1, |_| 1.0);
    let mut kite_poses = vec![FeatherPose::default(); 2];
    kites.run(&mut adjuster, &mut kite_poses, Selection::All, 0.0);
    let solved = kite_poses[1];
    kite_poses[1].pitch += 0.3;
    kites.run(&mut adjuster, &mut kite_poses, verify(0.3), rate);
    assert!((kite_poses[1].pitch - (solved.pitch + 0.3 - rate)).abs() < 1e-5, "{:?}", kite_poses[1]);
    assert!(adjuster.settling()[1], "the kite settles on toward its solved pose");
}
