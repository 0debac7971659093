//! How the coat is groomed: whether each feather runs the way its
//! neighbours run (discord), and where the orientation field has
//! singularities (whorls, partings, crowns, sources and sinks).

use crate::geometry::RootFrame;
use crate::ordering::KdTree;
use glam::Vec3;
use rayon::prelude::*;

/// Neighbours a feather's heading is compared with.
pub(crate) const DISCORD_NEIGHBOURS: usize = 8;

/// A feather is in discord when its heading turns more than this from the
/// mean heading of its neighbours, degrees.
pub(crate) const DISCORD_LIMIT_DEG: f64 = 45.0;

/// The groom figures of a set of feathers.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Groom {
    /// Percentage of the feathers in discord with their neighbours.
    pub discord_percent: f64,
    /// Mean angle between a feather's heading and its neighbours' mean, degrees.
    pub mean_deviation_deg: f64,
}

/// The groom figures of the feathers `member` accepts, each compared with
/// its [`DISCORD_NEIGHBOURS`] nearest feathers (any feather). A feather's
/// heading is its shaft direction in its root's tangent plane: the frame's
/// tangent, since pitch and bend turn the shaft about the binormal only.
/// The neighbours' headings are summed in the feather's tangent plane.
pub fn groom(frames: &[RootFrame], member: impl Fn(usize) -> bool + Sync) -> Groom {
    if frames.len() < 2 {
        return Groom::default();
    }
    let mut tree = KdTree::default();
    tree.rebuild(frames.iter().map(|f| f.position));
    let deviations: Vec<f64> = (0..frames.len())
        .into_par_iter()
        .filter(|&i| member(i))
        .map_init(Vec::new, |best, i| {
            let f = &frames[i];
            tree.nearest(f.position, DISCORD_NEIGHBOURS + 1, &|j| j as usize != i, best);
            let sum = best.iter().fold(Vec3::ZERO, |s, &(_, j)| s + frames[j as usize].tangent);
            let mean = sum - f.normal * sum.dot(f.normal);
            match mean.try_normalize() {
                Some(m) => f64::from(f.tangent.dot(m).clamp(-1.0, 1.0)).acos().to_degrees(),
                None => 90.0,
            }
        })
        .collect();
    if deviations.is_empty() {
        return Groom::default();
    }
    let n = deviations.len() as f64;
    Groom {
        discord_percent: 100.0 * deviations.iter().filter(|&&d| d > DISCORD_LIMIT_DEG).count() as f64 / n,
        mean_deviation_deg: deviations.iter().sum::<f64>() / n,
    }
}

/// The faces around which a per-vertex direction field turns: for each
/// triangle, the corners' directions projected into its plane, and the
/// signed angles from one corner's to the next summed round it, a whole
/// number of turns; the faces with a non-zero number, with it (+1 a
/// source, sink or vortex, −1 a saddle). Corners whose direction is normal
/// to the face are skipped (the face counts as regular).
pub fn field_singularities(positions: &[Vec3], triangles: &[[u32; 3]], directions: &[Vec3]) -> Vec<(u32, i32)> {
    triangles
        .iter()
        .enumerate()
        .filter_map(|(t, tri)| {
            let [a, b, c] = tri.map(|v| positions[v as usize]);
            let normal = (b - a).cross(c - a).try_normalize()?;
            let d = tri.map(|v| {
                let x = directions[v as usize];
                (x - normal * x.dot(normal)).try_normalize()
            });
            let [Some(d0), Some(d1), Some(d2)] = d else { return None };
            let turn = |u: Vec3, v: Vec3| u.cross(v).dot(normal).atan2(u.dot(v));
            let total = turn(d0, d1) + turn(d1, d2) + turn(d2, d0);
            let index = (total / std::f32::consts::TAU).round() as i32;
            (index != 0).then_some((t as u32, index))
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    fn frame(x: f32, y: f32, heading: Vec3) -> RootFrame {
        RootFrame::from_normal_and_direction(Vec3::new(x, y, 0.0), Vec3::Z, heading).unwrap()
    }

    #[test]
    fn a_combed_plate_has_no_discord_and_a_reversed_feather_has() {
        let mut frames: Vec<RootFrame> =
            (0..100).map(|k| frame((k % 10) as f32, (k / 10) as f32, Vec3::new(1.0, 0.1, 0.0))).collect();
        assert_eq!(groom(&frames, |_| true).discord_percent, 0.0);
        frames[55] = frame(5.0, 5.0, Vec3::NEG_X);
        let g = groom(&frames, |_| true);
        assert_eq!(g.discord_percent, 1.0, "only the reversed feather is off its neighbours");
        assert_eq!(groom(&frames, |i| i != 55).discord_percent, 0.0);
    }

    #[test]
    fn a_source_in_the_middle_of_a_fan_is_one_singular_face() {
        // A fan of triangles round a centre vertex, the field pointing away
        // from the centre (and at the centre, along +x).
        let mut positions = vec![Vec3::ZERO];
        let mut directions = vec![Vec3::X];
        let mut triangles = Vec::new();
        for k in 0..8 {
            let a = k as f32 * std::f32::consts::TAU / 8.0;
            positions.push(Vec3::new(a.cos(), a.sin(), 0.0));
            directions.push(Vec3::new(a.cos(), a.sin(), 0.0));
            triangles.push([0, 1 + k, 1 + (k + 1) % 8]);
        }
        let singular = field_singularities(&positions, &triangles, &directions);
        let total: i32 = singular.iter().map(|s| s.1).sum();
        assert_eq!(total, 1, "one source: {singular:?}");
        let combed = vec![Vec3::X; positions.len()];
        assert!(field_singularities(&positions, &triangles, &combed).is_empty());
    }
}
