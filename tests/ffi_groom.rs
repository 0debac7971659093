//! The groom's C inputs (`PlumageSkeleton`, `layer`, the type map) refused
//! with a status, never a crash, and accepted when well formed.

mod common;

use common::shapes::cylinder;
use plumage::ffi::*;
use std::ptr::{null, null_mut};

fn create(desc: &PlumageMeshDesc) -> (PlumageStatus, *mut PlumageSystem) {
    let mut cfg = std::mem::MaybeUninit::<PlumageConfig>::uninit();
    unsafe { plumage_config_init(cfg.as_mut_ptr()) };
    let mut cfg = unsafe { cfg.assume_init() };
    cfg.target_feathers = 150;
    let mut out = null_mut();
    let status = unsafe { plumage_system_create(&cfg, desc, &mut out) };
    (status, out)
}

fn destroyed(status: PlumageStatus, sys: *mut PlumageSystem) -> PlumageStatus {
    if !sys.is_null() {
        assert_eq!(unsafe { plumage_system_destroy(sys) }, PLUMAGE_STATUS_OK);
    }
    status
}

#[test]
fn skeletons_layers_and_type_maps_are_checked_at_the_boundary() {
    let shape = cylinder(0.5, 2.0, 24, 16);
    let n = shape.vertex_count();
    let mut base = std::mem::MaybeUninit::<PlumageMeshDesc>::uninit();
    unsafe { plumage_mesh_desc_init(base.as_mut_ptr()) };
    let mut base = unsafe { base.assume_init() };
    base.positions = shape.positions.as_ptr();
    base.vertex_count = n;
    base.indices = shape.indices.as_ptr();
    base.triangle_count = shape.indices.len() / 3;

    // A two-joint skeleton along the cylinder's axis.
    let joints = [0.0f32, 0.0, 2.0, 0.0, 0.0, 0.0];
    let parents = [-1i32, 0];
    let vj = vec![0u32; n];
    let vw = vec![1.0f32; n];
    let second = vec![1u32; n];
    let skeleton = PlumageSkeleton {
        joint_count: 2,
        influences: 1,
        joint_positions: joints.as_ptr(),
        joint_parents: parents.as_ptr(),
        vertex_joints: vj.as_ptr(),
        vertex_weights: vw.as_ptr(),
        head_joint: -1,
    };
    let with = |s: &PlumageSkeleton| PlumageMeshDesc { skeleton: s, ..base };
    let (st, sys) = create(&with(&skeleton));
    assert_eq!(destroyed(st, sys), PLUMAGE_STATUS_OK);
    let cases = [
        (PlumageSkeleton { joint_positions: null(), ..skeleton }, PLUMAGE_STATUS_NULL_POINTER),
        (PlumageSkeleton { vertex_weights: null(), ..skeleton }, PLUMAGE_STATUS_NULL_POINTER),
        (PlumageSkeleton { joint_count: 0, ..skeleton }, PLUMAGE_STATUS_INVALID_ARGUMENT),
        (PlumageSkeleton { influences: 17, ..skeleton }, PLUMAGE_STATUS_INVALID_ARGUMENT),
        (PlumageSkeleton { head_joint: 2, ..skeleton }, PLUMAGE_STATUS_INDEX_OUT_OF_RANGE),
        (
            PlumageSkeleton { joint_count: 1, vertex_joints: second.as_ptr(), ..skeleton },
            PLUMAGE_STATUS_INDEX_OUT_OF_RANGE,
        ),
    ];
    for (k, (bad, want)) in cases.into_iter().enumerate() {
        let (st, sys) = create(&with(&bad));
        assert_eq!(destroyed(st, sys), want, "case {k}");
        assert!(sys.is_null(), "case {k}: nothing is created");
    }
    let cycle = [1i32, 0];
    let cyclic = PlumageSkeleton { joint_parents: cycle.as_ptr(), ..skeleton };
    let (st, sys) = create(&with(&cyclic));
    assert_eq!(destroyed(st, sys), PLUMAGE_STATUS_INVALID_ARGUMENT, "cycle");

    let mut layer = vec![0.0f32; n];
    let (st, sys) = create(&PlumageMeshDesc { layer: layer.as_ptr(), ..base });
    assert_eq!(destroyed(st, sys), PLUMAGE_STATUS_OK);
    layer[7] = f32::INFINITY;
    let (st, sys) = create(&PlumageMeshDesc { layer: layer.as_ptr(), ..base });
    assert_eq!(destroyed(st, sys), PLUMAGE_STATUS_NON_FINITE);

    let mut types = [std::mem::MaybeUninit::<PlumageFeatherType>::uninit(); 2];
    for (t, preset) in types.iter_mut().zip([PLUMAGE_PRESET_FEATHERS, PLUMAGE_PRESET_SCALES]) {
        assert_eq!(unsafe { plumage_feather_type_init(t.as_mut_ptr(), preset) }, PLUMAGE_STATUS_OK);
    }
    let types = types.map(|t| unsafe { t.assume_init() });
    assert_eq!(unsafe { plumage_feather_type_init(null_mut(), PLUMAGE_PRESET_SCALES) }, PLUMAGE_STATUS_NULL_POINTER);
    let mut spare = types[0];
    assert_eq!(unsafe { plumage_feather_type_init(&mut spare, 99) }, PLUMAGE_STATUS_INVALID_ARGUMENT);
    let kinds: Vec<u32> = (0..n as u32).map(|v| v % 2).collect();
    let typed =
        PlumageMeshDesc { feather_type: kinds.as_ptr(), feather_types: types.as_ptr(), feather_type_count: 2, ..base };
    let (st, sys) = create(&typed);
    assert_eq!(destroyed(st, sys), PLUMAGE_STATUS_OK);
    for (k, (bad, want)) in [
        (PlumageMeshDesc { feather_types: null(), ..typed }, PLUMAGE_STATUS_NULL_POINTER),
        (PlumageMeshDesc { feather_type_count: 0, ..typed }, PLUMAGE_STATUS_INVALID_ARGUMENT),
        (PlumageMeshDesc { feather_type_count: 1, ..typed }, PLUMAGE_STATUS_INDEX_OUT_OF_RANGE),
    ]
    .into_iter()
    .enumerate()
    {
        let (st, sys) = create(&bad);
        assert_eq!(destroyed(st, sys), want, "type case {k}");
    }
    let nan = [PlumageFeatherType { length_per_spacing: f32::NAN, ..types[0] }, types[1]];
    let (st, sys) = create(&PlumageMeshDesc { feather_types: nan.as_ptr(), ..typed });
    assert_eq!(destroyed(st, sys), PLUMAGE_STATUS_INVALID_ARGUMENT, "NaN proportion");
}
