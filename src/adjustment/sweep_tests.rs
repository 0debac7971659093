//! Unit tests of `sweep.rs`.

use super::super::checks::pose_is_clear;
use super::super::{AdjustSteps, DrapeRoute, HeightField, adjust_feather};
use super::*;
use crate::body::BodyIndex;
use crate::feather::{feather_triangles, tip_position};
use crate::geometry::RootFrame;

fn shape() -> FeatherShape {
    FeatherShape::for_spacing(1.0).with_segments(4)
}

/// A surface from quads (corners counter-clockwise seen from +z).
fn quads(quads: &[[Vec3; 4]]) -> BodyIndex {
    let mut pos = Vec::new();
    let mut tris = Vec::new();
    for q in quads {
        let b = pos.len() as u32;
        pos.extend_from_slice(q);
        tris.extend_from_slice(&[[b, b + 1, b + 2], [b, b + 2, b + 3]]);
    }
    BodyIndex::from_mesh(&pos, &tris)
}

fn flat(x0: f32, x1: f32, z: f32) -> [Vec3; 4] {
    let w = 20.0;
    [Vec3::new(x0, -w, z), Vec3::new(x1, -w, z), Vec3::new(x1, w, z), Vec3::new(x0, w, z)]
}

fn root_at(x: f32, z: f32) -> RootFrame {
    RootFrame::from_normal_and_direction(Vec3::new(x, 0.0, z), Vec3::Z, Vec3::X).unwrap()
}

/// Three feathers ahead of a root at the origin on the flat `body`, each
/// adjusted lying on the one after it (a row of a coat).
fn stack_ahead(body: &BodyIndex) -> Vec<ObstacleFeather> {
    let (s, params) = (shape(), AdjustParams::default());
    let mut field = HeightField::new(params.height_field_u, params.height_field_v);
    let mut obstacles = Vec::new();
    for k in (1..=3).rev() {
        let frame = root_at(k as f32 * 0.25 * s.length, 0.0);
        let pose = adjust_feather(
            &frame,
            &s,
            FeatherPose::default(),
            &obstacles,
            body,
            &params,
            AdjustSteps::Full,
            &mut field,
        )
        .pose;
        obstacles.push(ObstacleFeather {
            triangles: feather_triangles(&frame, &s, pose),
            thickness: s.thickness,
            far_side: false,
        });
    }
    obstacles
}

/// Adjusts a bent feather at `frame` and checks that the swept drape
/// placed it, clear by the exact checks; returns its tip.
fn drape_at(frame: &RootFrame, obstacles: &[ObstacleFeather], body: &BodyIndex) -> Vec3 {
    let (shape, params) = (shape(), AdjustParams::default());
    let mut field = HeightField::new(params.height_field_u, params.height_field_v);
    let out =
        adjust_feather(frame, &shape, FeatherPose::default(), obstacles, body, &params, AdjustSteps::Full, &mut field);
    assert_eq!(out.drape, DrapeRoute::Swept, "the swept drape places it: {:?}", out.pose);
    assert!(pose_is_clear(frame, &shape, out.pose, obstacles, body, &mut field), "{:?}", out.pose);
    tip_position(frame, &shape, out.pose)
}

#[test]
fn over_a_step_the_tip_lies_on_the_upper_level() {
    // The skin steps up by three thicknesses halfway along the feather:
    // a kite must clear the step's edge and stands off the upper level;
    // the bent feather climbs it and lies down on it.
    let s = shape();
    let (edge, rise) = (0.5 * s.length, 3.0 * s.thickness);
    let body = quads(&[
        flat(-10.0, edge, 0.0),
        [
            Vec3::new(edge, -20.0, 0.0),
            Vec3::new(edge, -20.0, rise),
            Vec3::new(edge, 20.0, rise),
            Vec3::new(edge, 20.0, 0.0),
        ],
        flat(edge, 10.0, rise),
    ]);
    let tip = drape_at(&root_at(0.0, 0.0), &[], &body);
    let height = tip.z - rise;
    println!("step: tip {:.2} thicknesses above the upper level", height / s.thickness);
    assert!(height < 3.0 * s.thickness, "tip {:.4} thicknesses above the upper level", height / s.thickness);
}

#[test]
fn over_a_cylinder_the_tip_follows_the_skin() {
    // Root on top of a cylinder of radius 1.2 lengths, the feather
    // running around it: the skin falls 0.4 lengths below the tangent
    // plane at the tip, more than the lowest pitch lets a kite follow.
    let s = shape();
    let r = 1.2 * s.length;
    let n = 256;
    let mut pos = Vec::new();
    for a in 0..n {
        let t = a as f32 / n as f32 * std::f32::consts::TAU;
        for y in [-3.0f32, 3.0] {
            pos.push(Vec3::new(r * t.sin(), y, r * t.cos() - r));
        }
    }
    let mut tris = Vec::new();
    for a in 0..n as u32 {
        let (i, j) = (2 * a, 2 * ((a + 1) % n as u32));
        tris.extend_from_slice(&[[i, j, j + 1], [i, j + 1, i + 1]]);
    }
    let body = BodyIndex::from_mesh(&pos, &tris);
    let tip = drape_at(&root_at(0.0, 0.0), &[], &body);
    let height = (tip - Vec3::new(0.0, tip.y, -r)).length() - r;
    println!("cylinder: tip {:.2} thicknesses off the skin", height / s.thickness);
    assert!(height < 3.0 * s.thickness, "tip {:.4} thicknesses off the skin", height / s.thickness);
}

#[test]
fn on_a_stack_of_feathers_the_tip_lies_on_the_top_one() {
    // Three feathers ahead of the root, each lying on the one after it
    // (a row of a coat): the tip lies on the nearest of them, which is
    // the top of the stack there.
    let s = shape();
    let body = quads(&[flat(-10.0, 10.0, 0.0)]);
    let obstacles = stack_ahead(&body);
    let tip = drape_at(&root_at(0.0, 0.0), &obstacles, &body);
    // The stack beneath the tip: the feathers rooted behind it, one
    // thickness each.
    let beneath = obstacles.len() as f32;
    let height = tip.z - beneath * s.thickness;
    println!("stack: tip {:.2} thicknesses above the stack", height / s.thickness);
    assert!(height < 3.0 * s.thickness, "tip {:.4} thicknesses above the stack", height / s.thickness);
}

#[test]
fn passing_prisms_over_by_their_bounding_angle_changes_no_answer() {
    // Random obstacle and skin triangles round segments at random joints
    // and sweeps: the lowest clear angle (or a block) is the same with the
    // prisms ruled out by their boxes passed over and with every one cut.
    let mut unit = xorshift(0x9e37_79b9);
    let (mut differ, mut raised, mut blocked) = (0, 0, 0);
    for _ in 0..400 {
        let joint = Vec2::new(unit() * 0.6, unit() * 0.2);
        let seg = Segment {
            joint,
            length: 0.3,
            skin_from: 0.0,
            pieces: [(0.0, 0.1, 0.05), (0.1, 0.2, 0.08), (0.2, 0.3, 0.06)],
        };
        let lo = -0.6 + 0.4 * unit();
        let hi = lo + 0.2 + 0.8 * unit();
        let mut swept = Vec::new();
        for _ in 0..40 {
            let c = Vec3::new(joint.x - 0.2 + 0.7 * unit(), 0.3 * (unit() - 0.5), joint.y - 0.3 + 0.5 * unit());
            let t = [0, 1, 2].map(|_| c + 0.15 * Vec3::new(unit() - 0.5, unit() - 0.5, 0.4 * (unit() - 0.5)));
            let skin = unit() < 0.3;
            push_swept(&mut swept, &[t], if skin { 0.0 } else { 0.01 }, skin, |p| p);
        }
        let pruned = lowest_clear_angle_pruned(&swept, &seg, (lo, hi), true);
        let every = lowest_clear_angle_pruned(&swept, &seg, (lo, hi), false);
        differ += usize::from(pruned.map(f32::to_bits) != every.map(f32::to_bits));
        raised += usize::from(every.is_some_and(|a| a > lo));
        blocked += usize::from(every.is_none());
    }
    assert_eq!(differ, 0);
    // Both outcomes occur, and raised angles do.
    assert!(raised > 40 && blocked > 40, "raised {raised}, blocked {blocked}");
}

#[test]
fn a_repair_given_up_past_its_largest_change_finds_every_small_repair() {
    // The top feather of a stack pushed down into the one beneath it by
    // random amounts: a repair that gives up once an angle must change by
    // more than `most` finds exactly the repairs within `most` that an
    // unbounded one finds.
    use super::super::checks::{BoxesOf, FeatherInPlace};
    use super::super::drape::repair_drape;
    use super::super::obstacle::{ObstacleBounds, ObstacleBoxes};
    use crate::feather::pose_change;
    let (s, params) = (shape(), AdjustParams::default());
    let body = quads(&[flat(-10.0, 10.0, 0.0)]);
    let mut field = HeightField::new(params.height_field_u, params.height_field_v);
    let obstacles = stack_ahead(&body);
    let boxes: Vec<ObstacleBoxes> = obstacles.iter().map(|o| ObstacleBoxes::new(&o.triangles, o.thickness)).collect();
    let bounds: Vec<ObstacleBounds> = boxes.iter().map(ObstacleBoxes::bounds).collect();
    let frame = root_at(0.0, 0.0);
    let at = FeatherInPlace {
        frame: &frame,
        shape: &s,
        obstacles: BoxesOf { ids: None, all: &boxes, bounds: &bounds, aside: None },
        body: &body,
    };
    let rest =
        adjust_feather(&frame, &s, FeatherPose::default(), &obstacles, &body, &params, AdjustSteps::Full, &mut field)
            .pose;
    let mut unit = xorshift(0x2545_f491);
    let (mut within, mut beyond) = (0, 0);
    for _ in 0..200 {
        let mut start = rest;
        start.pitch -= 0.12 * unit();
        for b in start.bends.iter_mut().take(3) {
            *b -= 0.12 * unit() - 0.03;
        }
        let most = 0.01 + 0.05 * unit();
        let unbounded = repair_drape(&at, start, f32::INFINITY, &params, &mut field);
        let small = unbounded.filter(|p| pose_change(&start, p) <= most);
        let bounded = repair_drape(&at, start, most, &params, &mut field).filter(|p| pose_change(&start, p) <= most);
        assert_eq!(bounded, small, "{start:?} within {most}");
        within += usize::from(small.is_some_and(|p| p != start));
        beyond += usize::from(unbounded.is_some() && small.is_none());
    }
    // Both kinds occur: repairs that move the feather within the bound,
    // and repairs beyond it.
    assert!(within > 20 && beyond > 20, "within {within}, beyond {beyond}");
}

/// Numbers in [0, 1] from a xorshift generator seeded with `seed`.
fn xorshift(mut seed: u32) -> impl FnMut() -> f32 {
    move || {
        seed ^= seed << 13;
        seed ^= seed >> 17;
        seed ^= seed << 5;
        seed as f32 / u32::MAX as f32
    }
}
