//! `Walk` along the surface: exact on flat and developable meshes, stops at
//! boundaries, robust at vertices and on thin faces, never NaN.

mod common;

use common::shapes::{Shape, cylinder, grid};
use glam::Vec3;
use plumage::geometry::SurfacePoint;
use plumage::mesh::{MeshInput, weld};
use plumage::surface::{Surface, WalkEnd, WalkResult};
use proptest::prelude::*;
use std::f32::consts::{PI, TAU};

fn surface_of(shape: &Shape) -> (Surface, Vec<Vec3>) {
    let mesh = weld(&MeshInput::new(&shape.positions, &shape.indices)).unwrap();
    (Surface::new(&mesh), mesh.positions)
}

/// The surface point of `p` (on the z = 0 plate), found by barycentric test.
fn locate(s: &Surface, pos: &[Vec3], p: Vec3) -> SurfacePoint {
    for f in 0..s.face_count() {
        let [a, b, c] = s.corners(pos, f);
        let area = |u: Vec3, v: Vec3, w: Vec3| (v - u).cross(w - u).z;
        let total = area(a, b, c);
        let bary = [area(p, b, c) / total, area(a, p, c) / total, area(a, b, p) / total];
        if bary.iter().all(|&w| w >= -1e-6) {
            return SurfacePoint { face: f as u32, bary };
        }
    }
    panic!("{p} is not on the plate");
}

fn assert_on_mesh(s: &Surface, pos: &[Vec3], r: &WalkResult, distance: f32) {
    assert!((r.point.face as usize) < s.face_count(), "face {} out of range", r.point.face);
    let sum: f32 = r.point.bary.iter().sum();
    assert!(r.point.bary.iter().all(|w| w.is_finite() && (0.0..=1.0).contains(w)), "{:?}", r.point);
    assert!((sum - 1.0).abs() < 1e-4, "barycentrics sum to {sum}");
    assert!(s.position(pos, r.point).is_finite());
    assert!(r.direction.is_finite());
    assert!(r.travelled.is_finite() && r.travelled >= 0.0);
    let cap = if distance.is_finite() { distance.max(0.0) } else { 0.0 };
    assert!(r.travelled <= cap * (1.0 + 1e-4) + 1e-5, "travelled {} of {distance}", r.travelled);
}

#[test]
fn straight_lines_on_a_flat_grid_end_where_expected() {
    let (s, pos) = surface_of(&grid(10.0, 10.0, 13, 11, 0.0, true));
    let start = Vec3::new(4.3, 5.7, 0.0);
    let from = locate(&s, &pos, start);
    for k in 0..24 {
        let angle = k as f32 * TAU / 24.0 + 0.01;
        let dir = Vec3::new(angle.cos(), angle.sin(), 0.0);
        let r = s.walk(&pos, from, dir * 3.0, 3.7);
        assert_eq!(r.end, WalkEnd::Arrived, "angle {angle}");
        let expected = start + dir * 3.7;
        let got = s.position(&pos, r.point);
        assert!((got - expected).length() < 1e-4, "angle {angle}: {got} vs {expected}");
        assert!((r.travelled - 3.7).abs() < 1e-4);
        assert!((r.direction - dir).length() < 1e-4);
        assert!(r.edges_crossed > 0);
    }
}

#[test]
fn passing_exactly_through_grid_vertices_stays_on_the_line() {
    // 1 × 1 cells: the diagonal from a vertex runs through vertices only.
    let (s, pos) = surface_of(&grid(8.0, 8.0, 8, 8, 0.0, true));
    let from = locate(&s, &pos, Vec3::new(4.0, 4.0, 0.0));
    for dir in
        [Vec3::new(1.0, 1.0, 0.0), Vec3::new(-1.0, 1.0, 0.0), Vec3::new(1.0, 0.0, 0.0), Vec3::new(0.0, -1.0, 0.0)]
    {
        let r = s.walk(&pos, from, dir, 3.0);
        assert_eq!(r.end, WalkEnd::Arrived);
        let expected = Vec3::new(4.0, 4.0, 0.0) + dir.normalize() * 3.0;
        assert!((s.position(&pos, r.point) - expected).length() < 1e-4, "{dir}: {}", s.position(&pos, r.point));
    }
}

#[test]
fn once_around_a_cylinder_returns_to_the_start() {
    let (sides, radius) = (24, 2.0f32);
    let (s, pos) = surface_of(&cylinder(radius, 4.0, sides, 4));
    let perimeter = sides as f32 * 2.0 * radius * (PI / sides as f32).sin();
    // A point mid-height on the first quad of the ring, walking round it.
    let f = (0..s.face_count())
        .find(|&f| s.corners(&pos, f).iter().all(|c| c.z >= 1.0 - 1e-4 && c.z <= 2.0 + 1e-4))
        .unwrap();
    let from = SurfacePoint { face: f as u32, bary: [0.3, 0.3, 0.4] };
    let start = s.position(&pos, from);
    let normal = s.face_frame(&pos, f).normal;
    let around = normal.cross(Vec3::Z);
    let r = s.walk(&pos, from, around, perimeter);
    assert_eq!(r.end, WalkEnd::Arrived);
    let end = s.position(&pos, r.point);
    assert!((end - start).length() < 1e-3 * perimeter, "start {start}, end {end}");
    assert!(r.edges_crossed >= sides as u32);
    // Half way round is the antipode at the same height.
    let half = s.position(&pos, s.walk(&pos, from, around, perimeter / 2.0).point);
    assert!((half.z - start.z).abs() < 1e-4);
    assert!((half.truncate().length() - start.truncate().length()).abs() < 1e-3);
    assert!(half.truncate().dot(start.truncate()) < 0.0);
}

#[test]
fn stops_at_the_boundary_and_says_so() {
    let (s, pos) = surface_of(&grid(10.0, 10.0, 10, 10, 0.0, true));
    let start = Vec3::new(2.5, 3.5, 0.0);
    let from = locate(&s, &pos, start);
    let dir = Vec3::new(2.0, 1.0, 0.0).normalize();
    let r = s.walk(&pos, from, dir, 100.0);
    assert!(r.hit_boundary(), "{:?}", r.end);
    let WalkEnd::Boundary { face, side } = r.end else { unreachable!() };
    assert_eq!(face, r.point.face);
    assert!(s.is_boundary_side(face as usize, side as usize));
    let expected_t = (10.0 - 2.5) / dir.x; // leaves through x = 10
    assert!((r.travelled - expected_t).abs() < 1e-4, "travelled {}", r.travelled);
    assert!((s.position(&pos, r.point) - (start + dir * expected_t)).length() < 1e-4);
    assert!(r.point.bary[side as usize].abs() < 1e-6, "the end point is on the boundary side");
}

#[test]
fn a_non_manifold_edge_is_a_boundary() {
    // Two squares sharing the edge x = 1 plus a fin standing on it.
    let mut shape = grid(2.0, 1.0, 2, 1, 0.0, true);
    let base = shape.vertex_count() as u32;
    shape.positions.extend_from_slice(&[1.0, 0.0, 1.0, 1.0, 1.0, 1.0]);
    // Vertices 1 (1,0,0) and 4 (1,1,0) are the shared edge.
    shape.indices.extend_from_slice(&[1, 4, base + 1, 1, base + 1, base]);
    let (s, pos) = surface_of(&shape);
    assert!(s.non_manifold_edge_count() >= 1);
    let from = locate(&s, &pos, Vec3::new(0.5, 0.5, 0.0));
    let r = s.walk(&pos, from, Vec3::X, 1.5);
    assert!(r.hit_boundary());
    assert!((s.position(&pos, r.point).x - 1.0).abs() < 1e-5);
}

/// A bumpy, irregular grid with a row of sliver faces (height 1e-4 of their
/// length) and a closed box: the fuzzing meshes.
fn fuzz_meshes() -> Vec<(Surface, Vec<Vec3>)> {
    let mut bumpy = grid(6.0, 6.0, 12, 12, 0.0, true);
    for v in 0..bumpy.vertex_count() {
        let [x, y, _] = bumpy.vertex(v);
        let i = (x * 2.0).round() as i32;
        bumpy.positions[3 * v + 2] = 0.3 * (x * 1.3).sin() * (y * 0.7).cos();
        // Squash one column of cells almost flat: x of column 7 pulled to column 6.
        if i == 7 {
            bumpy.positions[3 * v] = 3.0 + 1e-4;
        }
    }
    let sphere_like = common::shapes::thin_box(3.0, 2.0, 1.0, 6, 4);
    vec![surface_of(&bumpy), surface_of(&sphere_like), surface_of(&cylinder(1.0, 3.0, 7, 3))]
}

proptest! {
    #![proptest_config(ProptestConfig { rng_seed: proptest::test_runner::RngSeed::Fixed(0x0070_6c75_6d61_6765), ..ProptestConfig::with_cases(256) })]

    #[test]
    fn walks_never_leave_the_mesh(
        mesh in 0usize..3,
        face_pick in 0.0f64..1.0,
        b in (0.0f32..1.0, 0.0f32..1.0),
        snap in 0u8..4,
        dir in (-1.0f32..1.0, -1.0f32..1.0, -1.0f32..1.0),
        distance in prop_oneof![Just(0.0f32), 0.0f32..30.0, Just(f32::INFINITY), Just(-1.0f32)],
    ) {
        thread_local! { static MESHES: Vec<(Surface, Vec<Vec3>)> = fuzz_meshes(); }
        MESHES.with(|meshes| {
            let (s, pos) = &meshes[mesh];
            let face = ((face_pick * s.face_count() as f64) as usize).min(s.face_count() - 1) as u32;
            // Some starts exactly on a vertex or an edge.
            let bary = match snap {
                0 => [1.0, 0.0, 0.0],
                1 => [0.0, b.0, 1.0 - b.0],
                _ => {
                    let (u, v) = if b.0 + b.1 > 1.0 { (1.0 - b.0, 1.0 - b.1) } else { b };
                    [1.0 - u - v, u, v]
                }
            };
            let start = SurfacePoint { face, bary };
            let r = s.walk(pos, start, Vec3::new(dir.0, dir.1, dir.2), distance);
            assert_on_mesh(s, pos, &r, distance);
        });
    }
}
