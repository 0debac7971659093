//! Height-field adjustment on small hand-built scenes (no sampler, no
//! ordering module): roots on a plane, a sphere and a torus, ordered tip
//! side first along a flow axis, adjusted, then checked by the exact
//! validation.

use glam::Vec3;
use plumage::adjustment::{
    AdjustParams, AdjustStats, AdjustSteps, Adjuster, HeightField, ObstacleFeather, OrderedRun, Selection,
    adjust_feather, adjust_in_order,
};
use plumage::body::BodyIndex;
use plumage::csr::CsrView;
use plumage::feather::{FeatherPose, FeatherShape, FeatherTriangles, feather_triangles};
use plumage::geometry::RootFrame;
use plumage::rng::Rng;
use plumage::validation::{ProbeSkin, Validation, ValidationInput, coverage, intersecting_pairs, validate};
use std::alloc::{GlobalAlloc, Layout, System};
use std::cell::Cell;

/// Counts allocations per thread, to check that warm scratch never allocates.
struct CountingAllocator;

thread_local! {
    static ALLOCATIONS: Cell<usize> = const { Cell::new(0) };
}

fn count_allocation() {
    let _ = ALLOCATIONS.try_with(|c| c.set(c.get() + 1));
}

fn allocations_on_this_thread() -> usize {
    ALLOCATIONS.with(|c| c.get())
}

// SAFETY: forwards every call to the system allocator unchanged.
unsafe impl GlobalAlloc for CountingAllocator {
    unsafe fn alloc(&self, layout: Layout) -> *mut u8 {
        count_allocation();
        // SAFETY: same contract as the caller's.
        unsafe { System.alloc(layout) }
    }
    unsafe fn dealloc(&self, ptr: *mut u8, layout: Layout) {
        // SAFETY: same contract as the caller's.
        unsafe { System.dealloc(ptr, layout) }
    }
    unsafe fn alloc_zeroed(&self, layout: Layout) -> *mut u8 {
        count_allocation();
        // SAFETY: same contract as the caller's.
        unsafe { System.alloc_zeroed(layout) }
    }
    unsafe fn realloc(&self, ptr: *mut u8, layout: Layout, new_size: usize) -> *mut u8 {
        count_allocation();
        // SAFETY: same contract as the caller's.
        unsafe { System.realloc(ptr, layout, new_size) }
    }
}

#[global_allocator]
static ALLOCATOR: CountingAllocator = CountingAllocator;

/// A feathered test scene: body mesh, roots, order and candidate lists.
struct Scene {
    positions: Vec<Vec3>,
    triangles: Vec<[u32; 3]>,
    body: BodyIndex,
    frames: Vec<RootFrame>,
    shapes: Vec<FeatherShape>,
    order: Vec<u32>,
    rank: Vec<u32>,
    offsets: Vec<u32>,
    candidates: Vec<u32>,
    bare: Vec<Vec3>,
}

/// Scene sizes: debug builds are slow, so they get fewer feathers.
fn debug_or_release(debug: usize, release: usize) -> usize {
    if cfg!(debug_assertions) { debug } else { release }
}

/// A grid mesh over `[0,1]²` mapped through `f` (u wraps when `wrap_u`, v when `wrap_v`).
fn grid_mesh(
    nu: usize,
    nv: usize,
    wrap_u: bool,
    wrap_v: bool,
    f: impl Fn(f32, f32) -> Vec3,
) -> (Vec<Vec3>, Vec<[u32; 3]>) {
    let (cu, cv) = (if wrap_u { nu } else { nu + 1 }, if wrap_v { nv } else { nv + 1 });
    let mut pos = Vec::with_capacity(cu * cv);
    for j in 0..cv {
        for i in 0..cu {
            pos.push(f(i as f32 / nu as f32, j as f32 / nv as f32));
        }
    }
    let id = |i: usize, j: usize| ((j % cv) * cu + (i % cu)) as u32;
    let mut tris = Vec::new();
    for j in 0..nv {
        for i in 0..nu {
            let (a, b, c, d) = (id(i, j), id(i + 1, j), id(i + 1, j + 1), id(i, j + 1));
            tris.push([a, b, c]);
            tris.push([a, c, d]);
        }
    }
    (pos, tris)
}

/// Area-weighted vertex normals.
fn vertex_normals(pos: &[Vec3], tris: &[[u32; 3]]) -> Vec<Vec3> {
    let mut n = vec![Vec3::ZERO; pos.len()];
    for t in tris {
        let [a, b, c] = t.map(|v| pos[v as usize]);
        let w = (b - a).cross(c - a);
        for &v in t {
            n[v as usize] += w;
        }
    }
    n.into_iter().map(|v| v.normalize_or_zero()).collect()
}

impl Scene {
    /// Plants roots at the mesh points nearest to `points` (interpolated
    /// normal, orientation from the flow axis), shapes from spacing `d`,
    /// order tip side first along `flow`, candidates within reach. Skin
    /// within `BARE_PER_LENGTH` feather lengths of a point of `bare` gets
    /// no roots: where the flow converges (a sink or a saddle of the
    /// projected axis) feathers from opposite sides would each lie over the
    /// other's root, which no order can resolve. Two feathers pointing at
    /// each other across the point reach each other's roots only when
    /// their distances to it sum to less than a length, so a bare disc of
    /// a little over half a length suffices; real coats are bare there too
    /// (the density map is 0, as at a vent).
    fn build(
        positions: Vec<Vec3>,
        triangles: Vec<[u32; 3]>,
        points: &[Vec3],
        d: f32,
        flow: Vec3,
        bare: &[Vec3],
    ) -> Self {
        let length = FeatherShape::for_spacing(d).length;
        let body = BodyIndex::from_mesh(&positions, &triangles);
        let normals = vertex_normals(&positions, &triangles);
        let mut scratch = Vec::new();
        let mut frames = Vec::new();
        for &p in points {
            if bare.iter().any(|b| (*b - p).length() < BARE_PER_LENGTH * length) {
                continue;
            }
            let Some(hit) = body.closest_point(p, 4.0 * d, &mut scratch) else { continue };
            let tri = triangles[hit.triangle as usize];
            let [a, b, c] = tri.map(|v| positions[v as usize]);
            let w = barycentric(hit.point, a, b, c);
            let n = (0..3).map(|k| normals[tri[k] as usize] * w[k]).sum::<Vec3>();
            if let Some(f) = RootFrame::from_normal_and_direction(hit.point, n, flow)
                && n.normalize().cross(flow.normalize()).length() > 0.2
            {
                frames.push(f);
            }
        }
        let shapes = vec![FeatherShape::for_spacing(d); frames.len()];
        let mut order: Vec<u32> = (0..frames.len() as u32).collect();
        order.sort_by(|&i, &j| {
            let (pi, pj) = (frames[i as usize].position.dot(flow), frames[j as usize].position.dot(flow));
            pj.total_cmp(&pi).then(i.cmp(&j))
        });
        let mut rank = vec![0u32; frames.len()];
        for (k, &i) in order.iter().enumerate() {
            rank[i as usize] = k as u32;
        }
        let (offsets, candidates) = within_reach(&frames, &shapes);
        Scene { positions, triangles, body, frames, shapes, order, rank, offsets, candidates, bare: bare.to_vec() }
    }

    /// The body triangles of the feathered skin (away from the bare discs).
    fn feathered_skin(&self) -> Vec<[u32; 3]> {
        let radius = BARE_PER_LENGTH * self.shapes[0].length;
        self.triangles
            .iter()
            .copied()
            .filter(|t| {
                let c = t.iter().map(|&v| self.positions[v as usize]).sum::<Vec3>() / 3.0;
                self.bare.iter().all(|b| (*b - c).length() > radius)
            })
            .collect()
    }

    fn lists(&self) -> CsrView<'_, u32> {
        CsrView::new(&self.offsets, &self.candidates)
    }

    /// An ordered run over the scene with `params` and `steps`.
    fn ordered<'a>(&'a self, params: &'a AdjustParams, steps: AdjustSteps) -> OrderedRun<'a> {
        OrderedRun {
            frames: &self.frames,
            shapes: &self.shapes,
            order: &self.order,
            rank: &self.rank,
            candidates: self.lists(),
            body: &self.body,
            params,
            steps,
            settle_rate: 0.0,
        }
    }

    fn adjust(&self, params: &AdjustParams) -> (Vec<FeatherPose>, plumage::adjustment::AdjustStats) {
        let mut poses = vec![FeatherPose::default(); self.frames.len()];
        let stats = adjust_in_order(&self.ordered(params, AdjustSteps::Full), &mut poses, None);
        (poses, stats)
    }

    fn triangles_at(&self, poses: &[FeatherPose]) -> Vec<FeatherTriangles> {
        (0..poses.len()).map(|i| feather_triangles(&self.frames[i], &self.shapes[i], poses[i])).collect()
    }

    fn validate(&self, poses: &[FeatherPose], probes: usize) -> Validation {
        validate(&ValidationInput {
            feather_triangles: &self.triangles_at(poses),
            frames: &self.frames,
            shapes: &self.shapes,
            poses,
            body: &self.body,
            skin: &ProbeSkin::whole(&self.positions, &self.triangles),
            probes,
            seed: 7,
        })
    }
}

fn barycentric(p: Vec3, a: Vec3, b: Vec3, c: Vec3) -> [f32; 3] {
    let (v0, v1, v2) = (b - a, c - a, p - a);
    let (d00, d01, d11, d20, d21) = (v0.dot(v0), v0.dot(v1), v1.dot(v1), v2.dot(v0), v2.dot(v1));
    let den = d00 * d11 - d01 * d01;
    let v = (d11 * d20 - d01 * d21) / den;
    let w = (d00 * d21 - d01 * d20) / den;
    [1.0 - v - w, v, w]
}

/// Candidate lists: roots within `L_i + L_j` (brute force, small scenes).
fn within_reach(frames: &[RootFrame], shapes: &[FeatherShape]) -> (Vec<u32>, Vec<u32>) {
    let mut offsets = vec![0u32];
    let mut list = Vec::new();
    for i in 0..frames.len() {
        for j in 0..frames.len() {
            let reach = shapes[i].length + shapes[j].length;
            if i != j && (frames[i].position - frames[j].position).length() <= reach {
                list.push(j as u32);
            }
        }
        offsets.push(list.len() as u32);
    }
    (offsets, list)
}

/// Roots on a staggered lattice over `[0, w] × [0, h]` of the plane z = 0
/// for spacing `d` (body a larger grid, flow along +x). The lattice step is
/// 1.3 d, which gives about the density of a maximal Poisson-disk set of
/// radius d (0.68 roots per d²), what the sampler produces.
fn plane_scene(d: f32, w: f32, h: f32) -> Scene {
    let s = LATTICE_PER_SPACING * d;
    let (pos, tris) = grid_mesh(24, 24, false, false, |u, v| {
        Vec3::new(-6.0 * s + (w + 12.0 * s) * u, -3.0 * s + (h + 6.0 * s) * v, 0.0)
    });
    let mut points = Vec::new();
    let row = s * 0.75f32.sqrt();
    let mut r = Rng::new(3);
    for j in 0..=((h / row) as usize) {
        for i in 0..=((w / s) as usize) {
            let x = i as f32 * s + if j % 2 == 1 { 0.5 * s } else { 0.0 };
            // A little jitter so no two roots tie in the order.
            points.push(Vec3::new(x + 0.05 * s * r.next_f32(), j as f32 * row + 0.05 * s * r.next_f32(), 0.0));
        }
    }
    Scene::build(pos, tris, &points, d, Vec3::X, &[])
}

/// Radius of the bare discs at flow singularities, in feather lengths.
const BARE_PER_LENGTH: f32 = 0.6;

/// Lattice step of the plane scenes, in spacings.
const LATTICE_PER_SPACING: f32 = 1.3;

/// Roots on a Fibonacci lattice of a UV sphere of radius `radius`, flow
/// towards +z (a sink at the north pole, a source at the south).
fn sphere_scene(n: usize, radius: f32) -> Scene {
    let (pos, tris) = grid_mesh(96, 48, true, false, |u, v| {
        let (theta, phi) = (std::f32::consts::TAU * u, std::f32::consts::PI * v);
        radius * Vec3::new(phi.sin() * theta.cos(), phi.sin() * theta.sin(), -phi.cos())
    });
    // Drop the degenerate pole triangles the UV grid makes.
    let tris: Vec<[u32; 3]> = tris
        .into_iter()
        .filter(|t| {
            let [a, b, c] = t.map(|v| pos[v as usize]);
            (b - a).cross(c - a).length() > 1e-9
        })
        .collect();
    let golden = std::f32::consts::PI * (3.0 - 5.0f32.sqrt());
    let points: Vec<Vec3> = (0..n)
        .map(|k| {
            let z = 1.0 - 2.0 * (k as f32 + 0.5) / n as f32;
            let r = (1.0 - z * z).sqrt();
            let a = golden * k as f32;
            radius * Vec3::new(r * a.cos(), r * a.sin(), z)
        })
        .collect();
    let d = 0.9 * radius * (4.0 * std::f32::consts::PI / n as f32).sqrt();
    // The north pole is a sink of the flow: left bare.
    Scene::build(pos, tris, &points, d, Vec3::Z, &[Vec3::new(0.0, 0.0, radius)])
}

/// Dart-throwing roots (radius `d`) on a torus around z, flow along +x:
/// both convex (outer) and saddle-shaped (inner) skin.
fn torus_scene(d: f32, major: f32, minor: f32) -> Scene {
    let at = |u: f32, v: f32| {
        let (a, b) = (std::f32::consts::TAU * u, std::f32::consts::TAU * v);
        Vec3::new((major + minor * b.cos()) * a.cos(), (major + minor * b.cos()) * a.sin(), minor * b.sin())
    };
    let (pos, tris) = grid_mesh(128, 48, true, true, at);
    // Dart throwing until saturation, with a grid of accepted points.
    let extent = major + minor;
    let cells = (2.0 * extent / d).ceil() as usize + 1;
    let cell_of = |p: Vec3| {
        let c = ((p + Vec3::splat(extent)) / d).floor();
        (c.x as usize).min(cells - 1) + cells * ((c.y as usize).min(cells - 1) + cells * (c.z as usize).min(cells - 1))
    };
    let mut grid: Vec<Vec<u32>> = vec![Vec::new(); cells * cells * cells];
    let mut r = Rng::new(17);
    let mut points: Vec<Vec3> = Vec::new();
    let tries = (60.0 * 4.0 * std::f32::consts::PI * std::f32::consts::PI * major * minor / (d * d)) as usize;
    for _ in 0..tries {
        // Area-weighted by rejection on the tube angle.
        let (u, v) = (r.next_f32(), r.next_f32());
        let weight = (major + minor * (std::f32::consts::TAU * v).cos()) / (major + minor);
        if r.next_f32() > weight {
            continue;
        }
        let p = at(u, v);
        let c = ((p + Vec3::splat(extent)) / d).floor();
        let mut free = true;
        for dz in -1i32..=1 {
            for dy in -1i32..=1 {
                for dx in -1i32..=1 {
                    let q = Vec3::new(c.x + dx as f32, c.y + dy as f32, c.z + dz as f32) * d - Vec3::splat(extent);
                    if q.min_element() < -extent - d || q.max_element() > extent + d {
                        continue;
                    }
                    let near = &grid[cell_of(q + Vec3::splat(0.5 * d))];
                    free &= near.iter().all(|&k| (points[k as usize] - p).length() > d);
                }
            }
        }
        if free {
            grid[cell_of(p)].push(points.len() as u32);
            points.push(p);
        }
    }
    // The outer +x point is a sink of the flow, the inner ±x points saddles.
    let bare =
        [Vec3::new(major + minor, 0.0, 0.0), Vec3::new(major - minor, 0.0, 0.0), Vec3::new(minor - major, 0.0, 0.0)];
    Scene::build(pos, tris, &points, d, Vec3::X, &bare)
}

fn assert_clean(name: &str, v: &Validation) {
    assert!(
        v.intersecting_pairs.is_empty(),
        "{name}: {} intersecting pairs, e.g. {:?}",
        v.intersecting_pairs.len(),
        &v.intersecting_pairs[..v.intersecting_pairs.len().min(5)]
    );
    assert!(
        v.body_penetrations.is_empty(),
        "{name}: {} body penetrations, e.g. {:?}",
        v.body_penetrations.len(),
        &v.body_penetrations[..v.body_penetrations.len().min(5)]
    );
}

#[test]
fn a_later_feather_lies_on_an_earlier_one_with_just_enough_pitch() {
    let d = 1.0;
    let shape = FeatherShape::for_spacing(d);
    let pos = [
        Vec3::new(-20.0, -20.0, 0.0),
        Vec3::new(20.0, -20.0, 0.0),
        Vec3::new(20.0, 20.0, 0.0),
        Vec3::new(-20.0, 20.0, 0.0),
    ];
    let tris = [[0, 1, 2], [0, 2, 3]];
    let body = BodyIndex::from_mesh(&pos, &tris);
    let params = AdjustParams::default();
    let ahead = RootFrame::from_normal_and_direction(Vec3::new(d, 0.0, 0.0), Vec3::Z, Vec3::X).unwrap();
    let behind = RootFrame::from_normal_and_direction(Vec3::ZERO, Vec3::Z, Vec3::X).unwrap();
    let mut field = HeightField::new(32, 16);
    let first =
        adjust_feather(&ahead, &shape, FeatherPose::default(), &[], &body, &params, AdjustSteps::Full, &mut field);
    let obstacle = ObstacleFeather {
        triangles: feather_triangles(&ahead, &shape, first.pose),
        thickness: shape.thickness,
        far_side: false,
    };
    let second = adjust_feather(
        &behind,
        &shape,
        FeatherPose::default(),
        &[obstacle],
        &body,
        &params,
        AdjustSteps::Full,
        &mut field,
    );
    assert_eq!(second.collision_tests, 1);
    assert!(!second.clamped);
    assert!(second.pose.roll.abs() < 1e-3, "symmetric scene, roll {}", second.pose.roll);

    // Analytic minimum: the later feather's shaft must pass the earlier
    // feather's top (its surface raised by t) plus the clearance. The
    // earlier feather rises along the shaft from its root at x = d; the
    // binding points are its root and (for a steeper earlier feather) the tip.
    let t = shape.thickness;
    let c = params.clearance * t;
    let tan_first = first.pose.pitch.tan();
    let need_at = |x: f32| ((x - d) * tan_first + t + c) / x;
    let exact = need_at(d).max(need_at(shape.length)).atan();
    // One cell of slack: heights are cell maxima judged at the cell's near edge.
    let dx = shape.length / 31.0;
    let slack = (((t + c) + dx * tan_first) / (d - dx)).atan();
    assert!(second.pose.pitch >= exact, "pitch {} below the analytic minimum {exact}", second.pose.pitch);
    assert!(
        second.pose.pitch <= slack,
        "pitch {} more than a cell above the minimum {exact} (bound {slack})",
        second.pose.pitch
    );
    let mine = feather_triangles(&behind, &shape, second.pose);
    let a = mine[0];
    assert!(intersecting_pairs(&[mine, obstacle.triangles]).is_empty());
    // The tip went up, over the earlier feather's top.
    assert!(a[1].z > (shape.length - d) * tan_first + t, "tip at {}", a[1].z);
}

#[test]
fn plane_coat_is_clean_and_closed() {
    let n = debug_or_release(16, 32);
    let (w, h) = (n as f32, 0.6 * n as f32);
    let scene = plane_scene(1.0, w, h);
    let (poses, stats) = scene.adjust(&AdjustParams::default());
    assert_eq!(stats.adjusted, scene.frames.len());
    let v = scene.validate(&poses, 2000);
    assert_clean("plane", &v);
    // Interior probes: skip the upstream strip (behind the first row's
    // roots) and the lateral edges.
    let shape = scene.shapes[0];
    let (probe_pos, probe_tris) = grid_mesh(8, 8, false, false, |u, v| {
        Vec3::new(shape.length + (w - shape.length) * u, shape.width + (h - 2.0 * shape.width) * v, 0.0)
    });
    let tris = scene.triangles_at(&poses);
    let cov = coverage(&tris, shape.length, &ProbeSkin::whole(&probe_pos, &probe_tris), &scene.body, 3000, 11);
    assert!(cov >= 0.95, "plane interior coverage {cov}");
    assert!(v.mean_pitch_deg > 0.0 && v.mean_pitch_deg < 15.0, "mean pitch {}", v.mean_pitch_deg);
    assert!(stats.clamped == 0, "{} clamped", stats.clamped);
    eprintln!(
        "plane: {} feathers, {} levels, {:.1} tests/feather, mean pitch {:.2}°, coverage {:.3}",
        scene.frames.len(),
        stats.levels,
        stats.collision_tests_per_feather(),
        v.mean_pitch_deg,
        cov
    );
}

#[test]
fn sphere_coat_is_clean_and_closed() {
    let scene = sphere_scene(debug_or_release(300, 1200), 1.0);
    let (poses, stats) = scene.adjust(&AdjustParams::default());
    let v = scene.validate(&poses, 4000);
    eprintln!(
        "sphere: {} feathers, {} levels, {:.1} tests/feather, mean pitch {:.2}°, coverage {:.3}, clamped {}",
        scene.frames.len(),
        stats.levels,
        stats.collision_tests_per_feather(),
        v.mean_pitch_deg,
        v.coverage,
        stats.clamped
    );
    assert_clean("sphere", &v);
    assert!(v.coverage >= 0.95, "sphere coverage {}", v.coverage);
}

#[test]
fn torus_coat_is_clean() {
    let d = debug_or_release(12, 8) as f32 / 100.0;
    let scene = torus_scene(d, 1.0, 0.5);
    let (poses, stats) = scene.adjust(&AdjustParams::default());
    let v = scene.validate(&poses, 4000);
    eprintln!(
        "torus: {} feathers, {} levels, {:.1} tests/feather, mean pitch {:.2}°, coverage {:.3} (all skin), clamped {}",
        scene.frames.len(),
        stats.levels,
        stats.collision_tests_per_feather(),
        v.mean_pitch_deg,
        v.coverage,
        stats.clamped
    );
    assert_clean("torus", &v);
    let skin = scene.feathered_skin();
    let cov = coverage(
        &scene.triangles_at(&poses),
        scene.shapes[0].length,
        &ProbeSkin::whole(&scene.positions, &skin),
        &scene.body,
        4000,
        13,
    );
    // Lower than on the sphere: the flow diverges at the outer −x point (a
    // source), and the tube's tight curvature opens gaps between vanes.
    assert!(cov >= 0.9, "torus coverage {cov} on the feathered skin");
}

#[test]
fn fluffiness_raises_mean_pitch_and_allowance_lowers_it() {
    let scene = plane_scene(1.0, 10.0, 6.0);
    let mean = |params: AdjustParams| {
        let (poses, _) = scene.adjust(&params);
        plumage::validation::mean_pitch_deg(&poses)
    };
    let base = mean(AdjustParams::default());
    let fluffed: Vec<f64> =
        [0.02, 0.05, 0.1, 0.2].iter().map(|&f| mean(AdjustParams { fluffiness: f, ..Default::default() })).collect();
    assert!(base < fluffed[0], "{base} vs {fluffed:?}");
    assert!(fluffed.windows(2).all(|w| w[0] < w[1]), "{fluffed:?}");
    let sunk = mean(AdjustParams { collision_allowance: 0.5, ..Default::default() });
    let deeper = mean(AdjustParams { collision_allowance: 1.0, ..Default::default() });
    assert!(sunk < base && deeper < sunk, "allowance: {base} → {sunk} → {deeper}");
}

#[test]
fn results_are_bitwise_identical_at_1_2_and_4_threads() {
    let scene = sphere_scene(debug_or_release(200, 600), 1.0);
    let run = |threads: usize| {
        let pool = rayon::ThreadPoolBuilder::new().num_threads(threads).build().unwrap();
        pool.install(|| {
            let (poses, stats) = scene.adjust(&AdjustParams::default());
            let v = scene.validate(&poses, 1000);
            let bits: Vec<(u32, u32)> = poses.iter().map(|p| (p.pitch.to_bits(), p.roll.to_bits())).collect();
            (bits, stats.collision_tests, stats.clamped, stats.levels, v)
        })
    };
    let one = run(1);
    assert_eq!(one, run(2));
    assert_eq!(one, run(4));
}

#[test]
fn levels_give_the_serial_result() {
    // Adjust one feather at a time in order with adjust_feather and compare.
    let scene = plane_scene(1.0, 6.0, 16.0);
    let params = AdjustParams::default();
    let (poses, stats) = scene.adjust(&params);
    assert!(stats.levels > 1 && stats.levels < scene.frames.len(), "levels {}", stats.levels);
    let mut serial = vec![FeatherPose::default(); scene.frames.len()];
    let mut field = HeightField::new(32, 16);
    for &i in &scene.order {
        let i = i as usize;
        let obstacles: Vec<ObstacleFeather> = scene
            .lists()
            .row(i)
            .iter()
            .map(|&j| j as usize)
            .filter(|&j| scene.rank[j] < scene.rank[i])
            .map(|j| ObstacleFeather {
                triangles: feather_triangles(&scene.frames[j], &scene.shapes[j], serial[j]),
                thickness: scene.shapes[j].thickness,
                far_side: false,
            })
            .collect();
        serial[i] = adjust_feather(
            &scene.frames[i],
            &scene.shapes[i],
            serial[i],
            &obstacles,
            &scene.body,
            &params,
            AdjustSteps::Full,
            &mut field,
        )
        .pose;
    }
    assert_eq!(poses, serial);
}

/// Runs an ordered adjustment of `scene` from `poses` with a selection.
fn readjust_stats(
    scene: &Scene,
    adjuster: &mut Adjuster,
    poses: &mut [FeatherPose],
    selection: Selection<'_>,
) -> AdjustStats {
    adjuster.adjust_in_order(&scene.ordered(&AdjustParams::default(), AdjustSteps::Full), poses, selection)
}

/// As [`readjust_stats`], returning the number of feathers adjusted.
fn readjust(scene: &Scene, adjuster: &mut Adjuster, poses: &mut [FeatherPose], selection: Selection<'_>) -> usize {
    readjust_stats(scene, adjuster, poses, selection).adjusted
}

#[test]
fn a_subset_readjusts_only_its_feathers_and_propagation_follows_moves() {
    let scene = plane_scene(1.0, 6.0, 16.0);
    let (settled, _) = scene.adjust(&AdjustParams::default());
    let n = scene.frames.len();
    let mut adjuster = Adjuster::new();

    // Readjusting a settled coat changes nothing.
    let mut poses = settled.clone();
    assert_eq!(readjust(&scene, &mut adjuster, &mut poses, Selection::Subset(&vec![true; n])), n);
    assert_eq!(poses, settled);

    // A disturbed feather alone is readjusted, back to where it was.
    let first = scene.order[0] as usize;
    let mut seeds = vec![false; n];
    seeds[first] = true;
    poses[first].pitch += 0.3;
    assert_eq!(readjust(&scene, &mut adjuster, &mut poses, Selection::Subset(&seeds)), 1);
    assert_eq!(poses, settled);

    // Lift it and readjust everything else: its dependants climb over it.
    let mut later = vec![true; n];
    later[first] = false;
    poses[first].pitch += 0.3;
    readjust(&scene, &mut adjuster, &mut poses, Selection::Subset(&later));
    let lifted = poses.clone();
    let moved = (0..n).filter(|&i| lifted[i] != settled[i]).count();
    assert!(moved > 1 && moved < n, "{moved} of {n} feathers moved");

    // Below the threshold propagation stops at the seed...
    let mut poses = lifted.clone();
    assert_eq!(readjust(&scene, &mut adjuster, &mut poses, Selection::Propagate { seeds: &seeds, threshold: 1.0 }), 1);
    // ...above it, it follows the moves down the obstacle relation and
    // restores the settled coat, without touching unrelated feathers.
    let mut poses = lifted.clone();
    let adjusted = readjust(&scene, &mut adjuster, &mut poses, Selection::Propagate { seeds: &seeds, threshold: 0.01 });
    assert_eq!(poses, settled);
    assert!(adjusted >= moved && adjusted < n, "adjusted {adjusted}, moved {moved}, of {n}");
    assert_eq!(adjuster.adjusted().iter().filter(|&&a| a).count(), adjusted);
}

#[test]
fn verifying_readjusts_only_feathers_that_intersect() {
    let scene = plane_scene(1.0, 6.0, 16.0);
    let (settled, _) = scene.adjust(&AdjustParams::default());
    let n = scene.frames.len();
    let mut adjuster = Adjuster::new();
    let run = |adjuster: &mut Adjuster, poses: &mut [FeatherPose], seeds: &[bool], suspects: &[bool]| {
        readjust_stats(&scene, adjuster, poses, Selection::Verify { seeds, suspects, threshold: 1.0 })
    };
    let none = vec![false; n];
    let all = vec![true; n];

    // A settled coat passes every check: nothing is readjusted.
    let mut poses = settled.clone();
    let stats = run(&mut adjuster, &mut poses, &none, &all);
    assert_eq!((stats.adjusted, stats.verified), (0, n));
    assert_eq!(poses, settled);
    assert!(adjuster.verified().iter().all(|&v| v));

    // Lift the first feather into those lying on it. Below the threshold
    // propagation does not pass the lift on, but the checks find every
    // feather it now cuts through, and only those are readjusted.
    let first = scene.order[0] as usize;
    let mut poses = settled.clone();
    poses[first].pitch += 0.3;
    let lifted_first = poses[first];
    let disturbed = poses.clone();
    let stats = run(&mut adjuster, &mut poses, &none, &all);
    assert_eq!(poses[first], lifted_first, "the first feather has no obstacle and stays lifted");
    let hit = stats.adjusted;
    assert!(hit > 0 && hit < n, "{hit} of {n} feathers readjusted");
    assert_eq!(stats.adjusted + stats.verified, n);
    assert!(scene.validate(&poses, 64).intersecting_pairs.is_empty(), "the readjusted coat is clean");
    // Without suspects nothing is checked, so the intersections stay.
    let mut unchecked = disturbed.clone();
    let stats = run(&mut adjuster, &mut unchecked, &none, &none);
    assert_eq!((stats.adjusted, stats.verified), (0, 0));
    assert!(!scene.validate(&unchecked, 64).intersecting_pairs.is_empty(), "the lift cuts through feathers");
}

#[test]
fn fine_pitch_only_keeps_roll_and_stays_clean() {
    let scene = plane_scene(1.0, 8.0, 5.0);
    let params = AdjustParams::default();
    let (mut poses, _) = scene.adjust(&params);
    let rolls: Vec<f32> = poses.iter().map(|p| p.roll).collect();
    let mut adjuster = Adjuster::new();
    adjuster.adjust_in_order(&scene.ordered(&params, AdjustSteps::FinePitchOnly), &mut poses, Selection::All);
    assert_eq!(poses.iter().map(|p| p.roll).collect::<Vec<_>>(), rolls);
    assert_clean("fine pitch", &scene.validate(&poses, 100));
}

#[test]
fn warm_scratch_allocates_nothing() {
    let scene = sphere_scene(debug_or_release(200, 600), 1.0);
    let params = AdjustParams::default();
    let (poses, _) = scene.adjust(&params);
    let mut field = HeightField::new(32, 16);
    let obstacles_of = |i: usize| -> Vec<ObstacleFeather> {
        scene
            .lists()
            .row(i)
            .iter()
            .map(|&j| j as usize)
            .filter(|&j| scene.rank[j] < scene.rank[i])
            .map(|j| ObstacleFeather {
                triangles: feather_triangles(&scene.frames[j], &scene.shapes[j], poses[j]),
                thickness: scene.shapes[j].thickness,
                far_side: false,
            })
            .collect()
    };
    let feathers: Vec<(usize, Vec<ObstacleFeather>)> =
        scene.order.iter().map(|&i| (i as usize, obstacles_of(i as usize))).collect();
    let run = |field: &mut HeightField| {
        for (i, obstacles) in &feathers {
            let steps = if i % 2 == 0 { AdjustSteps::Full } else { AdjustSteps::FinePitchOnly };
            adjust_feather(
                &scene.frames[*i],
                &scene.shapes[*i],
                poses[*i],
                obstacles,
                &scene.body,
                &params,
                steps,
                field,
            );
        }
    };
    run(&mut field);
    let before = allocations_on_this_thread();
    run(&mut field);
    assert_eq!(allocations_on_this_thread(), before, "adjust_feather allocated with warm scratch");

    // Ordered adjustment: after the first frame, frames of the same size
    // allocate nothing on the worker (a one-thread pool runs everything there).
    let pool = rayon::ThreadPoolBuilder::new().num_threads(1).build().unwrap();
    let counts: Vec<usize> = pool.install(|| {
        let mut adjuster = Adjuster::new();
        let mut poses = vec![FeatherPose::default(); scene.frames.len()];
        (0..3)
            .map(|_| {
                let before = allocations_on_this_thread();
                adjuster.adjust_in_order(&scene.ordered(&params, AdjustSteps::Full), &mut poses, Selection::All);
                allocations_on_this_thread() - before
            })
            .collect()
    });
    assert!(counts[0] > 0);
    assert_eq!(&counts[1..], &[0, 0], "allocations per call: {counts:?}");
}

/// A segmented feather (4 segments) adjusted alone over `body` from a root
/// at `root` with normal +z pointing +x: its straight and its draped pose,
/// and the tip's distance to the body in feather lengths for each.
fn drape_over(body_pos: &[Vec3], body_tris: &[[u32; 3]], root: Vec3) -> (FeatherPose, f32, FeatherPose, f32) {
    let body = BodyIndex::from_mesh(body_pos, body_tris);
    let shape = FeatherShape::for_spacing(1.0).with_segments(4);
    let frame = RootFrame::from_normal_and_direction(root, Vec3::Z, Vec3::X).unwrap();
    let mut field = HeightField::new(32, 16);
    let mut tip_height = |params: &AdjustParams| {
        let pose =
            adjust_feather(&frame, &shape, FeatherPose::default(), &[], &body, params, AdjustSteps::Full, &mut field)
                .pose;
        let tip = plumage::feather::tip_position(&frame, &shape, pose);
        let distance = body.closest_point(tip, 10.0 * shape.length, &mut Vec::new()).unwrap().distance;
        // No segment passes through the body beyond the root socket.
        let tris = feather_triangles(&frame, &shape, pose);
        let poses = [pose];
        let v = plumage::validation::body_penetrations(&[frame], &[shape], &poses, &body);
        assert!(v.is_empty(), "the feather at {pose:?} passes through the body ({} triangles)", tris.len());
        (pose, distance / shape.length)
    };
    let (straight, straight_height) = tip_height(&AdjustParams { bend_limit: 0.0, ..AdjustParams::default() });
    let (draped, draped_height) = tip_height(&AdjustParams::default());
    assert!(straight.is_straight());
    let (down, up) = AdjustParams::default().bend_range();
    assert!(
        draped.bends.iter().all(|&b| b <= up + 1e-6 && b >= down - 1e-6),
        "bends {:?} beyond the limits {down} .. {up}",
        draped.bends
    );
    (straight, straight_height, draped, draped_height)
}

#[test]
fn a_segmented_feather_drapes_over_a_cylinder() {
    // A cylinder of radius 0.8 feather lengths about the y axis; the root
    // on its top, the feather pointing round it.
    let (radius, length) = (3.2f32, 4.0f32);
    let (pos, tris) = grid_mesh(96, 8, true, false, |u, v| {
        let a = std::f32::consts::TAU * u;
        Vec3::new(radius * a.sin(), (v - 0.5) * 3.0 * length, radius * a.cos())
    });
    let (_, straight, draped_pose, draped) = drape_over(&pos, &tris, Vec3::new(0.0, 0.0, radius));
    println!("cylinder: tip height straight {straight:.3} L, draped {draped:.3} L, pose {draped_pose:?}");
    assert!(straight > 0.15, "a straight feather stands off a cylinder this thin ({straight})");
    assert!(draped < 0.05, "draped, the tip lies on the cylinder (within a few thicknesses): {draped}");
}

/// A strip 12 wide along y whose cross-section follows `profile`, (x, z)
/// points along x, normals up.
fn profile_mesh(profile: &[(f32, f32)]) -> (Vec<Vec3>, Vec<[u32; 3]>) {
    let mut pos = Vec::new();
    let mut tris = Vec::new();
    for pair in profile.windows(2) {
        let base = pos.len() as u32;
        for &(x, z) in pair {
            pos.push(Vec3::new(x, -6.0, z));
            pos.push(Vec3::new(x, 6.0, z));
        }
        tris.push([base, base + 2, base + 3]);
        tris.push([base, base + 3, base + 1]);
    }
    (pos, tris)
}

#[test]
fn a_segmented_feather_drapes_over_a_step() {
    // A floor at height 1.2 up to x = 2 (half the feather), a wall, then a
    // floor at 0: the feather lies on the upper floor and bends down over
    // the edge.
    let (a, h) = (2.0f32, 1.2f32);
    let profile = [(-4.0f32, h), (a, h), (a, 0.0), (12.0, 0.0)];
    let (pos, tris) = profile_mesh(&profile);
    let (_, straight, draped_pose, draped) = drape_over(&pos, &tris, Vec3::new(0.0, 0.0, h));
    println!("step: tip height straight {straight:.3} L, draped {draped:.3} L, bends {:?}", draped_pose.bends);
    assert!(draped < 0.5 * straight, "draped over the edge the tip comes down ({straight} -> {draped})");
    assert!(draped_pose.bends.iter().any(|&b| b < 0.0));
}

#[test]
fn a_segmented_feather_climbs_a_steep_ridge_and_drapes_beyond_it() {
    // A floor at 0 with a ridge rising at 45° just past the first joint (x
    // = 1.1 to a crest 0.7 high at 1.8, down again at 2.5): a root segment
    // laid on the floor leaves the next one no room within the bend limit,
    // so the drape must raise the root segment and then bend down beyond
    // the crest (before, it kept the straight pose).
    let profile = [(-4.0f32, 0.0f32), (1.1, 0.0), (1.8, 0.7), (2.5, 0.0), (12.0, 0.0)];
    let (pos, tris) = profile_mesh(&profile);
    let (_, straight, draped_pose, draped) = drape_over(&pos, &tris, Vec3::ZERO);
    println!("ridge: tip height straight {straight:.3} L, draped {draped:.3} L, pose {draped_pose:?}");
    assert!(!draped_pose.is_straight(), "the feather bends beyond the ridge");
    assert!(draped_pose.bends.iter().any(|&b| b < 0.0), "it bends down beyond the crest: {:?}", draped_pose.bends);
    assert!(draped < 0.5 * straight, "draped, the tip comes down beyond the ridge ({straight} -> {draped})");
}
