//! The C ABI contract, exercised from Rust: versions, status names, struct
//! sizes, and every bad input of the foundation issue. Each refusal has its
//! own status and a readable message, leaves `*out` NULL, and leaves a live
//! system exactly as it was.

use plumage::ffi::*;
use std::ffi::CStr;
use std::ptr::{null, null_mut};

/// A 4×4-vertex grid in the z = 0 plane, as a glTF-style soup (each
/// triangle has its own three vertices).
fn grid_soup() -> (Vec<f32>, Vec<u32>) {
    let mut pos = Vec::new();
    let mut idx = Vec::new();
    for j in 0..3 {
        for i in 0..3 {
            let (x, y) = (i as f32, j as f32);
            for (a, b) in [(0., 0.), (1., 0.), (1., 1.), (0., 0.), (1., 1.), (0., 1.)] {
                idx.push((pos.len() / 3) as u32);
                pos.extend_from_slice(&[x + a, y + b, 0.0]);
            }
        }
    }
    (pos, idx)
}

fn desc(pos: &[f32], idx: &[u32]) -> PlumageMeshDesc {
    let mut d = std::mem::MaybeUninit::<PlumageMeshDesc>::uninit();
    unsafe { plumage_mesh_desc_init(d.as_mut_ptr()) };
    let mut d = unsafe { d.assume_init() };
    d.positions = pos.as_ptr();
    d.vertex_count = pos.len() / 3;
    d.indices = idx.as_ptr();
    d.triangle_count = idx.len() / 3;
    d
}

fn thread_error() -> String {
    let n = unsafe { plumage_system_last_error(null(), null_mut(), 0) };
    let mut buf = vec![0 as std::ffi::c_char; n];
    unsafe { plumage_system_last_error(null(), buf.as_mut_ptr(), n) };
    unsafe { CStr::from_ptr(buf.as_ptr()) }.to_string_lossy().into_owned()
}

fn system_error(sys: *const PlumageSystem) -> String {
    let n = unsafe { plumage_system_last_error(sys, null_mut(), 0) };
    let mut buf = vec![0 as std::ffi::c_char; n];
    unsafe { plumage_system_last_error(sys, buf.as_mut_ptr(), n) };
    unsafe { CStr::from_ptr(buf.as_ptr()) }.to_string_lossy().into_owned()
}

/// Creates with `d`, expecting `status`; checks `*out` stays NULL and a message exists.
fn expect_refused(cfg: *const PlumageConfig, d: *const PlumageMeshDesc, status: u32) {
    let mut out: *mut PlumageSystem = std::ptr::dangling_mut::<PlumageSystem>();
    let got = unsafe { plumage_system_create(cfg, d, &mut out) };
    assert_eq!(got, status, "status {} ({}), message: {}", got, name(got), thread_error());
    assert!(out.is_null(), "*out must be NULL after a refusal");
    assert!(!thread_error().is_empty(), "a refused create leaves a message");
}

fn name(status: u32) -> String {
    unsafe { CStr::from_ptr(plumage_status_name(status)) }.to_string_lossy().into_owned()
}

fn create(pos: &[f32], idx: &[u32]) -> *mut PlumageSystem {
    let d = desc(pos, idx);
    let mut out = null_mut();
    let st = unsafe { plumage_system_create(null(), &d, &mut out) };
    assert_eq!(st, PLUMAGE_STATUS_OK, "{}", thread_error());
    assert!(!out.is_null());
    out
}

#[test]
fn versions_and_status_names() {
    let v = unsafe { CStr::from_ptr(plumage_version()) }.to_str().unwrap();
    assert_eq!(v.split('.').count(), 3);
    assert!(v.split('.').all(|p| p.parse::<u32>().is_ok()), "{v}");
    assert_eq!(v, env!("CARGO_PKG_VERSION"));
    assert_eq!(plumage_abi_version(), PLUMAGE_ABI_VERSION);
    let mut names = std::collections::BTreeSet::new();
    for s in 0..=PLUMAGE_STATUS_BUSY {
        let n = name(s);
        assert_ne!(n, "UNKNOWN_STATUS", "status {s} has a name");
        assert!(names.insert(n), "names are distinct");
    }
    assert_eq!(name(9999), "UNKNOWN_STATUS");
    assert_eq!(name(u32::MAX), "UNKNOWN_STATUS");
}

#[test]
fn init_functions_fill_sizes_and_defaults() {
    let mut cfg = std::mem::MaybeUninit::<PlumageConfig>::uninit();
    unsafe { plumage_config_init(cfg.as_mut_ptr()) };
    let cfg = unsafe { cfg.assume_init() };
    assert_eq!(cfg.struct_size as usize, std::mem::size_of::<PlumageConfig>());
    assert_eq!(cfg.k_neighbours, 10);
    assert!((cfg.gamma - 0.6).abs() < 1e-6 && (cfg.lambda - 0.3).abs() < 1e-6);
    assert!((cfg.theta - std::f32::consts::FRAC_PI_4).abs() < 1e-6);
    let d = desc(&[], &[]);
    assert_eq!(d.struct_size as usize, std::mem::size_of::<PlumageMeshDesc>());
    unsafe { plumage_config_init(null_mut()) };
    unsafe { plumage_mesh_desc_init(null_mut()) };
}

#[test]
fn a_gltf_soup_is_welded_and_steps_in_caller_numbering() {
    let (pos, idx) = grid_soup();
    let sys = create(&pos, &idx);
    let mut n = 0usize;
    assert_eq!(unsafe { plumage_system_vertex_count(sys, &mut n) }, PLUMAGE_STATUS_OK);
    assert_eq!(n, pos.len() / 3, "frames use the caller's own numbering");
    assert_eq!(unsafe { plumage_system_step(sys, pos.as_ptr(), n) }, PLUMAGE_STATUS_OK);
    assert_eq!(unsafe { plumage_system_evaluate(sys, pos.as_ptr(), n) }, PLUMAGE_STATUS_OK);
    let mut count = 7usize;
    assert_eq!(unsafe { plumage_system_feather_count(sys, &mut count) }, PLUMAGE_STATUS_OK);
    unsafe { plumage_system_destroy(sys) };
    unsafe { plumage_system_destroy(null_mut()) };
}

#[test]
fn bad_meshes_are_refused_with_their_own_status() {
    let (pos, idx) = grid_soup();
    let good = desc(&pos, &idx);
    let mut out = null_mut();
    assert_eq!(unsafe { plumage_system_create(null(), &good, null_mut()) }, PLUMAGE_STATUS_NULL_POINTER);
    expect_refused(null(), null(), PLUMAGE_STATUS_NULL_POINTER);
    expect_refused(null(), &PlumageMeshDesc { positions: null(), ..good }, PLUMAGE_STATUS_NULL_POINTER);
    expect_refused(null(), &PlumageMeshDesc { indices: null(), ..good }, PLUMAGE_STATUS_NULL_POINTER);
    expect_refused(null(), &PlumageMeshDesc { vertex_count: 0, ..good }, PLUMAGE_STATUS_EMPTY_MESH);
    expect_refused(null(), &PlumageMeshDesc { triangle_count: 0, ..good }, PLUMAGE_STATUS_EMPTY_MESH);
    expect_refused(null(), &PlumageMeshDesc { struct_size: 4, ..good }, PLUMAGE_STATUS_UNSUPPORTED_STRUCT_SIZE);
    expect_refused(null(), &PlumageMeshDesc { struct_size: 0, ..good }, PLUMAGE_STATUS_UNSUPPORTED_STRUCT_SIZE);
    expect_refused(null(), &PlumageMeshDesc { vertex_count: usize::MAX / 2, ..good }, PLUMAGE_STATUS_SIZE_OVERFLOW);
    for bad in [f32::NAN, f32::INFINITY, f32::NEG_INFINITY] {
        let mut p = pos.clone();
        p[7] = bad;
        expect_refused(null(), &desc(&p, &idx), PLUMAGE_STATUS_NON_FINITE);
    }
    let mut i = idx.clone();
    i[5] = (pos.len() / 3) as u32;
    expect_refused(null(), &desc(&pos, &i), PLUMAGE_STATUS_INDEX_OUT_OF_RANGE);
    i[5] = u32::MAX;
    expect_refused(null(), &desc(&pos, &i), PLUMAGE_STATUS_INDEX_OUT_OF_RANGE);
    let line = [0., 0., 0., 1., 0., 0., 2., 0., 0.];
    expect_refused(null(), &desc(&line, &[0, 1, 2, 2, 1, 0]), PLUMAGE_STATUS_DEGENERATE_MESH);
    let spacing = vec![-1.0f32; pos.len() / 3];
    expect_refused(
        null(),
        &PlumageMeshDesc { spacing_scale: spacing.as_ptr(), ..good },
        PLUMAGE_STATUS_INVALID_ARGUMENT,
    );
    // And the good mesh still works afterwards.
    assert_eq!(unsafe { plumage_system_create(null(), &good, &mut out) }, PLUMAGE_STATUS_OK);
    unsafe { plumage_system_destroy(out) };
}

/// Degenerate triangles (a repeated corner, one vertex thrice) among good
/// ones are accepted and ignored: the feathers are those of the mesh
/// without them, bit for bit, and a frame moves both systems alike.
#[test]
fn some_degenerate_triangles_among_good_ones_are_accepted() {
    let (pos, idx) = grid_soup();
    let (mut bad_pos, mut bad_idx) = (pos.clone(), idx.clone());
    let base = (pos.len() / 3) as u32;
    bad_pos.extend_from_slice(&[5., 5., 5., 5., 5., 5., 6., 5., 5.]);
    bad_idx.extend_from_slice(&[base, base + 1, base + 2, 0, 0, 0]);
    let (clean, degenerate) = (create(&pos, &idx), create(&bad_pos, &bad_idx));
    let feathers = |sys: *mut PlumageSystem| {
        let mut n = 0usize;
        unsafe { plumage_system_feather_triangles(sys, null_mut(), 0, &mut n) };
        let mut buf = vec![0f32; n];
        let st = unsafe { plumage_system_feather_triangles(sys, buf.as_mut_ptr(), n, &mut n) };
        assert_eq!(st, PLUMAGE_STATUS_OK);
        buf.iter().map(|x| x.to_bits()).collect::<Vec<u32>>()
    };
    let before = feathers(clean);
    assert!(!before.is_empty());
    assert_eq!(feathers(degenerate), before, "the degenerate triangles change no feather");
    // A frame: the extra vertices move along, the feathers still agree.
    let frame: Vec<f32> = bad_pos.chunks(3).flat_map(|p| [p[0], p[1], p[2] + 0.1 * p[0]]).collect();
    let clean_frame = &frame[..pos.len()];
    assert_eq!(unsafe { plumage_system_step(clean, clean_frame.as_ptr(), pos.len() / 3) }, PLUMAGE_STATUS_OK);
    assert_eq!(unsafe { plumage_system_step(degenerate, frame.as_ptr(), bad_pos.len() / 3) }, PLUMAGE_STATUS_OK);
    assert_eq!(feathers(degenerate), feathers(clean), "after a frame");
    unsafe { plumage_system_destroy(clean) };
    unsafe { plumage_system_destroy(degenerate) };
}

#[test]
fn bad_configs_are_refused() {
    let (pos, idx) = grid_soup();
    let d = desc(&pos, &idx);
    let mut cfg = std::mem::MaybeUninit::<PlumageConfig>::uninit();
    unsafe { plumage_config_init(cfg.as_mut_ptr()) };
    let cfg = unsafe { cfg.assume_init() };
    expect_refused(&PlumageConfig { struct_size: 8, ..cfg }, &d, PLUMAGE_STATUS_UNSUPPORTED_STRUCT_SIZE);
    expect_refused(&PlumageConfig { sampler: 7, ..cfg }, &d, PLUMAGE_STATUS_INVALID_ARGUMENT);
    expect_refused(&PlumageConfig { mode: 3, ..cfg }, &d, PLUMAGE_STATUS_INVALID_ARGUMENT);
    expect_refused(&PlumageConfig { gamma: f32::NAN, ..cfg }, &d, PLUMAGE_STATUS_NON_FINITE);
    expect_refused(&PlumageConfig { lambda: 0.9, ..cfg }, &d, PLUMAGE_STATUS_INVALID_ARGUMENT);
    expect_refused(&PlumageConfig { spacing: -1.0, ..cfg }, &d, PLUMAGE_STATUS_INVALID_ARGUMENT);
    expect_refused(&PlumageConfig { k_neighbours: 0, ..cfg }, &d, PLUMAGE_STATUS_INVALID_ARGUMENT);
    expect_refused(&PlumageConfig { curvature_min_scale: 0.0, ..cfg }, &d, PLUMAGE_STATUS_INVALID_ARGUMENT);
    expect_refused(&PlumageConfig { curvature_min_scale: f32::NAN, ..cfg }, &d, PLUMAGE_STATUS_NON_FINITE);
    expect_refused(&PlumageConfig { drift_tolerance: -0.1, ..cfg }, &d, PLUMAGE_STATUS_INVALID_ARGUMENT);
    expect_refused(&PlumageConfig { drift_tolerance: f32::INFINITY, ..cfg }, &d, PLUMAGE_STATUS_NON_FINITE);
    // Requests beyond the documented limits.
    expect_refused(&PlumageConfig { target_feathers: 1_000_000_000, ..cfg }, &d, PLUMAGE_STATUS_LIMIT_EXCEEDED);
    expect_refused(
        &PlumageConfig { target_feathers: PLUMAGE_MAX_FEATHERS + 1, ..cfg },
        &d,
        PLUMAGE_STATUS_LIMIT_EXCEEDED,
    );
    assert!(thread_error().contains(&PLUMAGE_MAX_FEATHERS.to_string()), "{}", thread_error());
    expect_refused(&PlumageConfig { spacing: 1e-9, ..cfg }, &d, PLUMAGE_STATUS_LIMIT_EXCEEDED);
    let huge: Vec<f32> = pos.iter().map(|x| x * 2.0 * PLUMAGE_MAX_COORDINATE).collect();
    expect_refused(&cfg, &desc(&huge, &idx), PLUMAGE_STATUS_LIMIT_EXCEEDED);
}

#[test]
fn a_config_of_the_first_layout_is_accepted_with_defaults_after_it() {
    // Callers compiled before `drift_tolerance`, or before
    // `curvature_min_scale`, were appended: what follows their struct is not
    // their own (here values that would be refused).
    let (pos, idx) = grid_soup();
    let d = desc(&pos, &idx);
    for end in
        [std::mem::offset_of!(PlumageConfig, drift_tolerance), std::mem::offset_of!(PlumageConfig, curvature_min_scale)]
    {
        let mut cfg = std::mem::MaybeUninit::<PlumageConfig>::uninit();
        unsafe { plumage_config_init(cfg.as_mut_ptr()) };
        let mut cfg = unsafe { cfg.assume_init() };
        cfg.struct_size = end as u32;
        cfg.curvature_min_scale = -5.0;
        if end == std::mem::offset_of!(PlumageConfig, drift_tolerance) {
            cfg.drift_tolerance = -5.0;
        }
        let mut out = null_mut();
        let st = unsafe { plumage_system_create(&cfg, &d, &mut out) };
        assert_eq!(st, PLUMAGE_STATUS_OK, "{}", thread_error());
        unsafe { plumage_system_destroy(out) };
    }
}

#[test]
fn a_larger_struct_size_is_accepted() {
    // A caller compiled against a future header: more bytes after our fields.
    #[repr(C)]
    struct Future {
        cfg: PlumageConfig,
        extra: [u64; 8],
    }
    #[repr(C)]
    struct FutureMesh {
        mesh: PlumageMeshDesc,
        extra: [u64; 8],
    }
    let (pos, idx) = grid_soup();
    let mut f = Future { cfg: unsafe { std::mem::zeroed() }, extra: [u64::MAX; 8] };
    unsafe { plumage_config_init(&mut f.cfg) };
    f.cfg.struct_size = std::mem::size_of::<Future>() as u32;
    let mut m = FutureMesh { mesh: desc(&pos, &idx), extra: [u64::MAX; 8] };
    m.mesh.struct_size = std::mem::size_of::<FutureMesh>() as u32;
    let mut out = null_mut();
    let st = unsafe { plumage_system_create(&f.cfg, &m.mesh, &mut out) };
    assert_eq!(st, PLUMAGE_STATUS_OK, "{}", thread_error());
    unsafe { plumage_system_destroy(out) };
}

#[test]
fn bad_frames_are_refused_and_leave_the_system_usable() {
    let (pos, idx) = grid_soup();
    let sys = create(&pos, &idx);
    let n = pos.len() / 3;
    assert_eq!(unsafe { plumage_system_step(null_mut(), pos.as_ptr(), n) }, PLUMAGE_STATUS_NULL_POINTER);
    assert_eq!(unsafe { plumage_system_step(sys, null(), n) }, PLUMAGE_STATUS_NULL_POINTER);
    assert!(!system_error(sys).is_empty());
    assert_eq!(unsafe { plumage_system_step(sys, pos.as_ptr(), n - 1) }, PLUMAGE_STATUS_VERTEX_COUNT_MISMATCH);
    assert!(system_error(sys).contains("vertices"), "{}", system_error(sys));
    assert_eq!(unsafe { plumage_system_step(sys, pos.as_ptr(), usize::MAX / 2) }, PLUMAGE_STATUS_SIZE_OVERFLOW);
    let mut nan = pos.clone();
    nan[4] = f32::NAN;
    assert_eq!(unsafe { plumage_system_step(sys, nan.as_ptr(), n) }, PLUMAGE_STATUS_NON_FINITE);
    assert_eq!(unsafe { plumage_system_evaluate(sys, nan.as_ptr(), n) }, PLUMAGE_STATUS_NON_FINITE);
    let mut far = pos.clone();
    far[5] = 2.0 * PLUMAGE_MAX_COORDINATE;
    assert_eq!(unsafe { plumage_system_step(sys, far.as_ptr(), n) }, PLUMAGE_STATUS_LIMIT_EXCEEDED);
    // Queries with NULL outputs.
    assert_eq!(unsafe { plumage_system_feather_count(sys, null_mut()) }, PLUMAGE_STATUS_NULL_POINTER);
    assert_eq!(unsafe { plumage_system_feather_count(null(), null_mut()) }, PLUMAGE_STATUS_NULL_POINTER);
    assert_eq!(unsafe { plumage_system_feathers(sys, null_mut(), 0, null_mut()) }, PLUMAGE_STATUS_NULL_POINTER);
    // The system still works and saw none of the refused frames.
    let moved: Vec<f32> = pos.iter().map(|x| x + 1.0).collect();
    assert_eq!(unsafe { plumage_system_step(sys, moved.as_ptr(), n) }, PLUMAGE_STATUS_OK);
    unsafe { plumage_system_destroy(sys) };
}

#[test]
fn last_error_truncates_and_reports_the_needed_size() {
    let mut out = null_mut();
    assert_eq!(unsafe { plumage_system_create(null(), null(), &mut out) }, PLUMAGE_STATUS_NULL_POINTER);
    let need = unsafe { plumage_system_last_error(null(), null_mut(), 0) };
    assert!(need > 1);
    let mut small = [0x55 as std::ffi::c_char; 4];
    assert_eq!(unsafe { plumage_system_last_error(null(), small.as_mut_ptr(), 4) }, need);
    assert_eq!(small[3], 0, "always NUL-terminated");
    let mut one = [0x55 as std::ffi::c_char; 1];
    unsafe { plumage_system_last_error(null(), one.as_mut_ptr(), 1) };
    assert_eq!(one[0], 0);
}

#[test]
fn frame_stats_report_r_k_and_the_seeds() {
    // A 20 × 20 plate (indexed); feathers point +x.
    let n = 21;
    let mut pos = Vec::new();
    for j in 0..n {
        for i in 0..n {
            pos.extend_from_slice(&[i as f32 * 0.5, j as f32 * 0.5, 0.0]);
        }
    }
    let mut idx = Vec::new();
    for j in 0..n - 1 {
        for i in 0..n - 1 {
            let a = (j * n + i) as u32;
            idx.extend_from_slice(&[a, a + 1, a + n as u32 + 1, a, a + n as u32 + 1, a + n as u32]);
        }
    }
    let d = desc(&pos, &idx);
    let mut cfg = std::mem::MaybeUninit::<PlumageConfig>::uninit();
    unsafe { plumage_config_init(cfg.as_mut_ptr()) };
    let cfg = PlumageConfig { target_feathers: 400, threads: 1, ..unsafe { cfg.assume_init() } };
    let mut sys = null_mut();
    assert_eq!(unsafe { plumage_system_create(&cfg, &d, &mut sys) }, PLUMAGE_STATUS_OK, "{}", thread_error());
    let stats = |sys: *const PlumageSystem| {
        let mut s =
            PlumageFrameStats { struct_size: std::mem::size_of::<PlumageFrameStats>() as u32, ..Default::default() };
        assert_eq!(unsafe { plumage_system_frame_stats(sys, &mut s) }, PLUMAGE_STATUS_OK);
        s
    };
    let mut feathers = 0usize;
    unsafe { plumage_system_feather_count(sys, &mut feathers) };
    let created = stats(sys);
    assert_eq!((created.deformed, created.seeds, created.adjusted), (0, feathers as u64, feathers as u64));
    // Create finds the neighbourhoods (part of its ordering time) and runs
    // the adjustment by levels: at least one, at most one per feather.
    assert!(created.neighbourhood_seconds > 0.0 && created.neighbourhood_seconds <= created.reorder_seconds);
    assert!((1..=created.adjusted).contains(&created.levels), "{} levels", created.levels);
    // Fold the strip x < 2 up about the line x = 2.
    let bent: Vec<f32> = pos
        .chunks(3)
        .flat_map(
            |p| if p[0] < 2.0 { [2.0 - (2.0 - p[0]) * 0.9, p[1], (2.0 - p[0]) * 0.44] } else { [p[0], p[1], p[2]] },
        )
        .collect();
    assert_eq!(unsafe { plumage_system_step(sys, bent.as_ptr(), pos.len() / 3) }, PLUMAGE_STATUS_OK);
    let s = stats(sys);
    assert!(s.deformed > 0, "the fold deforms roots near it");
    assert!(s.seeds <= s.adjusted, "{} ≤ {}", s.seeds, s.adjusted);
    assert!(s.verified > 0, "feathers near the fold are checked exactly");
    assert!((s.adjusted + s.verified) as usize <= feathers, "each feather is adjusted or checked at most once");
    assert!((s.adjusted as usize) < feathers, "a local fold does not readjust everything");
    assert!(s.neighbourhood_seconds > 0.0 && s.neighbourhood_seconds <= s.reorder_seconds);
    assert!((1..=feathers as u64).contains(&s.levels), "{} levels", s.levels);
    unsafe { plumage_system_destroy(sys) };
    // A legacy step keeps the neighbourhoods of the first frame.
    let cfg = PlumageConfig { mode: PLUMAGE_MODE_LEGACY, ..cfg };
    let mut sys = null_mut();
    assert_eq!(unsafe { plumage_system_create(&cfg, &d, &mut sys) }, PLUMAGE_STATUS_OK, "{}", thread_error());
    assert_eq!(unsafe { plumage_system_step(sys, bent.as_ptr(), pos.len() / 3) }, PLUMAGE_STATUS_OK);
    let s = stats(sys);
    assert!(s.adjusted > 0 && s.neighbourhood_seconds == 0.0, "{} adjusted, {} s", s.adjusted, s.neighbourhood_seconds);
    unsafe { plumage_system_destroy(sys) };
}

/// The feather geometry copy-out: totals with no buffers, a too-small buffer
/// refused by name with nothing written, and a full copy consistent with the
/// 18-float triangles of `plumage_system_feather_triangles`.
#[test]
fn feather_geometry_copy_out() {
    let (pos, idx) = grid_soup();
    let sys = create(&pos, &idx);
    let mut g = std::mem::MaybeUninit::<PlumageFeatherGeometry>::uninit();
    unsafe { plumage_feather_geometry_init(g.as_mut_ptr()) };
    let mut g = unsafe { g.assume_init() };
    assert_eq!(g.struct_size as usize, std::mem::size_of::<PlumageFeatherGeometry>());
    assert_eq!(unsafe { plumage_system_feather_geometry(sys, &mut g) }, PLUMAGE_STATUS_OK);
    let mut count = 0usize;
    assert_eq!(unsafe { plumage_system_feather_count(sys, &mut count) }, PLUMAGE_STATUS_OK);
    assert!(count > 0);
    assert_eq!(g.feather_count as usize, count);
    let (nv, nt) = (g.vertex_count as usize, g.triangle_count as usize);
    assert!(nv >= 3 * count && nt >= count);

    // One buffer too small: refused, named, nothing written.
    let mut positions = vec![f32::NAN; 3 * nv];
    let mut uvs = vec![-7.0f32; 2 * nv - 1];
    g.positions = positions.as_mut_ptr();
    g.positions_capacity = positions.len();
    g.uvs = uvs.as_mut_ptr();
    g.uvs_capacity = uvs.len();
    assert_eq!(unsafe { plumage_system_feather_geometry(sys, &mut g) }, PLUMAGE_STATUS_BUFFER_TOO_SMALL);
    assert!(system_error(sys).contains("uvs"), "{}", system_error(sys));
    assert!(positions.iter().all(|p| p.is_nan()) && uvs.iter().all(|&u| u == -7.0));

    // Everything.
    let mut uvs = vec![0f32; 2 * nv];
    let mut normals = vec![0f32; 3 * nv];
    let mut indices = vec![0u32; 3 * nt];
    let mut vertex_feathers = vec![0u32; nv];
    let mut vertex_counts = vec![0u32; count];
    let mut triangle_counts = vec![0u32; count];
    let mut placed = vec![9u8; count];
    g.uvs = uvs.as_mut_ptr();
    g.uvs_capacity = uvs.len();
    g.normals = normals.as_mut_ptr();
    g.normals_capacity = normals.len();
    g.indices = indices.as_mut_ptr();
    g.indices_capacity = indices.len();
    g.vertex_feathers = vertex_feathers.as_mut_ptr();
    g.vertex_feathers_capacity = nv;
    g.vertex_counts = vertex_counts.as_mut_ptr();
    g.vertex_counts_capacity = count;
    g.triangle_counts = triangle_counts.as_mut_ptr();
    g.triangle_counts_capacity = count;
    g.placed = placed.as_mut_ptr();
    g.placed_capacity = count;
    assert_eq!(unsafe { plumage_system_feather_geometry(sys, &mut g) }, PLUMAGE_STATUS_OK);
    assert_eq!(vertex_counts.iter().map(|&c| c as usize).sum::<usize>(), nv);
    assert_eq!(triangle_counts.iter().map(|&c| c as usize).sum::<usize>(), nt);
    assert!(placed.iter().all(|&p| p <= 1));
    assert!(uvs.iter().all(|u| (0.0..=1.0).contains(u)));
    assert!(normals.chunks(3).all(|n| ((n[0] * n[0] + n[1] * n[1] + n[2] * n[2]).sqrt() - 1.0).abs() < 1e-4));
    // Vertex feathers follow the counts; triangles stay within their feather.
    let mut first = 0usize;
    let mut tri = 0usize;
    for f in 0..count {
        let vc = vertex_counts[f] as usize;
        assert!(vertex_feathers[first..first + vc].iter().all(|&v| v as usize == f));
        for t in tri..tri + triangle_counts[f] as usize {
            assert!(indices[3 * t..3 * t + 3].iter().all(|&i| (first..first + vc).contains(&(i as usize))));
        }
        first += vc;
        tri += triangle_counts[f] as usize;
    }
    // The triangles are the ones `plumage_system_feather_triangles` copies
    // out (9 floats each), corner for corner.
    let mut len = 0usize;
    assert_eq!(
        unsafe { plumage_system_feather_triangles(sys, null_mut(), 0, &mut len) },
        PLUMAGE_STATUS_BUFFER_TOO_SMALL
    );
    let mut flat = vec![0f32; len];
    assert_eq!(
        unsafe { plumage_system_feather_triangles(sys, flat.as_mut_ptr(), flat.len(), &mut len) },
        PLUMAGE_STATUS_OK
    );
    assert_eq!(9 * nt, len);
    for t in 0..nt {
        for c in 0..3 {
            let v = indices[3 * t + c] as usize;
            assert_eq!(&positions[3 * v..3 * v + 3], &flat[9 * t + 3 * c..9 * t + 3 * c + 3]);
        }
    }
    assert_eq!(unsafe { plumage_system_feather_geometry(sys, null_mut()) }, PLUMAGE_STATUS_NULL_POINTER);
    assert_eq!(unsafe { plumage_system_feather_geometry(null(), &mut g) }, PLUMAGE_STATUS_NULL_POINTER);
    unsafe { plumage_system_destroy(sys) };
}

/// Validation: the coat figures appended to `PlumageValidation`, and
/// older, shorter structs (up to `mean_pitch_deg`, up to `bristle_percent`)
/// filled up to their size.
#[test]
fn validation_reports_tip_heights_and_fills_older_structs() {
    let (pos, idx) = grid_soup();
    let sys = create(&pos, &idx);
    let mut v =
        PlumageValidation { struct_size: std::mem::size_of::<PlumageValidation>() as u32, ..Default::default() };
    assert_eq!(unsafe { plumage_system_validate(sys, &mut v) }, PLUMAGE_STATUS_OK);
    assert!(v.tip_height_median >= 0.0 && v.tip_height_median <= v.tip_height_p90 && v.tip_height_p90 <= 1.0);
    assert!((0.0..=100.0).contains(&v.bristle_percent));
    assert!(v.stack_efficiency.is_finite() && v.stack_efficiency > 0.0, "{}", v.stack_efficiency);
    assert!(v.stack_depth_median >= 0.0 && v.stack_depth_median.fract() == 0.0);
    // The layout before the stack figures: filled up to `bristle_percent`.
    let before_stacks = std::mem::offset_of!(PlumageValidation, stack_efficiency);
    let mut previous =
        PlumageValidation { struct_size: before_stacks as u32, stack_efficiency: -1.0, ..Default::default() };
    assert_eq!(unsafe { plumage_system_validate(sys, &mut previous) }, PLUMAGE_STATUS_OK);
    assert_eq!(previous.struct_size as usize, before_stacks);
    assert_eq!((previous.bristle_percent, previous.stack_efficiency), (v.bristle_percent, -1.0));
    let old = std::mem::offset_of!(PlumageValidation, probes);
    let mut short = PlumageValidation { struct_size: old as u32, tip_height_p90: -3.0, ..Default::default() };
    assert_eq!(unsafe { plumage_system_validate(sys, &mut short) }, PLUMAGE_STATUS_OK);
    assert_eq!(short.struct_size as usize, old);
    assert_eq!(short.coverage, v.coverage);
    assert_eq!(short.tip_height_p90, -3.0, "bytes past struct_size are not written");
    let mut tiny = PlumageValidation { struct_size: 8, ..Default::default() };
    assert_eq!(unsafe { plumage_system_validate(sys, &mut tiny) }, PLUMAGE_STATUS_UNSUPPORTED_STRUCT_SIZE);
    unsafe { plumage_system_destroy(sys) };
}

/// Presets: scales are short, wide and nearly rigid; sleek feathers are the
/// default feathers with four shaft segments; an unknown preset is
/// refused and leaves the struct as it was; a scale coat is collision-free
/// and its scales are half as long as feathers would be.
#[test]
fn presets_fill_the_config() {
    let mut cfg = std::mem::MaybeUninit::<PlumageConfig>::uninit();
    assert_eq!(unsafe { plumage_config_init_preset(cfg.as_mut_ptr(), PLUMAGE_PRESET_SCALES) }, PLUMAGE_STATUS_OK);
    let scales = unsafe { cfg.assume_init() };
    assert_eq!(scales.struct_size as usize, std::mem::size_of::<PlumageConfig>());
    assert_eq!((scales.length_per_spacing, scales.width_per_spacing, scales.shaft_segments), (2.0, 2.0, 2));
    let mut feathers = scales;
    assert_eq!(unsafe { plumage_config_init_preset(&mut feathers, PLUMAGE_PRESET_FEATHERS) }, PLUMAGE_STATUS_OK);
    let mut plain = std::mem::MaybeUninit::<PlumageConfig>::uninit();
    unsafe { plumage_config_init(plain.as_mut_ptr()) };
    let plain = unsafe { plain.assume_init() };
    assert_eq!(
        (feathers.length_per_spacing, feathers.shaft_segments),
        (plain.length_per_spacing, plain.shaft_segments)
    );
    let mut sleek = scales;
    assert_eq!(unsafe { plumage_config_init_preset(&mut sleek, PLUMAGE_PRESET_SLEEK) }, PLUMAGE_STATUS_OK);
    assert_eq!(
        (sleek.length_per_spacing, sleek.width_per_spacing, sleek.shaft_segments, sleek.bend_limit),
        (plain.length_per_spacing, plain.width_per_spacing, 4, plain.bend_limit)
    );
    let mut kept = scales;
    assert_eq!(unsafe { plumage_config_init_preset(&mut kept, 7) }, PLUMAGE_STATUS_INVALID_ARGUMENT);
    assert!(thread_error().contains("preset 7"), "{}", thread_error());
    assert_eq!(kept.shaft_segments, scales.shaft_segments);
    assert_eq!(unsafe { plumage_config_init_preset(null_mut(), PLUMAGE_PRESET_SCALES) }, PLUMAGE_STATUS_NULL_POINTER);

    let (pos, idx) = grid_soup();
    let d = desc(&pos, &idx);
    let mut length = [0.0f32; 2];
    for (k, cfg) in [plain, scales].iter().enumerate() {
        let mut sys = null_mut();
        assert_eq!(unsafe { plumage_system_create(cfg, &d, &mut sys) }, PLUMAGE_STATUS_OK, "{}", thread_error());
        let mut v =
            PlumageValidation { struct_size: std::mem::size_of::<PlumageValidation>() as u32, ..Default::default() };
        assert_eq!(unsafe { plumage_system_validate(sys, &mut v) }, PLUMAGE_STATUS_OK);
        assert_eq!((v.intersecting_pairs, v.body_penetrations), (0, 0));
        let mut n = 0usize;
        unsafe { plumage_system_feathers(sys, null_mut(), 0, &mut n) };
        let mut records = vec![PlumageFeather::default(); n];
        assert_eq!(unsafe { plumage_system_feathers(sys, records.as_mut_ptr(), n, &mut n) }, PLUMAGE_STATUS_OK);
        let spacing = {
            let mut s = PlumageSamplingStats {
                struct_size: std::mem::size_of::<PlumageSamplingStats>() as u32,
                ..Default::default()
            };
            assert_eq!(unsafe { plumage_system_sampling_stats(sys, &mut s) }, PLUMAGE_STATUS_OK);
            s.spacing
        };
        length[k] = records.iter().map(|f| f.length).fold(0.0, f32::max) / spacing as f32;
        unsafe { plumage_system_destroy(sys) };
    }
    assert!((length[0] - 4.0).abs() < 0.5 && (length[1] - 2.0).abs() < 0.3, "longest per spacing {length:?}");
}

#[test]
fn seek_returns_the_frame_to_replay_from_and_refuses_without_checkpoints() {
    let (pos, idx) = grid_soup();
    let d = desc(&pos, &idx);
    let mut cfg = std::mem::MaybeUninit::<PlumageConfig>::uninit();
    unsafe { plumage_config_init(cfg.as_mut_ptr()) };
    let mut cfg = unsafe { cfg.assume_init() };
    assert_eq!((cfg.checkpoint_interval, cfg.checkpoint_cap), (0, 64), "defaults");
    // Off: refused, the system unchanged.
    let sys = create(&pos, &idx);
    let mut from = 7u64;
    assert_eq!(unsafe { plumage_system_seek(sys, 3, &mut from) }, PLUMAGE_STATUS_INVALID_ARGUMENT);
    assert!(system_error(sys).contains("checkpoint_interval"), "{}", system_error(sys));
    assert_eq!(from, 7, "a refused seek writes nothing");
    unsafe { plumage_system_destroy(sys) };
    cfg.checkpoint_cap = 0;
    expect_refused(&cfg, &d, PLUMAGE_STATUS_INVALID_ARGUMENT);
    cfg.checkpoint_cap = 4;
    cfg.checkpoint_interval = 2;
    let mut sys = null_mut();
    assert_eq!(unsafe { plumage_system_create(&cfg, &d, &mut sys) }, PLUMAGE_STATUS_OK, "{}", thread_error());
    let frame: Vec<f32> = pos.chunks(3).flat_map(|p| [p[0], p[1], p[2] + 0.05 * p[0] * p[0]]).collect();
    for _ in 0..5 {
        assert_eq!(unsafe { plumage_system_step(sys, frame.as_ptr(), frame.len() / 3) }, PLUMAGE_STATUS_OK);
    }
    assert_eq!(unsafe { plumage_system_seek(sys, 3, null_mut()) }, PLUMAGE_STATUS_NULL_POINTER);
    assert_eq!(unsafe { plumage_system_seek(sys, 3, &mut from) }, PLUMAGE_STATUS_OK, "{}", system_error(sys));
    assert_eq!(from, 2, "the checkpoint at or before frame 3");
    assert_eq!(unsafe { plumage_system_seek(sys, 9, &mut from) }, PLUMAGE_STATUS_OK);
    assert_eq!(from, 4, "a later checkpoint than the current frame is nearer");
    assert_eq!(unsafe { plumage_system_step(sys, frame.as_ptr(), frame.len() / 3) }, PLUMAGE_STATUS_OK);
    assert_eq!(unsafe { plumage_system_seek(sys, 9, &mut from) }, PLUMAGE_STATUS_OK);
    assert_eq!(from, 5, "forward within the playback: stay and replay from here");
    assert_eq!(unsafe { plumage_system_seek(null_mut(), 3, &mut from) }, PLUMAGE_STATUS_NULL_POINTER);
    unsafe { plumage_system_destroy(sys) };
}
