//! Micro-benchmarks of small hot kernels (issue 8):
//!
//! * `reversal/single_10k`: one edge reversal in the dynamic topological
//!   order of 10 000 roots (`PriorityOrder::update_pairs` with one pair
//!   whose `ΔP` changed sign). Iterations alternate the sign, so every one
//!   really reverses the edge; the pair is one whose reversal needs no
//!   cycle breaking, with the median rank gap among such pairs.
//! * `walk/grid_*`, `walk/flamingo_*`: one `Surface::walk` of a sampling
//!   step (about the root spacing of a 10 000-feather coat) and a long one,
//!   on a flat grid and on the welded Flamingo (skipped, with a message,
//!   when `Flamingo.glb` is not in `$PLUMAGE_DATA_DIR` or `../shared/data`).
//! * `pose_roots/10k_*`: re-posing 10 000 roots from a deformed mesh
//!   (`roots::pose_roots`), on one thread and on the default pool.
//!
//! The height-field fill and the three adjustment steps of one feather are
//! in `benches/adjustment.rs`; a whole frame of reordering in
//! `benches/ordering.rs`.

#[path = "../tests/common/mod.rs"]
mod common;

use common::shapes::{Shape, cylinder, grid};
use criterion::{Criterion, criterion_group, criterion_main};
use glam::Vec3;
use plumage::geometry::{RootFrame, SurfacePoint};
use plumage::mesh::{MeshInput, weld};
use plumage::ordering::{NeighbourParams, Neighbourhoods, Priorities, PriorityOrder};
use plumage::rng::Rng;
use plumage::roots::{RootBinding, RootNormal, edge_basis_coordinates, pose_roots, root_id};
use plumage::surface::{Surface, vertex_normals_into};
use std::hint::black_box;
use std::time::Duration;

const ROOTS: usize = 10_000;

// ---- reversal -----------------------------------------------------------------

/// Roots on a Fibonacci lattice over the ellipsoid with semi-axes (2, 1, 1),
/// feathers pointing towards −x (the body of `benches/ordering.rs`).
fn ellipsoid_roots(n: usize) -> Vec<RootFrame> {
    let golden = std::f32::consts::PI * (3.0 - 5.0f32.sqrt());
    (0..n)
        .map(|i| {
            let y = 1.0 - 2.0 * (i as f32 + 0.5) / n as f32;
            let r = (1.0 - y * y).sqrt();
            let a = golden * i as f32;
            let p = Vec3::new(y, r * a.cos(), r * a.sin()) * Vec3::new(2.0, 1.0, 1.0);
            let normal = p * Vec3::new(0.25, 1.0, 1.0);
            RootFrame::from_normal_and_direction(p, normal, -Vec3::X)
                .or_else(|| RootFrame::from_normal_and_direction(p, normal, Vec3::Y))
                .unwrap()
        })
        .collect()
}

fn reversal(c: &mut Criterion) {
    let frames = ellipsoid_roots(ROOTS);
    let mut nb = Neighbourhoods::new();
    nb.rebuild(&frames, &[], &NeighbourParams::default());
    let mut deltas = Vec::new();
    Priorities::improved(&frames, 0.6, 0.3).deltas_of_pairs(nb.pairs(), &mut deltas);
    let mut order = PriorityOrder::new();
    order.build_static(frames.len(), nb.pairs(), &deltas);

    // Candidates: every 37th pair whose reversal (and its undoing) is a plain
    // reversal, no cycle rule involved; take the median rank gap.
    let mut clean: Vec<(u32, u32, u32, f32)> = Vec::new();
    for &(a, b) in nb.pairs().iter().step_by(37) {
        let Some(d) = order.pair_delta(a, b).filter(|d| *d != 0.0) else { continue };
        let mut trial = order.clone();
        let there = trial.update_pairs(&[(a, b, -d)]);
        let back = trial.update_pairs(&[(a, b, d)]);
        if there.reversals_done == 1 && back.reversals_done == 1 && there.cycles_broken + back.cycles_broken == 0 {
            let gap = order.rank_of(a).abs_diff(order.rank_of(b));
            clean.push((gap, a, b, d));
        }
    }
    clean.sort_by_key(|&(gap, a, b, _)| (gap, a, b));
    let (gap, a, b, d) = clean[clean.len() / 2];
    eprintln!(
        "reversal: {} candidate pairs reverse cleanly; benched pair ({a}, {b}), rank gap {gap} (max {})",
        clean.len(),
        clean.last().unwrap().0
    );
    let mut flip = 1.0f32;
    c.bench_function("reversal/single_10k", |bench| {
        bench.iter(|| {
            flip = -flip;
            black_box(order.update_pairs(black_box(&[(a, b, flip * d)])))
        })
    });
}

// ---- walk ---------------------------------------------------------------------

/// A welded mesh as the library sees it.
fn surface_of(shape: &Shape) -> (Surface, Vec<Vec3>, Vec<[u32; 3]>) {
    let mesh = weld(&MeshInput::new(&shape.positions, &shape.indices)).expect("a valid mesh");
    (Surface::new(&mesh), mesh.positions, mesh.triangles)
}

fn area(positions: &[Vec3], triangles: &[[u32; 3]]) -> f32 {
    triangles
        .iter()
        .map(|t| {
            let [a, b, c] = t.map(|v| positions[v as usize]);
            0.5 * (b - a).cross(c - a).length()
        })
        .sum()
}

/// Benches walks of `short` and `long` surface length from the centroid of
/// the largest face, along its first edge turned by 30° in its plane.
fn bench_walks(c: &mut Criterion, name: &str, shape: &Shape, short: f32, long: f32) {
    let (surface, positions, triangles) = surface_of(shape);
    let face = (0..triangles.len())
        .max_by(|&i, &j| {
            let a = |f: usize| area(&positions, &triangles[f..f + 1]);
            a(i).total_cmp(&a(j)).then(j.cmp(&i))
        })
        .unwrap();
    let [p0, p1, p2] = triangles[face].map(|v| positions[v as usize]);
    let normal = (p1 - p0).cross(p2 - p0).normalize();
    let direction = glam::Quat::from_axis_angle(normal, std::f32::consts::FRAC_PI_6) * (p1 - p0).normalize();
    let start = SurfacePoint { face: face as u32, bary: [1.0 / 3.0; 3] };
    for (label, distance) in [("step", short), ("long", long)] {
        let r = surface.walk(&positions, start, direction, distance);
        eprintln!(
            "walk/{name}_{label}: {} faces, distance {distance:.4}: travelled {:.4}, {} edges crossed, end {:?}",
            triangles.len(),
            r.travelled,
            r.edges_crossed,
            r.end
        );
        c.bench_function(&format!("walk/{name}_{label}"), |b| {
            b.iter(|| black_box(surface.walk(&positions, black_box(start), direction, distance)))
        });
    }
}

fn walk(c: &mut Criterion) {
    // A 10 × 10 plate of 40 × 40 quads: a 10 000-feather coat has spacing 0.1.
    bench_walks(c, "grid", &grid(10.0, 10.0, 40, 40, 0.0, true), 0.1, 4.0);
    if let Some(flamingo) = common::gltf_mesh::load_model("Flamingo.glb") {
        let (_, positions, triangles) = surface_of(&flamingo);
        let spacing = (area(&positions, &triangles) / ROOTS as f32).sqrt();
        let (lo, hi) = positions
            .iter()
            .fold((Vec3::splat(f32::MAX), Vec3::splat(f32::MIN)), |(lo, hi), &p| (lo.min(p), hi.max(p)));
        bench_walks(c, "flamingo", &flamingo, spacing, 0.2 * (hi - lo).length());
    } else {
        eprintln!("walk/flamingo_*: skipped (Flamingo.glb not found)");
    }
}

// ---- pose_roots ---------------------------------------------------------------

fn pose(c: &mut Criterion) {
    // A cylinder of 64 × 32 quads, roots at random faces and barycentrics,
    // feathers along the axis; the pose is a twist and a bend.
    let shape = cylinder(1.0, 4.0, 64, 32);
    let (_, rest, triangles) = surface_of(&shape);
    let mut rng = Rng::new(8);
    let roots: Vec<RootBinding> = (0..ROOTS)
        .map(|k| {
            let face = rng.below(triangles.len()) as u32;
            let (mut u, mut v) = (rng.next_f32(), rng.next_f32());
            if u + v > 1.0 {
                (u, v) = (1.0 - u, 1.0 - v);
            }
            let corners = triangles[face as usize].map(|i| rest[i as usize]);
            RootBinding {
                id: root_id(face, k as u64, 8),
                point: SurfacePoint { face, bary: [1.0 - u - v, u, v] },
                rest_direction: edge_basis_coordinates(corners, Vec3::Z),
                spacing: 0.05,
                length_scale: 1.0,
                width_scale: 1.0,
            }
        })
        .collect();
    let posed: Vec<Vec3> = rest
        .iter()
        .map(|p| {
            let twist = glam::Quat::from_rotation_z(0.3 * p.z);
            twist * *p + Vec3::new(0.1 * p.z * p.z, 0.0, 0.0)
        })
        .collect();
    let mut normals = Vec::new();
    vertex_normals_into(&posed, &triangles, &mut normals);
    let mut out = Vec::with_capacity(ROOTS);
    let one = rayon::ThreadPoolBuilder::new().num_threads(1).build().unwrap();
    c.bench_function("pose_roots/10k_one_thread", |b| {
        b.iter(|| {
            one.install(|| {
                pose_roots(black_box(&roots), &posed, &triangles, &normals, RootNormal::FaceLimited, &mut out)
            })
        })
    });
    c.bench_function("pose_roots/10k_default_pool", |b| {
        b.iter(|| pose_roots(black_box(&roots), &posed, &triangles, &normals, RootNormal::FaceLimited, &mut out))
    });
}

criterion_group! {
    name = kernels;
    config = Criterion::default().warm_up_time(Duration::from_millis(500)).measurement_time(Duration::from_secs(2));
    targets = reversal, walk, pose
}
criterion_main!(kernels);
