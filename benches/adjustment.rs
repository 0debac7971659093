//! Height-field adjustment speed: one feather (fill + three steps) against
//! about ten obstacles, and ordered adjustment of a few thousand feathers
//! on one core and on the whole default pool: a plane, a sphere and the
//! Flamingo at rest as the library dresses it (2000 feathers, flow from the
//! head; skipped when the model is not available, see
//! `tests/common/gltf_mesh.rs`), whose per-feather time is the figure of
//! the static adjustment.

#[path = "../tests/common/mod.rs"]
mod common;

use criterion::{Criterion, Throughput, criterion_group, criterion_main};
use glam::Vec3;
use plumage::Config;
use plumage::adjustment::{
    AdjustParams, AdjustSteps, Adjuster, HeightField, ObstacleFeather, OrderedRun, Selection, adjust_feather,
};
use plumage::body::BodyIndex;
use plumage::coat::{Coat, Dressing};
use plumage::csr::CsrView;
use plumage::feather::{FeatherPose, FeatherShape, feather_triangles};
use plumage::field::{Fields, VertexMaps};
use plumage::frame::{Workspace, solve};
use plumage::geometry::RootFrame;
use plumage::mesh::{MeshInput, weld};
use plumage::progress::Progress;
use plumage::rng::Rng;
use plumage::sampling::sample_roots_with_progress;
use plumage::surface::Surface;
use std::hint::black_box;
use std::time::Duration;

/// Roots, body, order and candidates of a bench scene.
struct Scene {
    body: BodyIndex,
    frames: Vec<RootFrame>,
    shapes: Vec<FeatherShape>,
    order: Vec<u32>,
    rank: Vec<u32>,
    offsets: Vec<u32>,
    candidates: Vec<u32>,
    params: AdjustParams,
}

impl Scene {
    /// Order tip side first along `flow`, candidates within `L_i + L_j`.
    fn new(body: BodyIndex, frames: Vec<RootFrame>, d: f32, flow: Vec3) -> Self {
        let shapes = vec![FeatherShape::for_spacing(d); frames.len()];
        let mut order: Vec<u32> = (0..frames.len() as u32).collect();
        order.sort_by(|&i, &j| {
            let key = |k: u32| -frames[k as usize].position.dot(flow);
            key(i).total_cmp(&key(j)).then(i.cmp(&j))
        });
        let mut rank = vec![0u32; frames.len()];
        for (k, &i) in order.iter().enumerate() {
            rank[i as usize] = k as u32;
        }
        let reach = 2.0 * shapes[0].length;
        let mut offsets = vec![0u32];
        let mut candidates = Vec::new();
        for i in 0..frames.len() {
            for j in 0..frames.len() {
                if i != j && (frames[i].position - frames[j].position).length() <= reach {
                    candidates.push(j as u32);
                }
            }
            offsets.push(candidates.len() as u32);
        }
        Scene { body, frames, shapes, order, rank, offsets, candidates, params: AdjustParams::default() }
    }

    /// The Flamingo at rest as `System::new` dresses it on one thread:
    /// its roots, order, obstacle candidates and body, taken from the
    /// solved coat.
    fn flamingo() -> Option<Self> {
        let model = common::gltf_mesh::load_model("Flamingo.glb")?;
        let head = Vec3::new(0.0, 0.0, 100.4);
        let config = Config { target_feathers: 2000, threads: 1, flow_source: Some(head), ..Config::default() };
        let mesh = weld(&MeshInput::new(&model.positions, &model.indices)).ok()?;
        let surface = Surface::new(&mesh);
        let fields = Fields::new(&mesh, &surface, &VertexMaps::default(), &config).ok()?;
        let sampling = sample_roots_with_progress(&mesh, &surface, &fields, &config, &Progress::none()).ok()?;
        let dressing = Dressing::new(surface, &mesh, sampling.roots, &config);
        let mut coat = Coat::default();
        solve(&mut coat, &dressing, &mesh.positions, &mut Workspace::default(), &Progress::none()).ok()?;
        let rows = coat.neighbourhoods.obstacle_csr();
        Some(Scene {
            offsets: rows.offsets().to_vec(),
            candidates: rows.items().to_vec(),
            order: coat.order.order().to_vec(),
            rank: coat.order.ranks().to_vec(),
            body: coat.body,
            frames: coat.frames,
            shapes: dressing.shapes,
            params: dressing.adjust_params,
        })
    }

    fn adjust(&self, adjuster: &mut Adjuster, poses: &mut [FeatherPose]) -> plumage::adjustment::AdjustStats {
        adjuster.adjust_in_order(
            &OrderedRun {
                frames: &self.frames,
                shapes: &self.shapes,
                order: &self.order,
                rank: &self.rank,
                candidates: CsrView::new(&self.offsets, &self.candidates),
                body: &self.body,
                params: &self.params,
                steps: AdjustSteps::Full,
                settle_rate: 0.0,
            },
            poses,
            Selection::All,
        )
    }
}

fn grid_mesh(nu: usize, nv: usize, f: impl Fn(f32, f32) -> Vec3) -> (Vec<Vec3>, Vec<[u32; 3]>) {
    let mut pos = Vec::new();
    for j in 0..=nv {
        for i in 0..=nu {
            pos.push(f(i as f32 / nu as f32, j as f32 / nv as f32));
        }
    }
    let id = |i: usize, j: usize| (j * (nu + 1) + i) as u32;
    let mut tris = Vec::new();
    for j in 0..nv {
        for i in 0..nu {
            tris.push([id(i, j), id(i + 1, j), id(i + 1, j + 1)]);
            tris.push([id(i, j), id(i + 1, j + 1), id(i, j + 1)]);
        }
    }
    (pos, tris)
}

/// Staggered roots (step 1.3 d, about a Poisson-disk set's density) on a
/// plane, flow along +x.
fn plane_scene(w: f32, h: f32) -> Scene {
    let (pos, tris) = grid_mesh(32, 32, |u, v| Vec3::new(-8.0 + (w + 16.0) * u, -4.0 + (h + 8.0) * v, 0.0));
    let s = 1.3;
    let row = s * 0.75f32.sqrt();
    let mut r = Rng::new(3);
    let mut frames = Vec::new();
    for j in 0..=((h / row) as usize) {
        for i in 0..=((w / s) as usize) {
            let x = i as f32 * s + if j % 2 == 1 { 0.5 * s } else { 0.0 } + 0.05 * r.next_f32();
            let p = Vec3::new(x, j as f32 * row + 0.05 * r.next_f32(), 0.0);
            frames.push(RootFrame::from_normal_and_direction(p, Vec3::Z, Vec3::X).unwrap());
        }
    }
    Scene::new(BodyIndex::from_mesh(&pos, &tris), frames, 1.0, Vec3::X)
}

/// A Fibonacci lattice on a UV sphere (96 × 48 quads), flow towards +z,
/// with the north pole (a sink of the flow) left bare.
fn sphere_scene(n: usize) -> Scene {
    let (pos, tris) = grid_mesh(96, 48, |u, v| {
        let (theta, phi) = (std::f32::consts::TAU * u, std::f32::consts::PI * v);
        Vec3::new(phi.sin() * theta.cos(), phi.sin() * theta.sin(), -phi.cos())
    });
    let tris: Vec<[u32; 3]> = tris
        .into_iter()
        .filter(|t| {
            let [a, b, c] = t.map(|v| pos[v as usize]);
            (b - a).cross(c - a).length() > 1e-9
        })
        .collect();
    let d = 0.9 * (4.0 * std::f32::consts::PI / n as f32).sqrt();
    let bare = 0.6 * FeatherShape::for_spacing(d).length;
    let body = BodyIndex::from_mesh(&pos, &tris);
    let mut scratch = Vec::new();
    let golden = std::f32::consts::PI * (3.0 - 5.0f32.sqrt());
    let frames = (0..n)
        .filter_map(|k| {
            let z = 1.0 - 2.0 * (k as f32 + 0.5) / n as f32;
            let r = (1.0 - z * z).sqrt();
            let a = golden * k as f32;
            let p = Vec3::new(r * a.cos(), r * a.sin(), z);
            if (p - Vec3::Z).length() < bare {
                return None;
            }
            // Plant the root on the (inscribed) mesh, with the sphere's normal.
            let on_mesh = body.closest_point(p, 0.1, &mut scratch)?.point;
            RootFrame::from_normal_and_direction(on_mesh, p, Vec3::Z)
        })
        .collect();
    Scene::new(body, frames, d, Vec3::Z)
}

fn one_feather(c: &mut Criterion) {
    let scene = plane_scene(24.0, 16.0);
    let mut poses = vec![FeatherPose::default(); scene.frames.len()];
    scene.adjust(&mut Adjuster::new(), &mut poses);
    // A feather in the middle of the coat and its ten nearest earlier
    // neighbours (the ones its vanes actually reach).
    let i = scene.order[scene.order.len() / 2] as usize;
    let mut earlier: Vec<usize> = (0..scene.frames.len()).filter(|&j| scene.rank[j] < scene.rank[i]).collect();
    let dist = |j: usize| (scene.frames[j].position - scene.frames[i].position).length();
    earlier.sort_by(|&a, &b| dist(a).total_cmp(&dist(b)));
    let obstacles: Vec<ObstacleFeather> = earlier[..10]
        .iter()
        .map(|&j| ObstacleFeather {
            triangles: feather_triangles(&scene.frames[j], &scene.shapes[j], poses[j]),
            thickness: scene.shapes[j].thickness,
            far_side: false,
        })
        .collect();
    let params = AdjustParams::default();
    let mut field = HeightField::new(32, 16);
    let mut group = c.benchmark_group("one_feather");
    group.bench_function("fill_and_three_steps_10_obstacles", |b| {
        b.iter(|| {
            adjust_feather(
                &scene.frames[i],
                &scene.shapes[i],
                poses[i],
                black_box(&obstacles),
                &scene.body,
                &params,
                AdjustSteps::Full,
                &mut field,
            )
        })
    });
    group.bench_function("fill_only_10_obstacles", |b| {
        b.iter(|| {
            field.reset(&scene.shapes[i], params.min_pitch);
            for o in black_box(&obstacles) {
                field.add_obstacle(&scene.frames[i], &o.triangles, o.thickness);
            }
            field.add_body(&scene.frames[i], &scene.body);
        })
    });
    group.finish();
}

fn in_order(c: &mut Criterion) {
    let one = rayon::ThreadPoolBuilder::new().num_threads(1).build().unwrap();
    let mut group = c.benchmark_group("adjust_in_order");
    let scenes = [
        ("plane", Some(plane_scene(70.0, 50.0))),
        ("sphere", Some(sphere_scene(3000))),
        ("flamingo", Scene::flamingo()),
    ];
    for (name, scene) in scenes.into_iter().filter_map(|(name, s)| Some((name, s?))) {
        let n = scene.frames.len();
        group.throughput(Throughput::Elements(n as u64));
        let mut adjuster = Adjuster::new();
        let mut poses = vec![FeatherPose::default(); n];
        let stats = one.install(|| scene.adjust(&mut adjuster, &mut poses));
        eprintln!(
            "{name}: {n} feathers, {} levels, {:.1} collision tests per feather, {} clamped",
            stats.levels,
            stats.collision_tests_per_feather(),
            stats.clamped
        );
        group.bench_function(format!("{name}_{n}_one_thread"), |b| {
            b.iter(|| one.install(|| scene.adjust(&mut adjuster, &mut poses)))
        });
        group
            .bench_function(format!("{name}_{n}_default_pool"), |b| b.iter(|| scene.adjust(&mut adjuster, &mut poses)));
    }
    group.finish();
}

criterion_group! {
    name = benches;
    config = Criterion::default().sample_size(10).warm_up_time(Duration::from_millis(500)).measurement_time(Duration::from_secs(2));
    targets = one_feather, in_order
}
criterion_main!(benches);
