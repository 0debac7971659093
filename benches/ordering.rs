//! Benchmarks of the ordering module on a bird-like body: 10 000 roots on an
//! ellipsoid, feathers flowing from head (+x) to tail.
//!
//! * `neighbourhoods/10k`: k-nearest neighbourhoods and the pair set.
//! * `neighbourhoods_and_obstacles/10k`: the same plus obstacle candidates
//!   for feathers three root spacings long.
//! * `static_order/10k`: priorities of every pair and the static order.
//! * `frame_reorder/10k_2pct`: one frame of incremental reordering when a
//!   local patch of 2 % of the roots deforms (`R_k`, alternating between two
//!   poses, so every iteration really reverses edges).

use criterion::{Criterion, criterion_group, criterion_main};
use glam::{Quat, Vec3};
use plumage::geometry::RootFrame;
use plumage::ordering::{NeighbourParams, Neighbourhoods, Priorities, PriorityOrder};
use std::hint::black_box;

const ROOTS: usize = 10_000;

/// Roots on a Fibonacci lattice mapped onto the ellipsoid with semi-axes
/// (2, 1, 1), feathers pointing towards −x (head at +x).
fn bird_body(n: usize) -> Vec<RootFrame> {
    let golden = std::f32::consts::PI * (3.0 - 5.0f32.sqrt());
    (0..n)
        .map(|i| {
            let y = 1.0 - 2.0 * (i as f32 + 0.5) / n as f32;
            let r = (1.0 - y * y).sqrt();
            let a = golden * i as f32;
            let unit = Vec3::new(y, r * a.cos(), r * a.sin());
            let p = unit * Vec3::new(2.0, 1.0, 1.0);
            let normal = p * Vec3::new(0.25, 1.0, 1.0);
            RootFrame::from_normal_and_direction(p, normal, -Vec3::X)
                .or_else(|| RootFrame::from_normal_and_direction(p, normal, Vec3::Y))
                .unwrap()
        })
        .collect()
}

/// The roots of a local patch (the `count` nearest to `centre`) and a pose
/// where that patch is deformed: a bump lifts it along the normal, tilting
/// the normals down its slope, and the feather directions twist about the
/// normal, most at the patch centre.
fn deformed_patch(frames: &[RootFrame], centre: Vec3, count: usize) -> (Vec<u32>, Vec<RootFrame>) {
    let mut by_distance: Vec<u32> = (0..frames.len() as u32).collect();
    by_distance.sort_by(|&a, &b| {
        let da = (frames[a as usize].position - centre).length_squared();
        let db = (frames[b as usize].position - centre).length_squared();
        da.total_cmp(&db).then(a.cmp(&b))
    });
    let mut patch: Vec<u32> = by_distance[..count].to_vec();
    let radius = (frames[*patch.last().unwrap() as usize].position - centre).length();
    let mut deformed = frames.to_vec();
    for &i in &patch {
        let f = &frames[i as usize];
        let offset = f.position - centre;
        let w = 1.0 - offset.length() / radius;
        let slope = (offset - f.normal * offset.dot(f.normal)).normalize_or_zero();
        let normal = (f.normal + slope * 0.8 * w).normalize();
        let twist = Quat::from_axis_angle(normal, 0.9 * w);
        let position = f.position + f.normal * 0.05 * w * w;
        deformed[i as usize] = RootFrame::from_normal_and_direction(position, normal, twist * f.tangent).unwrap_or(*f);
    }
    patch.sort_unstable();
    (patch, deformed)
}

fn benches(c: &mut Criterion) {
    let frames = bird_body(ROOTS);
    let params = NeighbourParams::default();
    let mut nb = Neighbourhoods::new();
    nb.rebuild(&frames, &[], &params);

    c.bench_function("neighbourhoods/10k", |b| b.iter(|| nb.rebuild(black_box(&frames), &[], &params)));

    // Feathers three root spacings long (the body's area is about 21.5).
    let reach = vec![3.0 * (21.5 / ROOTS as f32).sqrt(); ROOTS];
    let mut with_obstacles = Neighbourhoods::new();
    c.bench_function("neighbourhoods_and_obstacles/10k", |b| {
        b.iter(|| with_obstacles.rebuild(black_box(&frames), &reach, &params))
    });
    eprintln!(
        "obstacle candidates: {} (mean {:.1} per root)",
        with_obstacles.obstacle_csr().len(),
        with_obstacles.obstacle_csr().len() as f64 / ROOTS as f64
    );

    let mut deltas = Vec::new();
    let mut order = PriorityOrder::new();
    c.bench_function("static_order/10k", |b| {
        b.iter(|| {
            Priorities::improved(&frames, 0.6, 0.3).deltas_of_pairs(nb.pairs(), &mut deltas);
            black_box(order.build_static(frames.len(), nb.pairs(), &deltas))
        })
    });
    let report = order.build_static(frames.len(), nb.pairs(), &deltas);
    eprintln!("static order: {report:?}");

    let (patch, deformed) = deformed_patch(&frames, Vec3::new(0.3, 0.7, 0.7), ROOTS / 50);
    let poses = [Priorities::improved(&frames, 0.6, 0.3), Priorities::improved(&deformed, 0.6, 0.3)];
    let mut frame = 0usize;
    let mut sample = order.clone();
    let forward = sample.update_frame(None, &patch, &poses[1]);
    let back = sample.update_frame(None, &patch, &poses[0]);
    eprintln!("frame reorder (deform): {forward:?}");
    eprintln!("frame reorder (restore): {back:?}");
    c.bench_function("frame_reorder/10k_2pct", |b| {
        b.iter(|| {
            frame += 1;
            black_box(order.update_frame(None, &patch, &poses[frame % 2]))
        })
    });
}

criterion_group!(ordering, benches);
criterion_main!(ordering);
