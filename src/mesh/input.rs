//! The mesh as the caller hands it in, and the checks it must pass.

use crate::error::{Error, ErrorKind, Result};
use crate::feather::FeatherTypeMap;
use crate::skeleton::SkeletonInput;

/// A borrowed mesh in the caller's own vertex numbering.
#[derive(Clone, Copy, Debug)]
pub struct MeshInput<'a> {
    /// xyz per vertex (`3 × vertex_count` floats).
    pub positions: &'a [f32],
    /// Three vertex indices per triangle.
    pub indices: &'a [u32],
    /// Optional xyz tangent hint per vertex (the orientation field).
    pub orientations: Option<&'a [f32]>,
    /// Optional spacing multiplier per vertex (0 = bare skin).
    pub spacing_scale: Option<&'a [f32]>,
    /// Optional feather length multiplier per vertex.
    pub length_scale: Option<&'a [f32]>,
    /// Optional feather width multiplier per vertex.
    pub width_scale: Option<&'a [f32]>,
    /// Optional skeleton the vertices are skinned to: without orientation
    /// hints or a flow source, the orientation field follows its bones.
    pub skeleton: Option<SkeletonInput<'a>>,
    /// Optional layer per vertex (finite): where two neighbouring feathers'
    /// layers differ, the one on the higher layer lies on top.
    pub layer: Option<&'a [f32]>,
    /// Optional feather type per vertex: each feather takes the type of the
    /// corner nearest its root.
    pub feather_types: Option<FeatherTypeMap<'a>>,
}

impl<'a> MeshInput<'a> {
    /// A mesh with positions and indices only.
    pub fn new(positions: &'a [f32], indices: &'a [u32]) -> Self {
        Self {
            positions,
            indices,
            orientations: None,
            spacing_scale: None,
            length_scale: None,
            width_scale: None,
            skeleton: None,
            layer: None,
            feather_types: None,
        }
    }

    /// Number of vertices (positions / 3).
    pub fn vertex_count(&self) -> usize {
        self.positions.len() / 3
    }

    /// Checks counts, finiteness, index range and the optional per-vertex
    /// arrays. Degenerate triangles are judged later, by the welder.
    pub fn check(&self) -> Result<()> {
        if self.positions.is_empty() {
            return Err(Error::new(ErrorKind::EmptyMesh, "mesh has no vertices"));
        }
        if self.indices.is_empty() {
            return Err(Error::new(ErrorKind::EmptyMesh, "mesh has no triangles"));
        }
        if self.positions.len() % 3 != 0 {
            return Err(Error::new(
                ErrorKind::InvalidMesh,
                format!("positions hold {} floats, not a multiple of 3", self.positions.len()),
            ));
        }
        if self.indices.len() % 3 != 0 {
            return Err(Error::new(
                ErrorKind::InvalidMesh,
                format!("indices hold {} values, not a multiple of 3", self.indices.len()),
            ));
        }
        let n = self.vertex_count();
        if n > u32::MAX as usize {
            return Err(Error::new(ErrorKind::SizeOverflow, format!("{n} vertices exceed the 32-bit index range")));
        }
        check_finite("position", self.positions, 3)?;
        check_magnitude(self.positions)?;
        if let Some((k, &i)) = self.indices.iter().enumerate().find(|&(_, &i)| i as usize >= n) {
            return Err(Error::new(
                ErrorKind::IndexOutOfRange,
                format!("triangle {} corner {} has index {} but the mesh has {} vertices", k / 3, k % 3, i, n),
            ));
        }
        if let Some(o) = self.orientations {
            check_len("orientations", o.len(), 3 * n)?;
            check_finite("orientation", o, 3)?;
        }
        for (name, arr) in [
            ("spacing_scale", self.spacing_scale),
            ("length_scale", self.length_scale),
            ("width_scale", self.width_scale),
        ] {
            if let Some(a) = arr {
                check_len(name, a.len(), n)?;
                if let Some((v, x)) = a.iter().enumerate().find(|(_, x)| !x.is_finite() || **x < 0.0) {
                    let kind = if x.is_finite() { ErrorKind::InvalidArgument } else { ErrorKind::NonFinite };
                    return Err(Error::new(kind, format!("{name} of vertex {v} is {x}; it must be finite and >= 0")));
                }
            }
        }
        if let Some(layer) = self.layer {
            check_len("layer", layer.len(), n)?;
            check_finite("layer", layer, 1)?;
        }
        if let Some(skeleton) = &self.skeleton {
            skeleton.check(n)?;
        }
        if let Some(types) = &self.feather_types {
            types.check(n)?;
        }
        Ok(())
    }
}

/// Checks a frame's positions: the right vertex count and finite values.
pub fn check_frame_positions(positions: &[f32], expected_vertices: usize) -> Result<()> {
    if positions.len() != expected_vertices * 3 {
        return Err(Error::new(
            ErrorKind::VertexCountMismatch,
            format!("frame has {} vertices but the rest mesh has {}", positions.len() / 3, expected_vertices),
        ));
    }
    check_finite("position", positions, 3)?;
    check_magnitude(positions)
}

/// Refuses coordinates beyond [`MAX_COORDINATE`](crate::limits::MAX_COORDINATE).
fn check_magnitude(positions: &[f32]) -> Result<()> {
    let limit = crate::limits::MAX_COORDINATE;
    match positions.iter().position(|x| x.abs() > limit) {
        None => Ok(()),
        Some(k) => Err(Error::new(
            ErrorKind::LimitExceeded,
            format!(
                "position of vertex {} has a coordinate of {:e}, beyond the supported magnitude {limit:e} model units; scale the model down",
                k / 3,
                positions[k]
            ),
        )),
    }
}

fn check_len(name: &str, got: usize, want: usize) -> Result<()> {
    if got != want {
        return Err(Error::new(ErrorKind::InvalidMesh, format!("{name} holds {got} values, expected {want}")));
    }
    Ok(())
}

fn check_finite(what: &str, values: &[f32], stride: usize) -> Result<()> {
    match values.iter().position(|x| !x.is_finite()) {
        None => Ok(()),
        Some(k) => Err(Error::new(
            ErrorKind::NonFinite,
            format!("{what} of vertex {} has a non-finite coordinate ({})", k / stride, values[k]),
        )),
    }
}
