//! Unit tests of `triangle_grid.rs`.

use super::*;
use crate::rng::Rng;

fn random_triangles(n: usize, seed: u64) -> Vec<[Vec3; 3]> {
    let mut r = Rng::new(seed);
    let mut v = |s: f32| Vec3::new(r.next_f32(), r.next_f32(), r.next_f32()) * s;
    (0..n)
        .map(|_| {
            let c = v(10.0);
            [c + v(1.0), c + v(1.0), c + v(1.0)]
        })
        .collect()
}

#[test]
fn box_query_matches_brute_force_without_duplicates() {
    let tris = random_triangles(500, 3);
    let mut g = TriangleGrid::new();
    g.rebuild(tris.iter().copied(), None);
    let mut out = Vec::new();
    let mut r = Rng::new(9);
    for _ in 0..50 {
        let c = Vec3::new(r.next_f32(), r.next_f32(), r.next_f32()) * 11.0;
        let q = Aabb::around(c, 0.1 + 2.0 * r.next_f32());
        g.query_box(&q, &mut out);
        let mut want: Vec<u32> =
            (0..tris.len() as u32).filter(|&t| Aabb::of_triangle(&tris[t as usize]).overlaps(&q)).collect();
        let mut got = out.clone();
        got.sort_unstable();
        assert_eq!(got.len(), out.len());
        got.dedup();
        assert_eq!(got.len(), out.len(), "duplicates reported");
        want.sort_unstable();
        assert_eq!(got, want);
    }
}

#[test]
fn ray_cast_finds_the_nearest_triangle() {
    let tris = random_triangles(400, 5);
    let mut g = TriangleGrid::new();
    g.rebuild(tris.iter().copied(), Some(0.7));
    let mut r = Rng::new(11);
    for _ in 0..100 {
        let o = Vec3::new(r.next_f32(), r.next_f32(), r.next_f32()) * 12.0 - Vec3::ONE;
        let d = (Vec3::new(r.next_f32(), r.next_f32(), r.next_f32()) - 0.5).normalize();
        let got = g.ray_cast(o, d, 8.0, |t| ray_triangle(o, d, tris[t as usize]));
        let want = (0..tris.len() as u32)
            .filter_map(|t| ray_triangle(o, d, tris[t as usize]).filter(|&s| s <= 8.0).map(|s| (s, t)))
            .min_by(|a, b| a.0.total_cmp(&b.0).then(a.1.cmp(&b.1)));
        assert_eq!(got.map(|h| (h.t, h.triangle)), want);
    }
}
