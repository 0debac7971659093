//! Adjusting one feather: its obstacles and the body near its root
//! rasterised into a [`HeightField`], the straight feather's pose chosen on
//! it ([`super::pitch_roll`]) and confirmed by the exact checks
//! ([`super::checks`]), shortened where no pose fits, then a segmented
//! shaft draped ([`super::drape`]).

use super::checks::{BoxesOf, CheckHints, FeatherInPlace, exact_check};
use super::drape::drape;
use super::height_field::JUDGE_FRACTION;
use super::obstacle::ObstacleBoxes;
use super::pitch_roll::choose_pose;
use super::raster::LocalMap;
use super::{AdjustOutcome, AdjustParams, AdjustSteps, DrapeRoute, HeightField, ObstacleFeather};
use crate::body::BodyIndex;
use crate::feather::{FeatherPose, FeatherShape, MAX_JOINTS};
use crate::geometry::RootFrame;

/// Sizes tried, largest first, for a feather that cannot lie down within
/// the pitch limit.
const SHRINK_STEPS: [f32; 8] = [0.85, 0.7, 0.6, 0.5, 0.4, 0.3, 0.22, 0.15];
/// Sizes below this are rasterised again (see [`adjust_feather`]): the root
/// socket, 2.5 % of the full length, is 5 % of a half-size feather.
const REFILL_BELOW: f32 = 0.5;
/// The relaxed judging distance near the root, as a fraction of the
/// length, tried before the field's conservative `JUDGE_FRACTION` (8 %).
/// The cells near the root mostly hold the vanes of the lateral
/// neighbours, which pass beside the root rather than over it (cells the
/// kite barely covers, rounded outward by half a cell); judged at 8 % of
/// the length, a neighbour's thickness there stands the feather up by
/// several degrees, and every later feather lying on it climbs as well.
/// A pose chosen with the relaxed distance is kept only if the exact check
/// passes and the feather also stays clear of every obstacle's top (see
/// [`raised_top`](super::obstacle::raised_top)), so the thickness is still respected.
/// Further out covers more, but the tighter coat leaves less slack for
/// motion: under the paper's rule (no exact checks while animating) it
/// then intersects (BENCHMARKS.md, "Measurements behind the code's
/// constants").
const RELAXED_JUDGE_FRACTION: f32 = 0.25;

/// Adjusts one feather: rasterises its obstacles and the body near its root
/// into `scratch`, then runs the chosen steps (see the module notes of
/// [`crate::adjustment`]). `previous` supplies the roll kept by
/// [`AdjustSteps::FinePitchOnly`]; [`AdjustSteps::Full`] does not read it,
/// so a full adjustment depends only on the geometry. Allocates nothing once
/// `scratch` has been used at this resolution.
#[allow(clippy::too_many_arguments)]
pub fn adjust_feather(
    frame: &RootFrame,
    shape: &FeatherShape,
    previous: FeatherPose,
    obstacles: &[ObstacleFeather],
    body: &BodyIndex,
    params: &AdjustParams,
    steps: AdjustSteps,
    scratch: &mut HeightField,
) -> AdjustOutcome {
    let (mut boxes, mut bounds) = (std::mem::take(&mut scratch.boxes), std::mem::take(&mut scratch.bounds));
    boxes.clear();
    boxes.extend(obstacles.iter().map(|o| ObstacleBoxes::new(&o.triangles, o.thickness)));
    bounds.clear();
    bounds.extend(boxes.iter().map(ObstacleBoxes::bounds));
    let at = FeatherInPlace {
        frame,
        shape,
        obstacles: BoxesOf { ids: None, all: &boxes, bounds: &bounds, aside: None },
        body,
    };
    let outcome = adjust_feather_boxed(&at, previous, obstacles, params, steps, scratch);
    (scratch.boxes, scratch.bounds) = (boxes, bounds);
    outcome
}

/// [`adjust_feather`] with the obstacles' [`ObstacleBoxes`] made already
/// (`boxes` lists them in the order of `obstacles`): the straight feather's
/// pose by the height field (and the exact checks), then, for a segmented
/// shaft, its drape (see [`drape`]).
pub(crate) fn adjust_feather_boxed(
    at: &FeatherInPlace<'_>,
    previous: FeatherPose,
    obstacles: &[ObstacleFeather],
    params: &AdjustParams,
    steps: AdjustSteps,
    scratch: &mut HeightField,
) -> AdjustOutcome {
    let straight = straight_pose(at, previous, obstacles, params, steps, scratch);
    if at.shape.segment_count() == 1 || params.bend_limit <= 0.0 || straight.pose.scale <= 0.0 {
        return straight;
    }
    let (draped, route) = drape(at, obstacles, straight.pose, params, scratch);
    AdjustOutcome { pose: draped, drape: route, ..straight }
}

/// The straight feather's pose (all joints unbent): the three steps on the
/// height field, each pose checked exactly, shortening where no pose fits.
fn straight_pose(
    at: &FeatherInPlace<'_>,
    previous: FeatherPose,
    obstacles: &[ObstacleFeather],
    params: &AdjustParams,
    steps: AdjustSteps,
    scratch: &mut HeightField,
) -> AdjustOutcome {
    let FeatherInPlace { frame, shape, body, .. } = *at;
    scratch.set_resolution(params.height_field_u, params.height_field_v);
    let collision_tests = fill_field(scratch, frame, shape, obstacles, body, params, false);
    // The height field is conservative but coarse, and blind to what it
    // leaves out (skin facing away, such as a wing hanging over the body;
    // feathers of the opposite skin). So every chosen pose is checked with
    // the exact tests of the validation against the obstacles and the
    // body. A feather that would have to stand steeper than the pitch
    // limit, or fails the check, is shortened instead, largest size first.
    // Down to `REFILL_BELOW` the filled field serves as it is (the shorter
    // kite covers a subset of it, and the root socket stays within the
    // validation's allowance); smaller sizes are rasterised again over
    // their own footprint.
    //
    // At each size the steps first judge the cells near the root at
    // `RELAXED_JUDGE_FRACTION` of the length (see there) and keep that
    // pose if it passes the exact check; only if not are they run again
    // with the conservative `JUDGE_FRACTION` of the height field.
    let mut filled_length = shape.length;
    let mut sizes = SHRINK_STEPS.iter().copied().filter(|&s| s >= params.min_scale);
    let mut scale = 1.0;
    let mut last = FeatherPose::new(params.max_pitch, 0.0);
    let mut hints = CheckHints::default();
    let found = 'sizes: loop {
        for judge in [RELAXED_JUDGE_FRACTION, JUDGE_FRACTION] {
            scratch.set_judge_fraction(judge, filled_length);
            let mut choice = choose_pose(scratch, previous, params, steps);
            choice.pose.scale = scale;
            last = choice.pose;
            let relaxed = judge != JUDGE_FRACTION;
            // The conservative judging demands at least the relaxed pitch
            // of every cell, so after a relaxed pose too steep for the limit
            // it would stand too steep as well; go to the next size. (Not a
            // proof once roll enters: BENCHMARKS.md has what the retry
            // changed.)
            if relaxed && choice.too_steep {
                break;
            }
            if !choice.too_steep && exact_check(at, choice.pose, scratch, relaxed, &mut hints) {
                if scale == 1.0 {
                    return AdjustOutcome {
                        pose: choice.pose,
                        collision_tests,
                        clamped: choice.clamped,
                        drape: DrapeRoute::Straight,
                    };
                }
                break 'sizes Some(choice);
            }
        }
        let Some(next) = sizes.next() else { break None };
        scale = next;
        let small = shape.scaled(scale);
        if scale < REFILL_BELOW {
            fill_field(scratch, frame, &small, obstacles, body, params, true);
            filled_length = small.length;
        } else {
            scratch.shape = small;
        }
    };
    // The height field found no clear pose at full size. Its lid semantics
    // (everything under an obstacle's top is solid) and its rounding are
    // the usual cause: at a wing root the body's feathers hover over the
    // root, and a feather could tuck under them; in a crease the rasterised
    // wall stands higher than the skin. So before shortening the feather
    // further, or leaving it out when no size fits (a root deep in a crease,
    // the rim of a blade-thin part), the exact checks alone look for the
    // lowest clear pitch, unrolled, at each larger size (see
    // [`exact_pitch_sweep`]). A shortened feather only gives way to a
    // larger one lying at most `SWEEP_MAX_PITCH` (standing higher, it would
    // cover less than the shorter one lying flatter); a feather that would
    // be left out takes any pitch up to the limit.
    let (smallest, max_pitch) = match found {
        Some(choice) => (choice.pose.scale, SWEEP_MAX_PITCH.min(params.max_pitch)),
        None => (0.0, params.max_pitch),
    };
    if let Some(pose) = exact_pitch_sweep(at, params, scratch, smallest, max_pitch, &mut hints) {
        return AdjustOutcome { pose, collision_tests, clamped: pose.scale < 1.0, drape: DrapeRoute::Straight };
    }
    match found {
        Some(choice) => {
            AdjustOutcome { pose: choice.pose, collision_tests, clamped: choice.clamped, drape: DrapeRoute::Straight }
        }
        None => AdjustOutcome {
            pose: FeatherPose { scale: 0.0, ..last },
            collision_tests,
            clamped: true,
            drape: DrapeRoute::Straight,
        },
    }
}

/// Pitches tried by [`exact_pitch_sweep`], from the lowest allowed up to
/// the highest, in even steps (3.9° with the default limits).
const SWEEP_PITCHES: usize = 24;
/// The highest pitch (radians, about 34°) at which the exact sweep may
/// replace a shortened feather by a larger one: the coverage gained levels
/// off past it (BENCHMARKS.md, "Measurements behind the code's constants").
const SWEEP_MAX_PITCH: f32 = 0.6;

/// The first pose clear by the exact check alone (and clear of the
/// obstacles' tops, see [`raised_top`](super::obstacle::raised_top)), trying the sizes of
/// `SHRINK_STEPS` larger than `smallest` (from full size), and at each
/// the pitches from the lowest allowed up to `max_pitch` in the steps of
/// `SWEEP_PITCHES`, unrolled.
/// Most feathers the height field leaves out (mostly at wing roots) find
/// a pose this way.
fn exact_pitch_sweep(
    at: &FeatherInPlace<'_>,
    params: &AdjustParams,
    scratch: &mut HeightField,
    smallest: f32,
    max_pitch: f32,
    hints: &mut CheckHints,
) -> Option<FeatherPose> {
    let FeatherInPlace { frame, shape, obstacles: boxes, .. } = *at;
    let sizes = std::iter::once(1.0).chain(SHRINK_STEPS.iter().copied().filter(|&s| s >= params.min_scale));
    let mut within = std::mem::take(&mut scratch.sweep_obstacles);
    let mut found = None;
    'sizes: for scale in sizes.take_while(|&s| s > smallest) {
        let near = boxes.within_reach(frame, &shape.scaled(scale), &mut within);
        for k in 0..=SWEEP_PITCHES {
            let t = k as f32 / SWEEP_PITCHES as f32;
            let pitch = params.min_pitch + t * (params.max_pitch - params.min_pitch);
            if pitch > max_pitch {
                break;
            }
            let pose = FeatherPose { pitch, roll: 0.0, scale, bends: [0.0; MAX_JOINTS] };
            if exact_check(&FeatherInPlace { obstacles: near, ..*at }, pose, scratch, true, hints) {
                found = Some(pose);
                break 'sizes;
            }
        }
    }
    scratch.sweep_obstacles = within;
    found
}

/// Clears `field` over `shape`'s footprint and rasterises the obstacles and
/// the body near the root. Returns the obstacles that touched it. A
/// `refill` (a smaller size of the same feather, at the same frame)
/// reuses the obstacles' local triangles of the first fill.
fn fill_field(
    field: &mut HeightField,
    frame: &RootFrame,
    shape: &FeatherShape,
    obstacles: &[ObstacleFeather],
    body: &BodyIndex,
    params: &AdjustParams,
    refill: bool,
) -> u32 {
    field.reset(shape, params.min_pitch);
    let near = || obstacles.iter().filter(|o| !o.far_side);
    let mut local = std::mem::take(&mut field.local_obstacles);
    if !refill {
        let map = LocalMap::new(frame);
        local.clear();
        local.extend(near().map(|o| map.triangles(&o.triangles)));
    }
    let mut collision_tests = 0u32;
    for (l, o) in local.iter().zip(near()) {
        if field.add_local_obstacle(l, o.thickness) {
            collision_tests += 1;
        }
    }
    field.local_obstacles = local;
    field.add_body(frame, body);
    collision_tests
}

#[cfg(test)]
mod tests {
    use super::super::checks::pose_is_clear;
    use super::*;
    use crate::feather::feather_triangles;
    use glam::Vec3;

    fn plane_body(size: f32) -> BodyIndex {
        let pos = [
            Vec3::new(-size, -size, 0.0),
            Vec3::new(size, -size, 0.0),
            Vec3::new(size, size, 0.0),
            Vec3::new(-size, size, 0.0),
        ];
        BodyIndex::from_mesh(&pos, &[[0, 1, 2], [0, 2, 3]])
    }

    fn frame_at(x: f32, y: f32) -> RootFrame {
        RootFrame::from_normal_and_direction(Vec3::new(x, y, 0.0), Vec3::Z, Vec3::X).unwrap()
    }

    fn adjust(
        frame: &RootFrame,
        obstacles: &[ObstacleFeather],
        body: &BodyIndex,
        params: &AdjustParams,
    ) -> AdjustOutcome {
        let shape = FeatherShape::for_spacing(1.0);
        let mut field = HeightField::new(params.height_field_u, params.height_field_v);
        adjust_feather(frame, &shape, FeatherPose::default(), obstacles, body, params, AdjustSteps::Full, &mut field)
    }

    #[test]
    fn alone_on_a_plane_the_feather_lies_at_the_body_clearance() {
        let params = AdjustParams::default();
        let out = adjust(&frame_at(0.0, 0.0), &[], &plane_body(10.0), &params);
        assert!((out.pose.pitch - params.body_clearance_angle).abs() < 2e-3, "{:?}", out.pose);
        assert!(out.pose.roll.abs() < 1e-4);
        assert!(!out.clamped);
        assert_eq!(out.collision_tests, 0);
    }

    #[test]
    fn skin_tilted_sideways_rolls_the_feather_onto_it() {
        // The root's normal is +z but the skin rises towards +y (as where an
        // interpolated normal differs from the face normal): rolling lays
        // the feather on the skin instead of pitching it over the slope.
        let params = AdjustParams::default();
        let slope = 0.1;
        let pos = [
            Vec3::new(-10.0, -10.0, -10.0 * slope),
            Vec3::new(10.0, -10.0, -10.0 * slope),
            Vec3::new(10.0, 10.0, 10.0 * slope),
            Vec3::new(-10.0, 10.0, 10.0 * slope),
        ];
        let body = BodyIndex::from_mesh(&pos, &[[0, 1, 2], [0, 2, 3]]);
        let frame = frame_at(0.0, 0.0);
        let shape = FeatherShape::for_spacing(1.0);
        let mut field = HeightField::new(32, 16);
        let mut run =
            |steps| adjust_feather(&frame, &shape, FeatherPose::default(), &[], &body, &params, steps, &mut field).pose;
        let rolled = run(AdjustSteps::Full);
        let flat = run(AdjustSteps::FinePitchOnly);
        assert!(rolled.roll > 0.5 * slope, "{rolled:?}");
        assert!(rolled.pitch < flat.pitch - 0.02, "{rolled:?} vs {flat:?}");
    }

    #[test]
    fn rolling_never_lifts_a_vane_corner() {
        let params = AdjustParams::default();
        let body = plane_body(10.0);
        let shape = FeatherShape::for_spacing(1.0);
        let frame = frame_at(0.0, 0.0);
        let mut rng = crate::rng::Rng::new(21);
        let mut field = HeightField::new(32, 16);
        for _ in 0..40 {
            let obstacles: Vec<ObstacleFeather> = (0..6)
                .map(|_| {
                    let at = frame_at(0.3 + 2.5 * rng.next_f32(), 2.4 * rng.next_f32() - 1.2);
                    let pose = FeatherPose::new(0.2 * rng.next_f32(), 0.2 * rng.next_f32() - 0.1);
                    ObstacleFeather {
                        triangles: feather_triangles(&at, &shape, pose),
                        thickness: shape.thickness,
                        far_side: false,
                    }
                })
                .collect();
            let run = |steps, field: &mut HeightField| {
                adjust_feather(&frame, &shape, FeatherPose::default(), &obstacles, &body, &params, steps, field).pose
            };
            let rolled = run(AdjustSteps::Full, &mut field);
            let flat = run(AdjustSteps::FinePitchOnly, &mut field);
            let corner = |p: FeatherPose| {
                let [_, _, left, right] = shape.kite_corners().map(|c| p.apply_local(c));
                left.z.max(right.z)
            };
            assert!(
                corner(rolled) <= corner(flat) + 0.05 * shape.thickness,
                "{rolled:?} lifts a corner above {flat:?}"
            );
            assert!(rolled.pitch <= flat.pitch + 1e-4);
        }
    }

    #[test]
    fn a_feather_tucks_under_an_obstacle_over_its_root() {
        let params = AdjustParams::default();
        let body = plane_body(10.0);
        let shape = FeatherShape::for_spacing(1.0);
        // A feather hovering right over the root, half a length up: the
        // height field counts everything under its top as solid, so no
        // size lies clear by the field; the exact sweep tucks the feather
        // under it, clear of it and of the skin.
        let mut other = frame_at(-0.5, 0.0);
        other.position.z = 0.3;
        let obstacle = ObstacleFeather {
            triangles: feather_triangles(&other, &shape, FeatherPose::default()),
            thickness: 0.1,
            far_side: false,
        };
        let frame = frame_at(0.0, 0.0);
        let out = adjust(&frame, &[obstacle], &body, &params);
        assert!(out.pose.scale > 0.0 && out.pose.pitch < 0.1, "{:?}", out.pose);
        let mut field = HeightField::new(32, 16);
        assert!(pose_is_clear(&frame, &shape, out.pose, &[obstacle], &body, &mut field));
    }

    #[test]
    fn convex_skin_lets_the_feather_droop_and_concave_skin_lifts_it() {
        let params = AdjustParams::default();
        let shape = FeatherShape::for_spacing(1.0);
        // A cylinder of radius r along y, root on top: convex along the shaft.
        let cylinder = |r: f32, inside: bool| {
            let (n, m) = (128usize, 8usize);
            let mut pos = Vec::new();
            for a in 0..n {
                let t = a as f32 / n as f32 * std::f32::consts::TAU;
                for b in 0..=m {
                    let y = -3.0 + 6.0 * b as f32 / m as f32;
                    pos.push(Vec3::new(r * t.sin(), y, r * t.cos() - r));
                }
            }
            let mut tris = Vec::new();
            for a in 0..n {
                for b in 0..m {
                    let (i0, i1) = ((a * (m + 1) + b) as u32, (((a + 1) % n) * (m + 1) + b) as u32);
                    let t = [[i0, i1, i1 + 1], [i0, i1 + 1, i0 + 1]];
                    for tri in t {
                        tris.push(if inside { [tri[0], tri[2], tri[1]] } else { tri });
                    }
                }
            }
            (BodyIndex::from_mesh(&pos, &tris), pos)
        };
        let mut field = HeightField::new(32, 16);
        let frame = frame_at(0.0, 0.0);
        let (convex, _) = cylinder(1.5, false);
        let out = adjust_feather(
            &frame,
            &shape,
            FeatherPose::default(),
            &[],
            &convex,
            &params,
            AdjustSteps::Full,
            &mut field,
        );
        assert!(out.pose.pitch < 0.0, "convex {:?}", out.pose);
        // Inside a cylinder the root sits at the bottom and the wall rises in front.
        let concave_frame = RootFrame::from_normal_and_direction(Vec3::new(0.0, 0.0, -8.0), Vec3::Z, Vec3::X).unwrap();
        let (concave, _) = cylinder(4.0, true);
        let out = adjust_feather(
            &concave_frame,
            &shape,
            FeatherPose::default(),
            &[],
            &concave,
            &params,
            AdjustSteps::Full,
            &mut field,
        );
        // The wall rises about x²/(2r) ahead: at x = L that is 0.4 L/r·L.
        assert!(out.pose.pitch > 0.3, "concave {:?}", out.pose);
    }

    #[test]
    fn fine_pitch_only_keeps_the_previous_roll() {
        let params = AdjustParams::default();
        let shape = FeatherShape::for_spacing(1.0);
        let mut field = HeightField::new(32, 16);
        let out = adjust_feather(
            &frame_at(0.0, 0.0),
            &shape,
            FeatherPose::new(0.4, 0.1),
            &[],
            &plane_body(10.0),
            &params,
            AdjustSteps::FinePitchOnly,
            &mut field,
        );
        assert_eq!(out.pose.roll, 0.1);
        // The lowered −y vane near the root needs a little pitch on a plane.
        assert!(out.pose.pitch > params.body_clearance_angle && out.pose.pitch < 0.2, "{:?}", out.pose);
    }

    #[test]
    fn fluffiness_adds_lift_and_the_limit_reports() {
        let body = plane_body(10.0);
        let base = adjust(&frame_at(0.0, 0.0), &[], &body, &AdjustParams::default()).pose.pitch;
        let fluffy = adjust(&frame_at(0.0, 0.0), &[], &body, &AdjustParams { fluffiness: 0.2, ..Default::default() });
        assert!((fluffy.pose.pitch - base - 0.2).abs() < 1e-5);
        assert!(!fluffy.clamped);
        let over = adjust(&frame_at(0.0, 0.0), &[], &body, &AdjustParams { fluffiness: 2.0, ..Default::default() });
        assert!(over.clamped && over.pose.pitch == AdjustParams::default().max_pitch);
    }
}
