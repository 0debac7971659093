//! Small procedural meshes (positions as xyz floats, triangle indices).

use std::f32::consts::TAU;

/// A mesh as flat arrays, the way a host hands it in.
#[derive(Clone, Debug, Default)]
pub struct Shape {
    pub positions: Vec<f32>,
    pub indices: Vec<u32>,
}

impl Shape {
    pub fn vertex_count(&self) -> usize {
        self.positions.len() / 3
    }

    pub fn vertex(&self, v: usize) -> [f32; 3] {
        [self.positions[3 * v], self.positions[3 * v + 1], self.positions[3 * v + 2]]
    }

    /// Appends another shape (indices offset).
    pub fn append(&mut self, other: &Shape) {
        let base = self.vertex_count() as u32;
        self.positions.extend_from_slice(&other.positions);
        self.indices.extend(other.indices.iter().map(|i| i + base));
    }
}

/// A `w × h` plate in the z = `z` plane split into `nx × ny` quads (two
/// triangles each); `up` chooses whether normals face +z or −z.
pub fn grid(w: f32, h: f32, nx: usize, ny: usize, z: f32, up: bool) -> Shape {
    let mut s = Shape::default();
    for j in 0..=ny {
        for i in 0..=nx {
            s.positions.extend_from_slice(&[w * i as f32 / nx as f32, h * j as f32 / ny as f32, z]);
        }
    }
    let at = |i: usize, j: usize| (j * (nx + 1) + i) as u32;
    for j in 0..ny {
        for i in 0..nx {
            let (a, b, c, d) = (at(i, j), at(i + 1, j), at(i + 1, j + 1), at(i, j + 1));
            if up {
                s.indices.extend_from_slice(&[a, b, c, a, c, d]);
            } else {
                s.indices.extend_from_slice(&[a, c, b, a, d, c]);
            }
        }
    }
    s
}

/// A closed UV sphere of radius 1 round the origin, poles on ±z (the
/// south pole first), `rings` bands of `sides` quads (triangles at the
/// poles), normals outward; with an even `rings`, one ring of vertices lies
/// exactly on the equator (z = 0).
pub fn uv_sphere(rings: usize, sides: usize) -> Shape {
    assert!(rings >= 2 && sides >= 3);
    let mut s = Shape::default();
    s.positions.extend_from_slice(&[0.0, 0.0, -1.0]);
    for r in 1..rings {
        let polar = std::f32::consts::PI * r as f32 / rings as f32;
        let z = if 2 * r == rings { 0.0 } else { -polar.cos() };
        for k in 0..sides {
            let a = std::f32::consts::TAU * k as f32 / sides as f32;
            s.positions.extend_from_slice(&[polar.sin() * a.cos(), polar.sin() * a.sin(), z]);
        }
    }
    s.positions.extend_from_slice(&[0.0, 0.0, 1.0]);
    let top = (s.positions.len() / 3 - 1) as u32;
    let ring = |r: usize, k: usize| (1 + (r - 1) * sides + k % sides) as u32;
    for k in 0..sides {
        s.indices.extend_from_slice(&[0, ring(1, k + 1), ring(1, k)]);
        for r in 1..rings - 1 {
            let (a, b, c, d) = (ring(r, k), ring(r, k + 1), ring(r + 1, k + 1), ring(r + 1, k));
            s.indices.extend_from_slice(&[a, b, c, a, c, d]);
        }
        s.indices.extend_from_slice(&[top, ring(rings - 1, k), ring(rings - 1, k + 1)]);
    }
    s
}

/// An open cylinder (prism) of `sides` sides and `rings` rows of quads
/// around the z axis, from z = 0 to `height`, normals outward.
pub fn cylinder(radius: f32, height: f32, sides: usize, rings: usize) -> Shape {
    let mut s = Shape::default();
    for r in 0..=rings {
        for k in 0..sides {
            let a = TAU * k as f32 / sides as f32;
            s.positions.extend_from_slice(&[radius * a.cos(), radius * a.sin(), height * r as f32 / rings as f32]);
        }
    }
    let at = |k: usize, r: usize| (r * sides + k % sides) as u32;
    for r in 0..rings {
        for k in 0..sides {
            let (a, b, c, d) = (at(k, r), at(k + 1, r), at(k + 1, r + 1), at(k, r + 1));
            s.indices.extend_from_slice(&[a, b, c, a, c, d]);
        }
    }
    s
}

/// A closed box `w × h × t`: two `nx × ny` skins `t` apart (top faces +z,
/// bottom −z) joined by a one-quad-high rim strip.
pub fn thin_box(w: f32, h: f32, t: f32, nx: usize, ny: usize) -> Shape {
    let mut s = grid(w, h, nx, ny, 0.0, false);
    s.append(&grid(w, h, nx, ny, t, true));
    let per_skin = ((nx + 1) * (ny + 1)) as u32;
    let at = |i: usize, j: usize| (j * (nx + 1) + i) as u32;
    // The rim, walked counterclockwise seen from +z.
    let mut ring = Vec::new();
    ring.extend((0..nx).map(|i| at(i, 0)));
    ring.extend((0..ny).map(|j| at(nx, j)));
    ring.extend((0..nx).map(|i| at(nx - i, ny)));
    ring.extend((0..ny).map(|j| at(0, ny - j)));
    for k in 0..ring.len() {
        let (a, b) = (ring[k], ring[(k + 1) % ring.len()]);
        let (ta, tb) = (a + per_skin, b + per_skin);
        s.indices.extend_from_slice(&[a, b, tb, a, tb, ta]);
    }
    s
}

/// The C++ host's built-in model (`cpp_examples/gltf_host/procedural_model.cpp`)
/// ported: a body 4 long along x swimming with a wave travelling to the
/// tail, `rings` cross-sections of `segments` vertices (seam duplicated)
/// and two poles. [`swim_pose`] gives its positions at time `t` seconds
/// (period 1 s; the wave fades in over the first half second).
pub fn swim_body(rings: usize, segments: usize) -> Shape {
    let ring_size = (segments + 1) as u32;
    let vertex = |ring: usize, seg: usize| (ring - 1) as u32 * ring_size + seg as u32;
    let head = (rings - 1) as u32 * ring_size;
    let tail = head + 1;
    let mut indices = Vec::new();
    for i in 1..rings - 1 {
        for j in 0..segments {
            let (a, b) = (vertex(i, j), vertex(i, j + 1));
            if i == 1 {
                indices.extend_from_slice(&[head, a, b]);
            }
            if i + 2 < rings {
                let (c, d) = (vertex(i + 1, j), vertex(i + 1, j + 1));
                indices.extend_from_slice(&[a, c, d, a, d, b]);
            } else {
                indices.extend_from_slice(&[a, tail, b]);
            }
        }
    }
    Shape { positions: swim_pose(rings, segments, 0.0), indices }
}

/// The positions of [`swim_body`] at time `t` seconds.
pub fn swim_pose(rings: usize, segments: usize, t: f64) -> Vec<f32> {
    use std::f64::consts::PI;
    let (length, body_radius, wavelength, period) = (4.0f64, 0.45, 0.8, 1.0);
    let radius = |u: f64| body_radius * (PI * u).sin().max(0.0).sqrt() * (1.0 - 0.5 * u);
    let amplitude = |u: f64| 0.05 + 0.35 * u * u;
    let s = (t / 0.5).clamp(0.0, 1.0);
    let env = s * s * (3.0 - 2.0 * s);
    let centre = |u: f64| {
        let phase = 2.0 * PI * (u / wavelength - t / period);
        let w = env * amplitude(u) * phase.sin();
        let dw = env * (0.7 * u * phase.sin() + amplitude(u) * phase.cos() * 2.0 * PI / wavelength);
        let n = length.hypot(dw);
        (length * u, w, length / n, dw / n)
    };
    let ring_size = segments + 1;
    let mut xyz = vec![0.0f32; ((rings - 1) * ring_size + 2) * 3];
    for i in 1..rings - 1 {
        let u = i as f64 / rings as f64;
        let (x, w, tx, tz) = centre(u);
        let r = radius(u);
        for j in 0..=segments {
            let phi = 2.0 * PI * (j % segments) as f64 / segments as f64;
            let (side, up) = (r * phi.cos(), 0.8 * r * phi.sin());
            let v = ((i - 1) * ring_size + j) * 3;
            xyz[v] = (x - side * tz) as f32;
            xyz[v + 1] = up as f32;
            xyz[v + 2] = (w + side * tx) as f32;
        }
    }
    let poles = (rings - 1) * ring_size * 3;
    for end in 0..2 {
        let (x, w, _, _) = centre(end as f64);
        xyz[poles + 3 * end] = x as f32;
        xyz[poles + 3 * end + 2] = w as f32;
    }
    xyz
}
