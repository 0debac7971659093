//! Reads the triangle meshes of a `.glb` test model into flat arrays, at the
//! rest shape: each mesh node's world transform applied, morph targets
//! blended with the node's (else the mesh's) default weights. Buffer data
//! comes from the GLB's binary chunk only (the models embed everything).
//!
//! Like the C++ host, a model with animated meshes (skinned or morphed) is
//! read as those meshes only: the Fox's four display bases are not part of
//! the animal. A skinned mesh is read in its bind pose, where glTF ignores
//! the node's own transform; [`skinned_clip`] skins it frame by frame.
//!
//! The models live in `../shared/data` relative to the crate root (see
//! [`data_dir`] for the override). A missing model fails the test that
//! needs it, unless `PLUMAGE_ALLOW_MISSING_DATA=1` is set: then
//! [`load_model`], [`morph_clip`] and [`skinned_clip`] print a numbered
//! `SKIPPED` line on stderr and return `None`, and the calling test checks
//! nothing.

use super::shapes::Shape;
use glam::{Mat4, Vec3};
use std::path::PathBuf;

/// Where the shared test models are: `../shared/data` from the crate root,
/// or `$PLUMAGE_DATA_DIR` when set (e.g. for a git worktree elsewhere).
pub fn data_dir() -> PathBuf {
    match std::env::var_os("PLUMAGE_DATA_DIR") {
        Some(dir) => PathBuf::from(dir),
        None => PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../shared/data"),
    }
}

/// Environment variable that turns a missing test model from a failure
/// into a counted skip.
pub const ALLOW_MISSING_DATA: &str = "PLUMAGE_ALLOW_MISSING_DATA";

/// Models reported missing by this test binary (numbers the skip lines).
static SKIPPED: std::sync::atomic::AtomicUsize = std::sync::atomic::AtomicUsize::new(0);

/// The bytes of the model at `path`. Missing: a panic naming the path and
/// the opt-out, or with `PLUMAGE_ALLOW_MISSING_DATA=1` a numbered skip line
/// and `None`.
pub fn read_model(path: &std::path::Path) -> Option<Vec<u8>> {
    match std::fs::read(path) {
        Ok(b) => Some(b),
        Err(e) if std::env::var(ALLOW_MISSING_DATA).is_ok_and(|v| v == "1") => {
            let n = SKIPPED.fetch_add(1, std::sync::atomic::Ordering::SeqCst) + 1;
            eprintln!(
                "SKIPPED ({n} in this test binary): test model {} not available ({e}); {ALLOW_MISSING_DATA}=1, so the test checks nothing",
                path.display()
            );
            None
        }
        Err(e) => panic!(
            "test model {} not available ({e}): the models live in ../shared/data from the crate root or in $PLUMAGE_DATA_DIR; set {ALLOW_MISSING_DATA}=1 to skip the tests that need them",
            path.display()
        ),
    }
}

/// Loads every triangle primitive of every mesh node of the default scene
/// of `file` (e.g. "Flamingo.glb"). A missing file: see [`read_model`].
pub fn load_model(file: &str) -> Option<Shape> {
    let path = data_dir().join(file);
    let bytes = read_model(&path)?;
    Some(read_glb(&bytes).unwrap_or_else(|e| panic!("{} is not a readable GLB: {e}", path.display())))
}

/// Parses GLB bytes into one flat mesh.
pub fn read_glb(bytes: &[u8]) -> Result<Shape, String> {
    read_glb_with_weights(bytes, None)
}

/// Parses GLB bytes into one flat mesh, with `weights` (node index, morph
/// weights) replacing that node's default morph weights.
pub fn read_glb_with_weights(bytes: &[u8], weights: Option<(usize, &[f32])>) -> Result<Shape, String> {
    let gltf = gltf::Gltf::from_slice(bytes).map_err(|e| e.to_string())?;
    read_gltf_posed(&gltf, weights, None)
}

/// [`read_glb_with_weights`] on a parsed model; with `worlds` (every
/// node's world matrix, by node index) a skinned mesh is skinned by its
/// joints at those matrices (linear blend skinning, glTF's convention)
/// instead of read in its bind pose.
fn read_gltf_posed(
    gltf: &gltf::Gltf,
    weights: Option<(usize, &[f32])>,
    worlds: Option<&[Mat4]>,
) -> Result<Shape, String> {
    let blob: Option<&[u8]> = gltf.blob.as_deref();
    let scene = gltf.default_scene().or_else(|| gltf.scenes().next()).ok_or("no scene")?;
    let mut out = Shape::default();
    let animated = |node: &gltf::Node| {
        node.skin().is_some() || node.mesh().is_some_and(|m| m.primitives().any(|p| p.morph_targets().next().is_some()))
    };
    let mut all = Vec::new();
    let mut stack: Vec<gltf::Node> = scene.nodes().collect();
    while let Some(node) = stack.pop() {
        stack.extend(node.children());
        all.push(node);
    }
    let only_animated = all.iter().any(animated);
    let mut stack: Vec<(gltf::Node, Mat4)> = scene.nodes().map(|n| (n, Mat4::IDENTITY)).collect();
    while let Some((node, parent)) = stack.pop() {
        let world = parent * Mat4::from_cols_array_2d(&node.transform().matrix());
        let wanted = !only_animated || animated(&node);
        let placement = if node.skin().is_some() { Mat4::IDENTITY } else { world };
        if let Some(mesh) = node.mesh().filter(|_| wanted) {
            let weights = match weights {
                Some((index, w)) if index == node.index() => w,
                _ => node.weights().or(mesh.weights()).unwrap_or(&[]),
            };
            let joints = match (node.skin(), worlds) {
                (Some(skin), Some(worlds)) => Some(joint_matrices(&skin, blob, worlds)),
                _ => None,
            };
            for primitive in mesh.primitives() {
                if primitive.mode() != gltf::mesh::Mode::Triangles {
                    continue;
                }
                append_primitive(&mut out, &primitive, blob, weights, placement, joints.as_deref())?;
            }
        }
        stack.extend(node.children().map(|c| (c, world)));
    }
    if out.indices.is_empty() {
        return Err("no triangles".into());
    }
    Ok(out)
}

fn append_primitive(
    out: &mut Shape,
    primitive: &gltf::Primitive,
    blob: Option<&[u8]>,
    weights: &[f32],
    world: Mat4,
    joints: Option<&[Mat4]>,
) -> Result<(), String> {
    let reader = primitive.reader(|buffer| match buffer.source() {
        gltf::buffer::Source::Bin => blob,
        gltf::buffer::Source::Uri(_) => None,
    });
    let mut positions: Vec<Vec3> =
        reader.read_positions().ok_or("primitive without positions")?.map(Vec3::from).collect();
    for (target, (displacements, _, _)) in reader.read_morph_targets().enumerate() {
        let w = weights.get(target).copied().unwrap_or(0.0);
        if let (Some(displacements), true) = (displacements, w != 0.0) {
            for (p, d) in positions.iter_mut().zip(displacements) {
                *p += Vec3::from(d) * w;
            }
        }
    }
    if let Some(joints) = joints {
        let indices = reader.read_joints(0).ok_or("skinned primitive without JOINTS_0")?.into_u16();
        let blend = reader.read_weights(0).ok_or("skinned primitive without WEIGHTS_0")?.into_f32();
        for ((p, j), w) in positions.iter_mut().zip(indices).zip(blend) {
            let skin: Mat4 = (0..4).map(|k| joints[j[k] as usize] * w[k]).fold(Mat4::ZERO, |a, b| a + b);
            *p = skin.transform_point3(*p);
        }
    }
    let base = out.vertex_count() as u32;
    for p in &positions {
        let q = world.transform_point3(*p);
        out.positions.extend_from_slice(&[q.x, q.y, q.z]);
    }
    match reader.read_indices() {
        Some(indices) => out.indices.extend(indices.into_u32().map(|i| i + base)),
        None => out.indices.extend((0..positions.len() as u32).map(|i| i + base)),
    }
    Ok(())
}

/// The frames of a model's first morph-weight animation sampled at `fps`
/// (LINEAR interpolation of the weights; node transforms taken as static),
/// each as flat positions in the numbering of [`read_glb`]. A missing file:
/// see [`read_model`].
pub fn morph_clip(file: &str, fps: f32) -> Option<(Shape, Vec<Vec<f32>>)> {
    let path = data_dir().join(file);
    let bytes = read_model(&path)?;
    let gltf = gltf::Gltf::from_slice(&bytes).expect("readable GLB");
    let blob = gltf.blob.as_deref();
    let animation = gltf.animations().next().expect("an animation");
    let channel = animation
        .channels()
        .find(|c| c.target().property() == gltf::animation::Property::MorphTargetWeights)
        .expect("a morph weight channel");
    let node = channel.target().node().index();
    let reader = channel.reader(|b| match b.source() {
        gltf::buffer::Source::Bin => blob,
        gltf::buffer::Source::Uri(_) => None,
    });
    let times: Vec<f32> = reader.read_inputs().expect("key times").collect();
    let values: Vec<f32> = match reader.read_outputs().expect("key values") {
        gltf::animation::util::ReadOutputs::MorphTargetWeights(w) => w.into_f32().collect(),
        _ => unreachable!("morph weight channel"),
    };
    let targets = values.len() / times.len();
    let duration = *times.last().unwrap();
    let count = (duration * fps).floor() as usize + 1;
    let rest = read_glb(&bytes).expect("rest shape");
    let frames = (0..count)
        .map(|k| {
            let t = (k as f32 / fps).min(duration);
            let i = times.partition_point(|&x| x <= t).clamp(1, times.len() - 1);
            let (t0, t1) = (times[i - 1], times[i]);
            let u = if t1 > t0 { ((t - t0) / (t1 - t0)).clamp(0.0, 1.0) } else { 0.0 };
            let w: Vec<f32> =
                (0..targets).map(|m| values[(i - 1) * targets + m] * (1.0 - u) + values[i * targets + m] * u).collect();
            read_glb_with_weights(&bytes, Some((node, &w))).expect("frame shape").positions
        })
        .collect();
    Some((rest, frames))
}

/// The shape of `file` as a loader that gets the vertex layout wrong reads
/// it: each primitive's positions re-read from the binary chunk at
/// `stride` bytes apart starting `offset` bytes after the accessor's start
/// (ignoring the bufferView's own stride), so that positions mix with the
/// normals, UVs, joints and indices stored beside them. Reads that would
/// run past the chunk wrap around to its start. Indices and node placement
/// are read correctly. A missing file: see [`read_model`].
pub fn misread_model(file: &str, stride: usize, offset: usize) -> Option<Shape> {
    let path = data_dir().join(file);
    let bytes = read_model(&path)?;
    Some(misread_glb(&bytes, stride, offset))
}

/// [`misread_model`] on GLB bytes already read.
pub fn misread_glb(bytes: &[u8], stride: usize, offset: usize) -> Shape {
    let mut shape = read_glb(bytes).expect("readable GLB");
    let gltf = gltf::Gltf::from_slice(bytes).expect("readable GLB");
    let blob = gltf.blob.as_deref().expect("a binary chunk");
    // The positions are replaced wholesale, one position accessor after
    // another (cycling), as far as the shape's vertex count reaches.
    let mut starts = Vec::new();
    for mesh in gltf.meshes() {
        for p in mesh.primitives() {
            if let Some(a) = p.get(&gltf::Semantic::Positions) {
                if let Some(view) = a.view() {
                    starts.push((view.offset() + a.offset(), a.count()));
                }
            }
        }
    }
    let word = |at: usize| -> f32 {
        let at = at % (blob.len() - 3);
        f32::from_le_bytes([blob[at], blob[at + 1], blob[at + 2], blob[at + 3]])
    };
    let mut out = Vec::with_capacity(shape.positions.len());
    'fill: for &(start, count) in starts.iter().cycle().take(starts.len().max(1) * 64) {
        for v in 0..count {
            if out.len() >= shape.positions.len() {
                break 'fill;
            }
            let at = start + offset + v * stride;
            out.extend_from_slice(&[word(at), word(at + 4), word(at + 8)]);
        }
    }
    shape.positions = out;
    shape
}

/// The joint matrices of `skin` (each joint's world matrix times its
/// inverse bind matrix) with the nodes at `worlds`.
fn joint_matrices(skin: &gltf::Skin, blob: Option<&[u8]>, worlds: &[Mat4]) -> Vec<Mat4> {
    let reader = skin.reader(|b| match b.source() {
        gltf::buffer::Source::Bin => blob,
        gltf::buffer::Source::Uri(_) => None,
    });
    let inverse: Vec<Mat4> = reader
        .read_inverse_bind_matrices()
        .map(|m| m.map(|c| Mat4::from_cols_array_2d(&c)).collect())
        .unwrap_or_default();
    skin.joints()
        .enumerate()
        .map(|(k, joint)| worlds[joint.index()] * inverse.get(k).copied().unwrap_or(Mat4::IDENTITY))
        .collect()
}

/// Every node's world matrix with the model's first animation sampled at
/// time `t` (LINEAR and STEP keys; a CUBICSPLINE key's value, its tangents
/// left out).
fn node_worlds(gltf: &gltf::Gltf, t: f32) -> Vec<Mat4> {
    use glam::Quat;
    use gltf::animation::util::ReadOutputs;
    let blob = gltf.blob.as_deref();
    let mut local: Vec<(Vec3, Quat, Vec3)> = gltf
        .nodes()
        .map(|n| {
            let (t, r, s) = n.transform().decomposed();
            (Vec3::from(t), Quat::from_array(r), Vec3::from(s))
        })
        .collect();
    for animation in gltf.animations().take(1) {
        for channel in animation.channels() {
            let reader = channel.reader(|b| match b.source() {
                gltf::buffer::Source::Bin => blob,
                gltf::buffer::Source::Uri(_) => None,
            });
            let Some(times) = reader.read_inputs().map(|i| i.collect::<Vec<f32>>()) else { continue };
            if times.is_empty() {
                continue;
            }
            let interpolation = channel.sampler().interpolation();
            let i = times.partition_point(|&x| x <= t).clamp(1, times.len().max(2) - 1).min(times.len() - 1);
            let (t0, t1) = (times[i.saturating_sub(1)], times[i]);
            let u = match interpolation {
                gltf::animation::Interpolation::Step => 0.0,
                _ if t1 > t0 => ((t - t0) / (t1 - t0)).clamp(0.0, 1.0),
                _ => 0.0,
            };
            // A cubic spline key holds (in-tangent, value, out-tangent).
            let key = |values: &[[f32; 4]], k: usize| match interpolation {
                gltf::animation::Interpolation::CubicSpline => values[3 * k + 1],
                _ => values[k],
            };
            let (a, b) = (i.saturating_sub(1), i);
            let node = &mut local[channel.target().node().index()];
            match reader.read_outputs() {
                Some(ReadOutputs::Translations(v)) => {
                    let v: Vec<[f32; 4]> = v.map(|p| [p[0], p[1], p[2], 0.0]).collect();
                    let (p, q) = (Vec3::from_slice(&key(&v, a)), Vec3::from_slice(&key(&v, b)));
                    node.0 = p.lerp(q, u);
                }
                Some(ReadOutputs::Scales(v)) => {
                    let v: Vec<[f32; 4]> = v.map(|p| [p[0], p[1], p[2], 0.0]).collect();
                    let (p, q) = (Vec3::from_slice(&key(&v, a)), Vec3::from_slice(&key(&v, b)));
                    node.2 = p.lerp(q, u);
                }
                Some(ReadOutputs::Rotations(r)) => {
                    let v: Vec<[f32; 4]> = r.into_f32().collect();
                    let (p, q) = (Quat::from_array(key(&v, a)).normalize(), Quat::from_array(key(&v, b)).normalize());
                    node.1 = p.slerp(q, u);
                }
                _ => {}
            }
        }
    }
    let mut worlds = vec![Mat4::IDENTITY; local.len()];
    let scene = gltf.default_scene().or_else(|| gltf.scenes().next());
    let mut stack: Vec<(gltf::Node, Mat4)> =
        scene.map(|s| s.nodes().map(|n| (n, Mat4::IDENTITY)).collect()).unwrap_or_default();
    while let Some((node, parent)) = stack.pop() {
        let (t, r, s) = local[node.index()];
        let world = parent * Mat4::from_scale_rotation_translation(s, r, t);
        worlds[node.index()] = world;
        stack.extend(node.children().map(|c| (c, world)));
    }
    worlds
}

/// A skinned model's animation sampled at `fps` for up to `frames` frames
/// from its start, each skinned (see [`node_worlds`]), as flat positions in
/// the numbering of [`read_glb`]: the first frame as the rest shape, the
/// others as the clip. A missing file: see [`read_model`].
pub fn skinned_clip(file: &str, fps: f32, frames: usize) -> Option<(Shape, Vec<Vec<f32>>)> {
    let path = data_dir().join(file);
    let bytes = read_model(&path)?;
    let gltf = gltf::Gltf::from_slice(&bytes).expect("readable GLB");
    let shape_at = |k: usize| {
        let worlds = node_worlds(&gltf, k as f32 / fps);
        read_gltf_posed(&gltf, None, Some(&worlds)).expect("a skinned frame")
    };
    let rest = shape_at(0);
    let clip = (1..frames).map(|k| shape_at(k).positions).collect();
    Some((rest, clip))
}
