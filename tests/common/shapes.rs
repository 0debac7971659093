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
