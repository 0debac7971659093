//! The safe Rust API: the same contract as the C ABI, without pointers.

use plumage::{Config, ErrorKind, MeshInput, System};

fn quad() -> (Vec<f32>, Vec<u32>) {
    (vec![0., 0., 0., 1., 0., 0., 1., 1., 0., 0., 1., 0.], vec![0, 1, 2, 0, 2, 3])
}

#[test]
fn create_and_step() {
    let (pos, idx) = quad();
    let mut sys = System::new(&Config::default(), &MeshInput::new(&pos, &idx)).unwrap();
    assert_eq!(sys.vertex_count(), 4);
    sys.step(&pos).unwrap();
    assert_eq!(sys.frames_stepped(), 1);
}

#[test]
fn refusals_leave_the_system_unchanged() {
    let (pos, idx) = quad();
    let mut sys = System::new(&Config::default(), &MeshInput::new(&pos, &idx)).unwrap();
    let before = sys.mesh().positions.clone();
    assert_eq!(sys.step(&pos[..9]).unwrap_err().kind(), ErrorKind::VertexCountMismatch);
    let mut nan = pos.clone();
    nan[0] = f32::NAN;
    assert_eq!(sys.step(&nan).unwrap_err().kind(), ErrorKind::NonFinite);
    assert_eq!(sys.evaluate(&nan).unwrap_err().kind(), ErrorKind::NonFinite);
    assert_eq!(sys.mesh().positions, before);
    assert_eq!(sys.frames_stepped(), 0);
}

#[test]
fn bad_meshes_have_distinct_kinds() {
    let (pos, idx) = quad();
    let cfg = Config::default();
    let kind = |p: &[f32], i: &[u32]| System::new(&cfg, &MeshInput::new(p, i)).unwrap_err().kind();
    assert_eq!(kind(&[], &idx), ErrorKind::EmptyMesh);
    assert_eq!(kind(&pos, &[]), ErrorKind::EmptyMesh);
    assert_eq!(kind(&pos, &[0, 1, 9]), ErrorKind::IndexOutOfRange);
    assert_eq!(kind(&pos[..10], &idx), ErrorKind::InvalidMesh);
    assert_eq!(kind(&[0., 0., 0., 1., 1., 1., 2., 2., 2.], &[0, 1, 2]), ErrorKind::DegenerateMesh);
    let mut inf = pos.clone();
    inf[5] = f32::INFINITY;
    assert_eq!(kind(&inf, &idx), ErrorKind::NonFinite);
}
