//! The orientation and density fields on the welded mesh (DESIGN.md §3).
//!
//! Orientation: one unit tangent per welded vertex at the rest pose. Host
//! hints are projected onto each vertex's tangent plane; without hints the
//! config's flow axis is projected instead and the result smoothed. Where
//! the projection is degenerate (normal ∥ hint or axis) the direction is
//! filled from neighbouring vertices.
//!
//! Density: the global spacing `d` times a per-vertex multiplier; a
//! multiplier of 0 marks bare skin. Across a face, "bare" and "spacing" are
//! blended separately, so a bare vertex never pulls the spacing towards 0
//! (which would mean *denser* roots): a point is bare when the barycentric
//! weight of its bare corners exceeds ½, and elsewhere its multiplier is the
//! blend of the feathered corners' multipliers alone.

use crate::config::Config;
use crate::error::{Error, ErrorKind, Result};
use crate::geometry::SurfacePoint;
use crate::mesh::WeldedMesh;
use crate::spacing::nominal_spacing;
use crate::surface::Surface;
use glam::Vec3;

/// Tangent projections shorter than this fraction of the projected vector
/// are degenerate (the vector is within ~3° of the normal).
const DEGENERATE_TANGENT: f32 = 0.05;

/// Smoothing passes over a field derived from the flow axis.
const SMOOTHING_ITERATIONS: usize = 4;

/// Smoothing passes over the curvature spacing multiplier, so that the
/// spacing changes over a few rings of vertices rather than at one.
const CURVATURE_SMOOTHING: usize = 2;

/// The per-vertex arrays the fields are built from, each optional, per
/// welded vertex.
#[derive(Clone, Copy, Debug, Default)]
pub struct VertexMaps<'a> {
    /// xyz tangent hints, used as given (projected, not smoothed).
    pub orientations: Option<&'a [f32]>,
    /// xyz flow from the skeleton ([`crate::skeleton::SkeletonInput::flow_hints`]).
    pub skeleton_flow: Option<&'a [f32]>,
    /// Spacing multipliers (0 = bare skin).
    pub spacing_scale: Option<&'a [f32]>,
    /// Feather length multipliers.
    pub length_scale: Option<&'a [f32]>,
    /// Feather width multipliers.
    pub width_scale: Option<&'a [f32]>,
}

/// Per-vertex fields of one welded mesh.
#[derive(Clone, Debug)]
pub struct Fields {
    directions: Vec<Vec3>,
    spacing_scale: Vec<f32>,
    length_scale: Vec<f32>,
    width_scale: Vec<f32>,
}

impl Fields {
    /// Builds the fields from `maps` (per *welded* vertex: use
    /// [`WeldedMesh::weld_attribute`]). The orientation field is, in order of
    /// precedence: the hints as given; the flow away from
    /// `config.flow_source`; the skeleton's flow; `config.flow_axis` (derived
    /// when zero). Derived flows are projected and smoothed. `config` is
    /// checked by [`Config::validate`], the one rule for its fields.
    pub fn new(mesh: &WeldedMesh, surface: &Surface, maps: &VertexMaps<'_>, config: &Config) -> Result<Self> {
        config.validate()?;
        let n = mesh.positions.len();
        if surface.vertex_count() != n {
            return Err(Error::new(
                ErrorKind::InvalidArgument,
                format!("surface has {} vertices but the welded mesh has {n}", surface.vertex_count()),
            ));
        }
        let normals = surface.rest_vertex_normals();
        let directions = match maps.orientations {
            Some(hints) => {
                check_values("orientations", hints, 3 * n, false)?;
                let hints: Vec<Vec3> = hints.chunks_exact(3).map(|c| Vec3::new(c[0], c[1], c[2])).collect();
                let mut dirs = project_onto_tangent_planes(&hints, normals);
                fill_from_neighbours(surface, normals, &mut dirs);
                dirs.into_iter().map(Option::unwrap).collect()
            }
            None => {
                // A checked config's axis is finite and not tiny, or zero:
                // derived, always a unit vector.
                let axis = if config.flow_axis == Vec3::ZERO { principal_flow_axis(mesh) } else { config.flow_axis };
                let flow = match (config.flow_source, maps.skeleton_flow) {
                    (Some(source), _) => flow_from_source(mesh, surface, source, axis),
                    // A skeleton whose bones give no direction anywhere (no
                    // vertex weighted to a joint with a bone) leaves the axis.
                    (None, Some(bones)) if bones.iter().any(|&x| x != 0.0) => {
                        check_values("skeleton flow", bones, 3 * n, false)?;
                        bones.chunks_exact(3).map(|c| Vec3::new(c[0], c[1], c[2])).collect()
                    }
                    (None, _) => vec![axis; n],
                };
                let mut dirs = project_onto_tangent_planes(&flow, normals);
                fill_from_neighbours(surface, normals, &mut dirs);
                let dirs = dirs.into_iter().map(Option::unwrap).collect();
                smooth_directions(surface, normals, dirs, SMOOTHING_ITERATIONS)
            }
        };
        let mut spacing_scale = multiplier("spacing_scale", maps.spacing_scale, n)?;
        if config.curvature_min_scale < 1.0 && config.feather_length <= 0.0 {
            let length = nominal_feather_length(surface, config);
            let bend = curvature_spacing(mesh, surface, normals, length, config.curvature_min_scale);
            for (s, b) in spacing_scale.iter_mut().zip(bend) {
                *s *= b;
            }
        }
        clamp_multiplier_range(&mut spacing_scale);
        Ok(Self {
            directions,
            spacing_scale,
            length_scale: clamped(multiplier("length_scale", maps.length_scale, n)?),
            width_scale: clamped(multiplier("width_scale", maps.width_scale, n)?),
        })
    }

    /// Unit rest tangent direction of each welded vertex.
    pub fn vertex_directions(&self) -> &[Vec3] {
        &self.directions
    }

    /// Spacing multiplier of each welded vertex (0 = bare skin).
    pub fn vertex_spacing_scales(&self) -> &[f32] {
        &self.spacing_scale
    }

    /// Whether any vertex carries feathers.
    pub fn any_feathered(&self) -> bool {
        self.spacing_scale.iter().any(|&s| s > 0.0)
    }

    /// The field direction at `p`, as a unit vector in the plane normal to
    /// `normal`: the barycentric blend of the corner directions, projected;
    /// where the blend cancels, the dominant corner's direction; failing
    /// that, any tangent.
    pub fn direction_at(&self, surface: &Surface, p: SurfacePoint, normal: Vec3) -> Vec3 {
        let tri = surface.triangles()[p.face as usize];
        let blend = (0..3).fold(Vec3::ZERO, |acc, k| acc + self.directions[tri[k] as usize] * p.bary[k]);
        let project = |v: Vec3| (v - normal * v.dot(normal)).try_normalize();
        project(blend)
            .or_else(|| {
                let k = (0..3).max_by(|&a, &b| p.bary[a].total_cmp(&p.bary[b])).unwrap_or(0);
                project(self.directions[tri[k] as usize])
            })
            .unwrap_or_else(|| normal.any_orthonormal_vector())
    }

    /// The spacing multiplier at `p`, or `None` where the skin is bare.
    pub fn spacing_scale_at(&self, surface: &Surface, p: SurfacePoint) -> Option<f32> {
        let tri = surface.triangles()[p.face as usize];
        let (mut presence, mut blend) = (0.0f32, 0.0f32);
        for (&v, &w) in tri.iter().zip(&p.bary) {
            let s = self.spacing_scale[v as usize];
            if s > 0.0 {
                presence += w;
                blend += w * s;
            }
        }
        (presence >= 0.5).then(|| blend / presence)
    }

    /// The feather length multiplier at `p` (barycentric blend).
    pub fn length_scale_at(&self, surface: &Surface, p: SurfacePoint) -> f32 {
        blend_at(&self.length_scale, surface, p)
    }

    /// The feather width multiplier at `p` (barycentric blend).
    pub fn width_scale_at(&self, surface: &Surface, p: SurfacePoint) -> f32 {
        blend_at(&self.width_scale, surface, p)
    }

    /// The median positive per-vertex spacing multiplier (1 when none).
    pub(crate) fn median_spacing_scale(&self) -> f32 {
        let mut positive: Vec<f32> = self.spacing_scale.iter().copied().filter(|&s| s > 0.0).collect();
        if positive.is_empty() {
            return 1.0;
        }
        positive.sort_unstable_by(f32::total_cmp);
        positive[positive.len() / 2]
    }
}

/// The barycentric blend at `p` of per-vertex `values`.
pub(crate) fn blend_at(values: &[f32], surface: &Surface, p: SurfacePoint) -> f32 {
    let tri = surface.triangles()[p.face as usize];
    (0..3).map(|k| values[tri[k] as usize] * p.bary[k]).sum()
}

/// `scales` after [`clamp_multiplier_range`].
fn clamped(mut scales: Vec<f32>) -> Vec<f32> {
    clamp_multiplier_range(&mut scales);
    scales
}

/// Brings positive multipliers (spacing, length, width) within
/// [`MAX_MULTIPLIER_RATIO`](crate::limits::MAX_MULTIPLIER_RATIO) of their median
/// either way (0 stays 0): the sampler's rejection and its grid queries take
/// time in proportion to the density ratio, and a feather 10^38 times longer
/// than its neighbours has no finite geometry.
fn clamp_multiplier_range(scales: &mut [f32]) {
    let mut positive: Vec<f32> = scales.iter().copied().filter(|&s| s > 0.0).collect();
    if positive.is_empty() {
        return;
    }
    let mid = positive.len() / 2;
    let median = *positive.select_nth_unstable_by(mid, f32::total_cmp).1;
    let ratio = crate::limits::MAX_MULTIPLIER_RATIO;
    let (lo, hi) = (median / ratio, median * ratio);
    scales.iter_mut().filter(|s| **s > 0.0).for_each(|s| *s = s.clamp(lo, hi));
}

fn multiplier(name: &str, values: Option<&[f32]>, n: usize) -> Result<Vec<f32>> {
    match values {
        None => Ok(vec![1.0; n]),
        Some(v) => {
            check_values(name, v, n, true)?;
            Ok(v.to_vec())
        }
    }
}

fn check_values(name: &str, values: &[f32], expected: usize, non_negative: bool) -> Result<()> {
    if values.len() != expected {
        return Err(Error::new(
            ErrorKind::InvalidArgument,
            format!("{name} holds {} values, expected {expected} (per welded vertex)", values.len()),
        ));
    }
    if let Some((i, x)) = values.iter().enumerate().find(|(_, x)| !x.is_finite()) {
        return Err(Error::new(ErrorKind::NonFinite, format!("{name}[{i}] is {x}")));
    }
    if non_negative {
        if let Some((i, x)) = values.iter().enumerate().find(|(_, x)| **x < 0.0) {
            return Err(Error::new(ErrorKind::InvalidArgument, format!("{name}[{i}] is {x}; it must be >= 0")));
        }
    }
    Ok(())
}

/// About how long a feather will be before any multiplier: the default
/// shape's length for the configured spacing, or for the spacing that
/// spreads the wanted feather count over the whole surface.
fn nominal_feather_length(surface: &Surface, config: &Config) -> f32 {
    config.length_per_spacing * nominal_spacing(surface.rest_area(), config)
}

/// Per vertex, the spacing multiplier the bending of the surface calls for:
/// `R / L`, clamped to `[min_scale, 1]`, with `L` the nominal feather length
/// and `R` the smallest radius of curvature along the vertex's edges (edge
/// length over the angle between the two ends' normals). A feather longer
/// than the radius it lies on stands off a convex part (a thin leg, a wing
/// tip) and runs into the far wall of a concave one (a crease); with the
/// spacing, and so the feather, scaled to the radius it wraps the part.
/// Smoothed over the neighbours a few times (Jacobi, order-independent).
fn curvature_spacing(mesh: &WeldedMesh, surface: &Surface, normals: &[Vec3], length: f32, min_scale: f32) -> Vec<f32> {
    let p = &mesh.positions;
    let mut scale: Vec<f32> = (0..p.len())
        .map(|v| {
            let curvature = surface.vertex_neighbours(v).iter().map(|&u| u as usize).fold(0.0f32, |k, u| {
                let edge = p[u].distance(p[v]);
                let angle = normals[u].dot(normals[v]).clamp(-1.0, 1.0).acos();
                if edge > 0.0 && angle.is_finite() { k.max(angle / edge) } else { k }
            });
            let radius = 1.0 / curvature;
            if (radius / length).is_nan() { 1.0 } else { (radius / length).clamp(min_scale, 1.0) }
        })
        .collect();
    for _ in 0..CURVATURE_SMOOTHING {
        scale = (0..scale.len())
            .map(|v| {
                let ring = surface.vertex_neighbours(v);
                (scale[v] + ring.iter().map(|&u| scale[u as usize]).sum::<f32>()) / (1 + ring.len()) as f32
            })
            .collect();
    }
    scale
}

/// Per vertex, the direction in which the surface distance from the vertex
/// nearest `source` grows fastest (a least-squares gradient over the
/// vertex's edges; distances along mesh edges, by Dijkstra). Vertices the
/// source cannot reach (another component) get `axis`.
/// The flow axis of a mesh given none: the principal axis of its surface
/// (the largest eigenvector of the area-weighted covariance of its
/// triangles' centroids), the long axis of a body, a limb or a wing,
/// signed by glTF's conventions (models face +Z, +Y is up): towards −Z,
/// so that feathers run from the front to the back; an axis across Z
/// points down (−Y), and one along X points to +X. Deterministic: sums in
/// triangle order, a fixed number of power iterations from a fixed start.
fn principal_flow_axis(mesh: &WeldedMesh) -> Vec3 {
    let corners = |t: &[u32; 3]| t.map(|v| mesh.positions[v as usize].as_dvec3());
    let area = |[a, b, c]: [glam::DVec3; 3]| 0.5 * (b - a).cross(c - a).length();
    let (mut total, mut mean) = (0.0f64, glam::DVec3::ZERO);
    for t in &mesh.triangles {
        let c = corners(t);
        total += area(c);
        mean += area(c) * (c[0] + c[1] + c[2]) / 3.0;
    }
    if total.is_nan() || total <= 0.0 {
        return Vec3::X;
    }
    mean /= total;
    let mut cov = glam::DMat3::ZERO;
    for t in &mesh.triangles {
        let c = corners(t);
        let d = (c[0] + c[1] + c[2]) / 3.0 - mean;
        cov += glam::DMat3::from_cols(d * d.x, d * d.y, d * d.z) * area(c);
    }
    let mut axis = glam::DVec3::new(0.3, 0.5, 0.8).normalize();
    for _ in 0..64 {
        match (cov * axis).try_normalize() {
            Some(next) => axis = next,
            None => return Vec3::X,
        }
    }
    let preferred = [glam::DVec3::NEG_Z, glam::DVec3::NEG_Y, glam::DVec3::X];
    let sign = preferred.iter().map(|p| axis.dot(*p)).find(|d| d.abs() > 0.1).unwrap_or(1.0).signum();
    (axis * sign).as_vec3()
}

fn flow_from_source(mesh: &WeldedMesh, surface: &Surface, source: Vec3, axis: Vec3) -> Vec<Vec3> {
    use petgraph::graph::{NodeIndex, UnGraph};
    let p = &mesh.positions;
    let n = p.len();
    let mut graph = UnGraph::<(), f32>::with_capacity(n, surface.edge_count());
    for _ in 0..n {
        graph.add_node(());
    }
    for e in 0..surface.edge_count() {
        let [a, b] = surface.edge_vertices(e);
        graph.add_edge(NodeIndex::new(a as usize), NodeIndex::new(b as usize), p[a as usize].distance(p[b as usize]));
    }
    // The nearest vertex, lowest index on ties.
    let start = (0..n).min_by(|&a, &b| p[a].distance_squared(source).total_cmp(&p[b].distance_squared(source)));
    let Some(start) = start else { return Vec::new() };
    let found = petgraph::algo::dijkstra(&graph, NodeIndex::new(start), None, |e| *e.weight());
    let mut distance = vec![f32::INFINITY; n];
    for (node, d) in found {
        distance[node.index()] = d;
    }
    (0..n)
        .map(|v| {
            if !distance[v].is_finite() {
                return axis;
            }
            let gradient =
                surface.vertex_neighbours(v).iter().map(|&u| u as usize).filter(|&u| distance[u].is_finite()).fold(
                    Vec3::ZERO,
                    |g, u| {
                        let edge = p[u] - p[v];
                        let len2 = edge.length_squared();
                        if len2 > 0.0 { g + edge * ((distance[u] - distance[v]) / len2) } else { g }
                    },
                );
            gradient.try_normalize().unwrap_or(Vec3::ZERO)
        })
        .collect()
}

/// Each vector projected onto its vertex's tangent plane and normalised;
/// `None` where the projection is degenerate.
fn project_onto_tangent_planes(vectors: &[Vec3], normals: &[Vec3]) -> Vec<Option<Vec3>> {
    vectors
        .iter()
        .zip(normals)
        .map(|(&v, &n)| {
            let t = v - n * v.dot(n);
            (t.length() > DEGENERATE_TANGENT * v.length()).then(|| t.normalize())
        })
        .collect()
}

/// Fills degenerate directions from already known neighbours, one ring at a
/// time (each ring reads only the previous state, so the result does not
/// depend on visiting order). Vertices of a component with no known
/// direction get an arbitrary tangent.
fn fill_from_neighbours(surface: &Surface, normals: &[Vec3], dirs: &mut [Option<Vec3>]) {
    loop {
        let fills: Vec<(usize, Vec3)> = (0..dirs.len())
            .filter(|&v| dirs[v].is_none())
            .filter_map(|v| {
                let n = normals[v];
                let sum = surface
                    .vertex_neighbours(v)
                    .iter()
                    .filter_map(|&u| dirs[u as usize])
                    .fold(Vec3::ZERO, |a, d| a + d);
                let known = surface.vertex_neighbours(v).iter().any(|&u| dirs[u as usize].is_some());
                known
                    .then(|| (sum - n * sum.dot(n)).try_normalize().unwrap_or_else(|| n.any_orthonormal_vector()))
                    .map(|d| (v, d))
            })
            .collect();
        if fills.is_empty() {
            break;
        }
        for (v, d) in fills {
            dirs[v] = Some(d);
        }
    }
    for (v, d) in dirs.iter_mut().enumerate() {
        if d.is_none() {
            *d = Some(normals[v].any_orthonormal_vector());
        }
    }
}

/// Jacobi smoothing: each vertex takes the sum of its own and its
/// neighbours' directions, projected onto its tangent plane.
fn smooth_directions(surface: &Surface, normals: &[Vec3], mut dirs: Vec<Vec3>, iterations: usize) -> Vec<Vec3> {
    for _ in 0..iterations {
        dirs = (0..dirs.len())
            .map(|v| {
                let n = normals[v];
                let sum = surface.vertex_neighbours(v).iter().fold(dirs[v], |a, &u| a + dirs[u as usize]);
                (sum - n * sum.dot(n)).try_normalize().unwrap_or(dirs[v])
            })
            .collect();
    }
    dirs
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::mesh::{MeshInput, weld};

    fn plate() -> WeldedMesh {
        let pos = [0., 0., 0., 1., 0., 0., 1., 1., 0., 0., 1., 0.];
        weld(&MeshInput::new(&pos, &[0, 1, 2, 0, 2, 3])).unwrap()
    }

    fn weld_of(positions: Vec<Vec3>, triangles: Vec<[u32; 3]>) -> WeldedMesh {
        let pos: Vec<f32> = positions.iter().flat_map(|p| p.to_array()).collect();
        let idx: Vec<u32> = triangles.iter().flatten().copied().collect();
        weld(&MeshInput::new(&pos, &idx)).unwrap()
    }

    #[test]
    fn a_mesh_given_no_axis_flows_along_its_long_axis_towards_its_back() {
        // A box 10 long in z, 2 across: the axis is ±Z, signed towards −Z.
        let mut positions = Vec::new();
        for &z in &[-5.0f32, 5.0] {
            for &(x, y) in &[(-1.0f32, -1.0f32), (1.0, -1.0), (1.0, 1.0), (-1.0, 1.0)] {
                positions.push(Vec3::new(x, y, z));
            }
        }
        let quads = [[0, 1, 2, 3], [4, 7, 6, 5], [0, 4, 5, 1], [1, 5, 6, 2], [2, 6, 7, 3], [3, 7, 4, 0]];
        let triangles: Vec<[u32; 3]> = quads.iter().flat_map(|q| [[q[0], q[1], q[2]], [q[0], q[2], q[3]]]).collect();
        let mesh = weld_of(positions.clone(), triangles.clone());
        let axis = principal_flow_axis(&mesh);
        assert!((axis - Vec3::NEG_Z).length() < 1e-4, "{axis:?}");
        // Turned to lie along y: points down.
        let turned = weld_of(positions.iter().map(|p| Vec3::new(p.x, p.z, p.y)).collect(), triangles);
        assert!((principal_flow_axis(&turned) - Vec3::NEG_Y).length() < 1e-4);
    }

    #[test]
    fn flow_axis_is_projected_and_degenerate_axis_is_filled() {
        let mesh = plate();
        let s = Surface::new(&mesh);
        let cfg = Config { flow_axis: Vec3::new(1.0, 0.0, 5.0), ..Config::default() };
        let f = Fields::new(&mesh, &s, &VertexMaps::default(), &cfg).unwrap();
        for d in f.vertex_directions() {
            assert!((*d - Vec3::X).length() < 1e-5, "{d:?}");
        }
        // Axis along the normal everywhere: still unit tangents, no NaN.
        let cfg = Config { flow_axis: Vec3::Z, ..Config::default() };
        let f = Fields::new(&mesh, &s, &VertexMaps::default(), &cfg).unwrap();
        for d in f.vertex_directions() {
            assert!((d.length() - 1.0).abs() < 1e-5 && d.z.abs() < 1e-5);
        }
    }

    #[test]
    fn a_config_the_rule_refuses_is_refused() {
        let mesh = plate();
        let s = Surface::new(&mesh);
        for flow_axis in [Vec3::new(f32::NAN, 0.0, 0.0), Vec3::new(1e-9, 0.0, 0.0)] {
            let cfg = Config { flow_axis, ..Config::default() };
            let e = Fields::new(&mesh, &s, &VertexMaps::default(), &cfg).unwrap_err();
            assert_eq!(e.kind(), ErrorKind::InvalidArgument);
            assert!(e.message().contains("flow_axis"), "{}", e.message());
        }
    }

    #[test]
    fn host_hints_are_projected_and_missing_ones_filled() {
        let mesh = plate();
        let s = Surface::new(&mesh);
        // Vertex 2's hint is zero: it takes its neighbours' direction.
        let hints = [0.0, 1.0, 3.0, 0.0, 2.0, -1.0, 0.0, 0.0, 0.0, 0.0, 0.5, 0.0];
        let f = Fields::new(
            &mesh,
            &s,
            &VertexMaps { orientations: Some(&hints), ..Default::default() },
            &Config::default(),
        )
        .unwrap();
        for d in f.vertex_directions() {
            assert!((*d - Vec3::Y).length() < 1e-5, "{d:?}");
        }
        let at = f.direction_at(&s, SurfacePoint { face: 0, bary: [0.2, 0.3, 0.5] }, Vec3::Z);
        assert!((at - Vec3::Y).length() < 1e-5);
    }

    /// A closed prism of `sides` sides, radius `r` and height `20 r`
    /// around z, capped.
    fn prism(r: f32, sides: usize) -> WeldedMesh {
        let mut pos = Vec::new();
        for z in [0.0f32, 20.0 * r] {
            for k in 0..sides {
                let a = std::f32::consts::TAU * k as f32 / sides as f32;
                pos.extend_from_slice(&[r * a.cos(), r * a.sin(), z]);
            }
        }
        pos.extend_from_slice(&[0.0, 0.0, 0.0, 0.0, 0.0, 20.0 * r]);
        let (s, bottom, top) = (sides as u32, 2 * sides as u32, 2 * sides as u32 + 1);
        let mut idx = Vec::new();
        for k in 0..s {
            let j = (k + 1) % s;
            idx.extend_from_slice(&[k, j, s + j, k, s + j, s + k, bottom, j, k, top, s + k, s + j]);
        }
        weld(&MeshInput::new(&pos, &idx)).unwrap()
    }

    #[test]
    fn bending_shrinks_the_spacing_down_to_the_limit() {
        let (thin, thick) = (prism(0.5, 12), prism(50.0, 12));
        let config = Config { spacing: 1.0, ..Config::default() };
        let scales = |mesh: &WeldedMesh, config: &Config| {
            let s = Surface::new(mesh);
            Fields::new(mesh, &s, &VertexMaps::default(), config).unwrap().vertex_spacing_scales().to_vec()
        };
        // A leg of radius 0.5 under feathers 4 long: every vertex at the limit.
        for &x in &scales(&thin, &config) {
            assert!((x - config.curvature_min_scale).abs() < 1e-6, "{x}");
        }
        // A barrel of radius 50 with 12 sides: bent, but not on the scale of a feather.
        assert!(scales(&thick, &config).iter().all(|&x| x == 1.0));
        // Off when turned off, or when the feather length is fixed.
        for off in [Config { curvature_min_scale: 1.0, ..config.clone() }, Config { feather_length: 2.0, ..config }] {
            assert!(scales(&thin, &off).iter().all(|&x| x == 1.0));
        }
    }

    #[test]
    fn bare_corners_do_not_shrink_the_spacing() {
        let mesh = plate();
        let s = Surface::new(&mesh);
        let scale = [0.0, 2.0, 2.0, 2.0];
        let f = Fields::new(
            &mesh,
            &s,
            &VertexMaps { spacing_scale: Some(&scale), ..Default::default() },
            &Config::default(),
        )
        .unwrap();
        let near_bare = SurfacePoint { face: 0, bary: [0.4, 0.3, 0.3] };
        assert_eq!(f.spacing_scale_at(&s, near_bare), Some(2.0));
        let bare = SurfacePoint { face: 0, bary: [0.6, 0.2, 0.2] };
        assert_eq!(f.spacing_scale_at(&s, bare), None);
        assert!(
            Fields::new(
                &mesh,
                &s,
                &VertexMaps { spacing_scale: Some(&[1.0; 3]), ..Default::default() },
                &Config::default()
            )
            .is_err()
        );
    }
}
