use super::params::normals_agree;
use super::*;
use crate::error::{ErrorKind, Result};
use crate::snapshot::{Reader, Writer};
use glam::Vec3;

/// Roots on a wavy 12 × 12 patch, reach long enough for many obstacles.
fn patch() -> (Vec<RootFrame>, Vec<f32>) {
    let frames: Vec<RootFrame> = (0..144)
        .map(|k| {
            let (x, y) = ((k % 12) as f32, (k / 12) as f32);
            let p = Vec3::new(x + 0.3 * (y * 1.7).sin(), y, 0.2 * (x * 0.9).sin());
            RootFrame::from_normal_and_direction(p, Vec3::Z, Vec3::X).unwrap()
        })
        .collect();
    let reach = (0..144).map(|k| 1.0 + (k % 5) as f32 * 0.4).collect();
    (frames, reach)
}

fn blob_of(write: impl FnOnce(&mut Writer)) -> Vec<u8> {
    let mut w = Writer::new(1);
    write(&mut w);
    w.finish()
}

fn read(blob: &[u8], roots: usize) -> Result<Neighbourhoods> {
    let mut r = Reader::open(blob, 1)?;
    let s = Neighbourhoods::read_state(&mut r, roots)?;
    r.finish()?;
    Ok(s)
}

/// Roots of a jittered 48 × 24 strip folding about the line x = 24 by
/// `t` half-turns, the folded half landing a little above the other (a
/// wing coming against the flank) and stretched along y as it goes.
fn folding_strip(t: f32, rng: &mut crate::rng::Rng) -> Vec<RootFrame> {
    (0..48 * 24)
        .map(|k| {
            let (x, y) = ((k % 48) as f32 + 0.3 * rng.next_f32(), (k / 48) as f32 + 0.3 * rng.next_f32());
            let (p, n) = if x <= 24.0 {
                (Vec3::new(x, y, 0.0), Vec3::Z)
            } else {
                // Rolled about a hinge 0.6 above the plane.
                let a = std::f32::consts::PI * t;
                let (sin, cos) = a.sin_cos();
                let (u, v) = (x - 24.0, -0.6);
                let p = Vec3::new(24.0 + u * cos - v * sin, y * (1.0 + 0.1 * t), 0.6 + u * sin + v * cos);
                (p, Vec3::new(-sin, 0.0, cos))
            };
            RootFrame::from_normal_and_direction(p, n, Vec3::Y).unwrap()
        })
        .collect()
}

/// Every relation by exhaustive search, in the same `f32` operations.
fn exhaustive(frames: &[RootFrame], reach: &[f32], params: &NeighbourParams) -> (Vec<Vec<u32>>, Vec<Vec<u32>>) {
    let n = frames.len();
    let d2 = |i: usize, j: usize| (frames[j].position - frames[i].position).length_squared();
    let rows = (0..n)
        .map(|i| {
            (0..n as u32)
                .filter(|&j| {
                    let (j, limit) = (j as usize, sanitized_reach(reach[i]) + sanitized_reach(reach[j as usize]));
                    j != i && d2(i, j) <= limit * limit
                })
                .collect()
        })
        .collect();
    let knn = (0..n)
        .map(|i| {
            let mut all: Vec<(f32, u32)> = (0..n)
                .filter(|&j| j != i && normals_agree(&frames[i], &frames[j], params.min_normal_dot))
                .map(|j| (d2(i, j), j as u32))
                .collect();
            all.sort_by(|a, b| a.0.total_cmp(&b.0).then(a.1.cmp(&b.1)));
            all.iter().take(params.k).map(|e| e.1).collect()
        })
        .collect();
    (rows, knn)
}

#[test]
fn rows_and_nearest_match_the_exhaustive_search_on_a_fold_at_any_thread_count() {
    let params = NeighbourParams::default();
    let reach: Vec<f32> = (0..48 * 24).map(|k| if k % 97 == 5 { 0.0 } else { 1.2 + (k % 7) as f32 * 0.2 }).collect();
    let pools: Vec<rayon::ThreadPool> =
        [1, 2, 3].iter().map(|&t| rayon::ThreadPoolBuilder::new().num_threads(t).build().unwrap()).collect();
    // One `Neighbourhoods` through every pose and thread count: its leaf
    // layout is kept while the leaves stay compact, and then the roots
    // of reach 0 (whose k nearest the rows cannot settle) wait for a
    // tree over the current positions.
    let mut nb = Neighbourhoods::new();
    let mut fold_pairs = 0;
    let mut rebuilds = 0;
    for (step, t) in [0.0f32, 0.3, 0.6, 0.85, 0.97, 1.0].into_iter().enumerate() {
        let frames = folding_strip(t, &mut crate::rng::Rng::new(5));
        let (rows, knn) = exhaustive(&frames, &reach, &params);
        // Pairs across the hinge line that only the fold brings together.
        fold_pairs = (0..frames.len())
            .map(|i| rows[i].iter().filter(|&&j| (i % 48 < 12) && (j as usize % 48 > 36)).count())
            .sum::<usize>();
        let mut seen = Vec::new();
        for pool in &pools {
            pool.install(|| nb.rebuild(&frames, &reach, &params));
            rebuilds += 1;
            for i in 0..frames.len() {
                assert_eq!(nb.obstacle_candidates_of(i as u32), &rows[i][..], "row {i}, pose {step}");
                assert_eq!(nb.neighbours_of(i as u32), &knn[i][..], "nearest of {i}, pose {step}");
            }
            seen.push((nb.obstacle_csr().offsets().to_vec(), nb.obstacle_csr().items().to_vec(), nb.pairs().to_vec()));
        }
        assert!(seen.windows(2).all(|w| w[0] == w[1]), "pose {step} depends on the thread count");
    }
    assert!(fold_pairs > 100, "the folded pose must bring far roots together ({fold_pairs} pairs)");
    assert_eq!(nb.layout_generation, 1, "the fold keeps the leaves compact: one layout throughout");
    assert!(rebuilds > 2);
    // Stretched to 1.5 times its size, the strip's leaves spread out and
    // are laid out again; the rows still match.
    let stretched: Vec<RootFrame> = folding_strip(0.5, &mut crate::rng::Rng::new(5))
        .iter()
        .map(|f| RootFrame { position: f.position * 1.5, ..*f })
        .collect();
    let (rows, knn) = exhaustive(&stretched, &reach, &params);
    nb.rebuild(&stretched, &reach, &params);
    assert_eq!(nb.layout_generation, 2, "stretched leaves must be laid out again");
    for i in 0..stretched.len() {
        assert_eq!(nb.obstacle_candidates_of(i as u32), &rows[i][..], "row {i}, stretched");
        assert_eq!(nb.neighbours_of(i as u32), &knn[i][..], "nearest of {i}, stretched");
    }
}

#[test]
fn leaf_pairs_give_the_tree_queries_obstacles_bitwise() {
    let mut rng = crate::rng::Rng::new(11);
    let (patch_frames, patch_reach) = patch();
    let mut cases = vec![(patch_frames, patch_reach)];
    for (n, spread) in [(1usize, 1.0f32), (17, 0.5), (600, 6.0), (2000, 20.0)] {
        let frames: Vec<RootFrame> = (0..n)
            .map(|k| {
                // Some roots repeat a position exactly.
                let p = if k % 37 == 5 {
                    Vec3::ZERO
                } else {
                    Vec3::new(rng.next_f32(), rng.next_f32(), 0.3 * rng.next_f32()) * spread
                };
                RootFrame::from_normal_and_direction(p, Vec3::Z, Vec3::X).unwrap()
            })
            .collect();
        let reach = (0..n).map(|k| if k % 11 == 3 { 0.0 } else { 0.2 + rng.next_f32() }).collect();
        cases.push((frames, reach));
    }
    for (frames, reach) in cases {
        let mut nb = Neighbourhoods::new();
        nb.rebuild(&frames, &reach, &NeighbourParams::default());
        let mut by_tree = nb.clone();
        by_tree.obstacles_by_tree(&frames, &reach);
        assert_eq!(nb.obstacle_csr(), by_tree.obstacle_csr(), "{} roots", frames.len());
        // The k nearest from the rows are the tree's.
        let params = NeighbourParams::default();
        let mut best = Vec::new();
        for (i, frame) in frames.iter().enumerate() {
            let accept = |j: u32| j as usize != i && normals_agree(frame, &frames[j as usize], params.min_normal_dot);
            nb.tree.nearest(frame.position, params.k, &accept, &mut best);
            let ids: Vec<u32> = best.iter().map(|b| b.1).collect();
            assert_eq!(nb.neighbours_of(i as u32), &ids[..], "root {i} of {}", frames.len());
        }
        nb.rebuild(&frames, &[], &NeighbourParams::default());
        assert!(nb.obstacle_csr().is_empty() && nb.obstacle_csr().rows() == frames.len());
    }
}

#[test]
fn round_trip_restores_every_relation() {
    let (frames, reach) = patch();
    let mut nb = Neighbourhoods::new();
    nb.rebuild(&frames, &reach, &NeighbourParams::default());
    assert!(nb.obstacle_csr().len() > 10 * frames.len(), "the patch must have many obstacles");
    let blob = blob_of(|w| nb.write_state(w));
    let back = read(&blob, frames.len()).unwrap();
    assert_eq!(back.neighbours_csr(), nb.neighbours_csr());
    assert_eq!(back.obstacle_csr(), nb.obstacle_csr());
    assert_eq!(back.pairs(), nb.pairs());
    assert_eq!(blob_of(|w| back.write_state(w)), blob);
    assert_eq!(read(&blob, frames.len() + 1).unwrap_err().kind(), ErrorKind::InvalidState);
    let empty = blob_of(|w| Neighbourhoods::new().write_state(w));
    assert!(read(&empty, 0).unwrap().is_empty());
}

#[test]
fn hostile_rows_are_refused() {
    // Three roots; k-nearest rows, then the obstacle rows above the diagonal.
    let blob = |knn: (&[u32], &[u32]), obstacles: (&[u32], &[u32])| {
        blob_of(|w| {
            w.u32s(knn.0);
            w.u32s(knn.1);
            w.u32s(obstacles.0);
            w.u32s(obstacles.1);
        })
    };
    let good_knn: (&[u32], &[u32]) = (&[0, 1, 2, 3], &[1, 0, 1]);
    let good_obstacles: (&[u32], &[u32]) = (&[0, 2, 2, 2], &[1, 2]);
    let ok = read(&blob(good_knn, good_obstacles), 3).unwrap();
    assert_eq!(ok.obstacle_candidates_of(2), &[0]);
    assert_eq!(ok.pairs(), &[(0, 1), (1, 2)]);
    for (what, knn, obstacles) in [
        ("index out of range", (&[0u32, 1, 2, 3][..], &[1u32, 0, 7][..]), good_obstacles),
        ("own root", (&[0, 1, 2, 3], &[0, 0, 1]), good_obstacles),
        ("offsets decrease", (&[0, 2, 1, 3], &[1, 2, 1]), good_obstacles),
        ("offsets overrun", (&[0, 1, 2, 9], &[1, 0, 1]), good_obstacles),
        ("offsets not from 0", (&[1, 1, 2, 3], &[1, 0, 1]), good_obstacles),
        ("too few offsets", (&[0, 1, 3], &[1, 0, 1]), good_obstacles),
        ("obstacle below the diagonal", good_knn, (&[0, 0, 1, 1], &[0])),
        ("obstacle row unsorted", good_knn, (&[0, 2, 2, 2], &[2, 1])),
        ("obstacle row repeated", good_knn, (&[0, 2, 2, 2], &[1, 1])),
        ("obstacle out of range", good_knn, (&[0, 1, 1, 1], &[3])),
    ] {
        let err = read(&blob(knn, obstacles), 3).expect_err(what);
        assert_eq!(err.kind(), ErrorKind::InvalidState, "{what}");
    }
}

#[test]
fn rows_match_the_exhaustive_search_through_small_steps_a_rigid_turn_and_a_fold() {
    let params = NeighbourParams::default();
    let reach: Vec<f32> = (0..48 * 24).map(|k| if k % 97 == 5 { 0.0 } else { 1.2 + (k % 7) as f32 * 0.2 }).collect();
    let pools: Vec<rayon::ThreadPool> =
        [1, 2].iter().map(|&t| rayon::ThreadPoolBuilder::new().num_threads(t).build().unwrap()).collect();
    // One `Neighbourhoods` per thread count, each stepped through every
    // pose: small steps of the fold (the layout and each leaf's cached
    // candidates kept from frame to frame while they can be), the whole
    // strip turning and moving as it goes.
    let mut nbs = [Neighbourhoods::new(), Neighbourhoods::new()];
    for step in 0..=40 {
        let t = step as f32 / 40.0;
        let turn = glam::Quat::from_rotation_z(0.05 * step as f32) * glam::Quat::from_rotation_x(0.02 * step as f32);
        let shift = Vec3::new(0.3, -0.2, 0.1) * step as f32;
        let frames: Vec<RootFrame> = folding_strip(t, &mut crate::rng::Rng::new(5))
            .iter()
            .map(|f| {
                RootFrame::from_normal_and_direction(turn * f.position + shift, turn * f.normal, turn * f.tangent)
                    .unwrap()
            })
            .collect();
        let (rows, knn) = exhaustive(&frames, &reach, &params);
        for (nb, pool) in nbs.iter_mut().zip(&pools) {
            pool.install(|| nb.rebuild(&frames, &reach, &params));
            for i in 0..frames.len() {
                assert_eq!(nb.obstacle_candidates_of(i as u32), &rows[i][..], "row {i}, step {step}");
                assert_eq!(nb.neighbours_of(i as u32), &knn[i][..], "nearest of {i}, step {step}");
            }
        }
        assert_eq!(nbs[0].pairs(), nbs[1].pairs(), "step {step} depends on the thread count");
    }
    assert!(nbs[1].layout_generation > 1, "the steps must also lay the leaves out again");
    // One big jump back: the pairs follow.
    let folded = folding_strip(0.3, &mut crate::rng::Rng::new(5));
    let (rows, knn) = exhaustive(&folded, &reach, &params);
    let nb = &mut nbs[1];
    nb.rebuild(&folded, &reach, &params);
    let mut pairs: Vec<(u32, u32)> =
        (0..folded.len() as u32).flat_map(|i| knn[i as usize].iter().map(move |&j| (i.min(j), i.max(j)))).collect();
    pairs.sort_unstable();
    pairs.dedup();
    assert_eq!(nb.pairs(), &pairs[..]);
    for i in 0..folded.len() {
        assert_eq!(nb.obstacle_candidates_of(i as u32), &rows[i][..], "row {i}, jump");
        assert_eq!(nb.neighbours_of(i as u32), &knn[i][..], "nearest of {i}, jump");
    }
}
