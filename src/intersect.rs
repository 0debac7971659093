//! Exact triangle–triangle intersection in f64, with a stated meaning for
//! contact.
//!
//! Meaning. Two triangles intersect when their relative interiors meet:
//! they cross (the segment where each meets the other's plane overlaps the
//! other's by a positive length), or they are coplanar and overlap with a
//! positive area. Contact that no plane can separate only weakly is not an
//! intersection: touching at a vertex, along an edge, a vertex resting on a
//! face, coplanar triangles sharing an edge. Distances and overlaps within
//! `1e-6` of the pair's bounding-box diagonal count as zero, i.e. as touching.
//!
//! Why. Feathers rest on each other; a resting contact is not a collision,
//! and f32 input cannot resolve a separation below about 1e-7 of the model
//! size anyway, so a stricter test would only report rounding. The adjuster
//! keeps a clearance of a tenth of a thickness, far above the tolerance, so
//! feathers it places never come near the boundary case.

use glam::{DVec2, DVec3, Vec3};

/// Distances below this fraction of the pair's bounding-box diagonal are
/// treated as zero (contact).
pub(crate) const CONTACT_TOLERANCE: f64 = 1e-6;

/// Whether two triangles intersect (see the module notes: crossing or
/// coplanar overlap with positive area; mere contact does not count).
pub fn triangles_intersect(a: &[Vec3; 3], b: &[Vec3; 3]) -> bool {
    triangles_intersect_f64(&a.map(|p| p.as_dvec3()), &b.map(|p| p.as_dvec3()))
}

/// [`triangles_intersect`] on f64 corners.
pub fn triangles_intersect_f64(a: &[DVec3; 3], b: &[DVec3; 3]) -> bool {
    prepared_intersect(&Prepared::new(*a), &Prepared::new(*b))
}

/// What the test needs of one triangle whatever the other: its corners,
/// bounds and unnormalised normal. Preparing a triangle once for many
/// tests gives the same answers as [`triangles_intersect`] (the same f64
/// operations in the same order).
#[derive(Clone, Copy, Debug)]
pub(crate) struct Prepared {
    t: [DVec3; 3],
    /// Running min and max from ±∞ over the corners (the joint bounds
    /// continue from these), and the corners' own bounds.
    from_inf: (DVec3, DVec3),
    bounds: (DVec3, DVec3),
    normal: DVec3,
    normal_len: f64,
    longest: f64,
}

impl Prepared {
    pub(crate) fn new(t: [DVec3; 3]) -> Self {
        let lo = t.iter().fold(DVec3::splat(f64::INFINITY), |m, p| m.min(*p));
        let hi = t.iter().fold(DVec3::splat(f64::NEG_INFINITY), |m, p| m.max(*p));
        let normal = (t[1] - t[0]).cross(t[2] - t[0]);
        let longest = (t[1] - t[0]).length().max((t[2] - t[1]).length()).max((t[0] - t[2]).length());
        Self {
            t,
            from_inf: (lo, hi),
            bounds: (t[0].min(t[1]).min(t[2]), t[0].max(t[1]).max(t[2])),
            normal,
            normal_len: normal.length(),
            longest,
        }
    }

    /// From f32 corners.
    pub(crate) fn of(t: &[Vec3; 3]) -> Self {
        Self::new(t.map(|p| p.as_dvec3()))
    }

    /// The unit normal, or `None` when the triangle's height over its
    /// longest edge is within the tolerance (no area to speak of).
    fn unit_normal(&self, eps: f64) -> Option<DVec3> {
        // |n| = longest · height.
        (self.normal_len > eps * self.longest && self.longest > 0.0).then(|| self.normal / self.normal_len)
    }
}

/// [`triangles_intersect`] on prepared triangles.
pub(crate) fn prepared_intersect(pa: &Prepared, pb: &Prepared) -> bool {
    let (a, b) = (&pa.t, &pb.t);
    let lo = b.iter().fold(pa.from_inf.0, |m, p| m.min(*p));
    let hi = b.iter().fold(pa.from_inf.1, |m, p| m.max(*p));
    let diag = (hi - lo).length();
    if diag <= 0.0 || !diag.is_finite() {
        return false;
    }
    let eps = CONTACT_TOLERANCE * diag;
    // Quick reject on separated bounding boxes.
    let (alo, ahi) = pa.bounds;
    let (blo, bhi) = pb.bounds;
    if (alo - bhi).max_element() > eps || (blo - ahi).max_element() > eps {
        return false;
    }
    match (pa.unit_normal(eps), pb.unit_normal(eps)) {
        (Some(na), Some(nb)) => crossing_or_overlap(a, na, b, nb, eps),
        (None, Some(nb)) => segment_pierces(longest_edge(a), b, nb, eps),
        (Some(na), None) => segment_pierces(longest_edge(b), a, na, eps),
        (None, None) => false,
    }
}

fn longest_edge(t: &[DVec3; 3]) -> [DVec3; 2] {
    let edges = [[t[0], t[1]], [t[1], t[2]], [t[2], t[0]]];
    edges
        .into_iter()
        .max_by(|x, y| (x[1] - x[0]).length_squared().total_cmp(&(y[1] - y[0]).length_squared()))
        .unwrap_or(edges[0])
}

/// Signed distances of `t`'s corners from the plane (`n`, through `p`),
/// snapped to zero within `eps`.
fn plane_distances(t: &[DVec3; 3], n: DVec3, p: DVec3, eps: f64) -> [f64; 3] {
    t.map(|v| {
        let d = n.dot(v - p);
        if d.abs() <= eps { 0.0 } else { d }
    })
}

fn straddles(d: &[f64; 3]) -> bool {
    d.iter().any(|&x| x > 0.0) && d.iter().any(|&x| x < 0.0)
}

fn crossing_or_overlap(a: &[DVec3; 3], na: DVec3, b: &[DVec3; 3], nb: DVec3, eps: f64) -> bool {
    let db = plane_distances(b, na, a[0], eps);
    let da = plane_distances(a, nb, b[0], eps);
    if db.iter().all(|&d| d == 0.0) || da.iter().all(|&d| d == 0.0) {
        return coplanar_overlap(a, b, na, eps);
    }
    // A triangle on one closed side of the other's plane can only touch it.
    if !straddles(&db) || !straddles(&da) {
        return false;
    }
    let dir = na.cross(nb);
    let len = dir.length();
    if len <= 0.0 || len.is_nan() {
        return false;
    }
    let dir = dir / len;
    let (a0, a1) = plane_crossing_interval(a, &da, dir);
    let (b0, b1) = plane_crossing_interval(b, &db, dir);
    a1.min(b1) - a0.max(b0) > eps
}

/// The interval, along `dir`, of the segment where the triangle meets the
/// plane its signed distances `d` refer to.
fn plane_crossing_interval(t: &[DVec3; 3], d: &[f64; 3], dir: DVec3) -> (f64, f64) {
    let (mut lo, mut hi) = (f64::INFINITY, f64::NEG_INFINITY);
    let mut take = |p: DVec3| {
        let s = p.dot(dir);
        lo = lo.min(s);
        hi = hi.max(s);
    };
    for k in 0..3 {
        let (i, j) = (k, (k + 1) % 3);
        if d[i] == 0.0 {
            take(t[i]);
        }
        if (d[i] < 0.0 && d[j] > 0.0) || (d[i] > 0.0 && d[j] < 0.0) {
            take(t[i] + (t[j] - t[i]) * (d[i] / (d[i] - d[j])));
        }
    }
    (lo, hi)
}

/// Coplanar triangles overlap with positive area iff no edge normal (in
/// the plane) separates or merely touches their projections.
fn coplanar_overlap(a: &[DVec3; 3], b: &[DVec3; 3], n: DVec3, eps: f64) -> bool {
    let (u, v) = plane_basis(n);
    let pa = a.map(|p| DVec2::new(p.dot(u), p.dot(v)));
    let pb = b.map(|p| DVec2::new(p.dot(u), p.dot(v)));
    for tri in [&pa, &pb] {
        for k in 0..3 {
            let e = tri[(k + 1) % 3] - tri[k];
            let len = e.length();
            if len <= 0.0 || len.is_nan() {
                continue;
            }
            let axis = e.perp() / len;
            let (a0, a1) = project(&pa, axis);
            let (b0, b1) = project(&pb, axis);
            if a1.min(b1) - a0.max(b0) <= eps {
                return false;
            }
        }
    }
    true
}

fn project(t: &[DVec2; 3], axis: DVec2) -> (f64, f64) {
    let s = t.map(|p| p.dot(axis));
    (s[0].min(s[1]).min(s[2]), s[0].max(s[1]).max(s[2]))
}

fn plane_basis(n: DVec3) -> (DVec3, DVec3) {
    let helper = if n.x.abs() < 0.6 { DVec3::X } else { DVec3::Y };
    let u = n.cross(helper).normalize();
    (u, n.cross(u))
}

/// A segment (a triangle without area) pierces a triangle when its ends
/// lie strictly on both sides of the plane and the crossing point is
/// strictly inside.
fn segment_pierces(seg: [DVec3; 2], t: &[DVec3; 3], n: DVec3, eps: f64) -> bool {
    let d = seg.map(|p| n.dot(p - t[0]));
    if !((d[0] > eps && d[1] < -eps) || (d[0] < -eps && d[1] > eps)) {
        return false;
    }
    let x = seg[0] + (seg[1] - seg[0]) * (d[0] / (d[0] - d[1]));
    (0..3).all(|k| {
        let (p, q) = (t[k], t[(k + 1) % 3]);
        let e = q - p;
        let len = e.length();
        len > 0.0 && n.cross(e).dot(x - p) / len > eps
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    fn t(p: [[f32; 3]; 3]) -> [Vec3; 3] {
        p.map(Vec3::from_array)
    }

    #[test]
    fn plane_distance_snapping_treats_resting_vertices_as_contact() {
        let a = t([[0., 0., 0.], [2., 0., 0.], [0., 2., 0.]]);
        // A tetrahedron face whose lowest vertex rests on a's interior.
        let b = t([[0.5, 0.5, 0.0], [1.0, 0.5, 1.0], [0.5, 1.0, 1.0]]);
        assert!(!triangles_intersect(&a, &b));
        let below = t([[0.5, 0.5, -1e-3], [1.0, 0.5, 1.0], [0.5, 1.0, 1.0]]);
        assert!(triangles_intersect(&a, &below));
    }

    #[test]
    fn a_degenerate_triangle_acts_as_its_segment() {
        let a = t([[0., 0., 0.], [2., 0., 0.], [0., 2., 0.]]);
        let needle = t([[0.5, 0.5, -1.0], [0.5, 0.5, 1.0], [0.5, 0.5, 0.0]]);
        assert!(triangles_intersect(&a, &needle));
        let beside = t([[3.5, 0.5, -1.0], [3.5, 0.5, 1.0], [3.5, 0.5, 0.0]]);
        assert!(!triangles_intersect(&a, &beside));
    }
}
