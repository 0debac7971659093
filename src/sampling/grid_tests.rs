//! Unit tests of `grid.rs`.

use super::*;
use crate::rng::Rng;

#[test]
fn static_grid_finds_exactly_the_points_in_range() {
    let mut rng = Rng::new(5);
    let pts: Vec<Vec3> =
        (0..500).map(|_| Vec3::new(rng.next_f32(), rng.next_f32(), rng.next_f32()) * 4.0 - 2.0).collect();
    let grid = StaticGrid::new(&pts, 0.3);
    let c = Vec3::new(0.1, -0.2, 0.3);
    let mut found = Vec::new();
    grid.for_each_within(c, 0.7, |i, _| found.push(i));
    found.sort_unstable();
    let expected: Vec<u32> = (0..500).filter(|&i| (pts[i as usize] - c).length() <= 0.7).collect();
    assert_eq!(found, expected);
}

#[test]
fn floor_to_i32_is_floor_then_cast() {
    let mut rng = Rng::new(3);
    let special = [
        0.0,
        -0.0,
        0.5,
        -0.5,
        -1.0,
        1.0,
        -1e-30,
        2147483520.0,
        2147483648.0,
        -2147483648.0,
        -2147483904.0,
        1e20,
        -1e20,
        f32::INFINITY,
        f32::NEG_INFINITY,
        f32::NAN,
        f32::MIN_POSITIVE,
    ];
    let random = (0..10_000).map(|_| (rng.next_f32() - 0.5) * 10f32.powi((rng.next_f32() * 12.0) as i32 - 3));
    for v in special.into_iter().chain(random) {
        assert_eq!(floor_to_i32(v), v.floor() as i32, "{v}");
    }
}

/// The radix sort is the stable sort: equal keys keep index order, at
/// any key width.
#[test]
fn radix_order_is_the_stable_sort() {
    let mut rng = Rng::new(11);
    for bits in [1u32, 7, 20, 33, 63, 64] {
        let keys: Vec<u64> = (0..3000)
            .map(|_| {
                let k = rng.next_u64() >> (64 - bits);
                if rng.next_f32() < 0.3 { k & !0xFF } else { k }
            })
            .collect();
        let mut expected: Vec<u32> = (0..keys.len() as u32).collect();
        expected.sort_by_key(|&i| keys[i as usize]);
        assert_eq!(stable_order_by_key(&keys), expected, "{bits} bits");
    }
    assert!(stable_order_by_key(&[]).is_empty());
}

/// Points spread far apart against the cell: too many columns for the
/// dense table, so columns are hashed. Either way a query finds exactly
/// the points in range, in slot order: by cell in (x, y, z) order, then
/// by index.
#[test]
fn dense_and_hashed_columns_find_the_points_in_slot_order() {
    let mut rng = Rng::new(7);
    let mut pts: Vec<Vec3> =
        (0..400).map(|_| Vec3::new(rng.next_f32(), rng.next_f32(), rng.next_f32()) * 1000.0).collect();
    // A dense clump, so that some queries meet many points.
    pts.extend((0..200).map(|_| Vec3::new(rng.next_f32(), rng.next_f32(), rng.next_f32()) * 3.0 + 500.0));
    let hashed = StaticGrid::new(&pts, 0.5);
    assert!(matches!(hashed.columns, ColumnIndex::Hashed(_)));
    let dense = StaticGrid::new(&pts[400..], 0.5);
    assert!(matches!(dense.columns, ColumnIndex::Dense { .. }));
    for (grid, pts) in [(&hashed, &pts[..]), (&dense, &pts[400..])] {
        for c in [Vec3::splat(501.5), Vec3::new(500.2, 502.9, 501.0), pts[3], pts[150]] {
            for r in [0.3, 1.1, 2.5] {
                let mut found = Vec::new();
                grid.for_each_within(c, r, |i, _| found.push(i));
                let mut expected: Vec<u32> =
                    (0..pts.len() as u32).filter(|&i| (pts[i as usize] - c).length() <= r).collect();
                expected.sort_by_key(|&i| (cell_of(pts[i as usize] - grid.origin, grid.inv_cell), i));
                assert_eq!(found, expected, "centre {c}, radius {r}");
            }
        }
    }
}

/// Non-finite positions (which a caller should never pass) leave the
/// grid usable: their cells fall outside the packed range, so columns
/// are hashed and scanned whole, and queries still find exactly the
/// finite points in range.
#[test]
fn non_finite_positions_do_not_break_queries() {
    let mut rng = Rng::new(13);
    let mut pts: Vec<Vec3> =
        (0..300).map(|_| Vec3::new(rng.next_f32(), rng.next_f32(), rng.next_f32()) * 4.0 - 2.0).collect();
    pts.push(Vec3::new(f32::NAN, 0.0, 0.0));
    pts.push(Vec3::new(0.5, f32::NEG_INFINITY, 0.5));
    let grid = StaticGrid::new(&pts, 0.3);
    assert!(!grid.z_sorted);
    for c in [Vec3::new(0.1, -0.2, 0.3), Vec3::splat(1.5), Vec3::splat(-1.9)] {
        let mut found = Vec::new();
        grid.for_each_within(c, 0.7, |i, _| found.push(i));
        found.sort_unstable();
        let expected: Vec<u32> = (0..pts.len() as u32).filter(|&i| (pts[i as usize] - c).length() <= 0.7).collect();
        assert_eq!(found, expected, "centre {c}");
    }
}

/// A radius far beyond the cell size (or infinite) scans instead of
/// walking cells, and gives the same calls in the same order as the walk.
#[test]
fn huge_radii_scan_in_the_walk_order() {
    let mut rng = Rng::new(9);
    let pts: Vec<Vec3> =
        (0..300).map(|_| Vec3::new(rng.next_f32(), rng.next_f32(), rng.next_f32()) * 4.0 - 2.0).collect();
    let grid = StaticGrid::new(&pts, 0.5);
    let mut dynamic = DynamicGrid::new(0.5);
    pts.iter().enumerate().for_each(|(i, &p)| dynamic.insert(i as u32, p));
    let c = Vec3::new(0.1, -0.2, 0.3);
    // Both paths at a radius where the walk is still cheap.
    let r = 1.3;
    assert!(box_cell_count(c - grid.origin, r, grid.inv_cell) <= pts.len() as f64);
    let mut walked = Vec::new();
    grid.for_each_within(c, r, |i, d2| walked.push((i, d2)));
    let mut scanned = Vec::new();
    let r2 = r * r;
    for (slot, p) in grid.positions.iter().enumerate() {
        let d2 = (*p - c).length_squared();
        if d2 <= r2 {
            scanned.push((grid.order[slot], d2));
        }
    }
    assert_eq!(walked, scanned);
    let mut walked = Vec::new();
    for_each_cell(c, r, dynamic.inv_cell, |cell| {
        if let Some(list) = dynamic.cells.get(&cell) {
            walked.extend_from_slice(list);
        }
    });
    let mut cells: Vec<Cell> = dynamic.cells.keys().copied().collect();
    cells.sort_unstable();
    let visited: Vec<u32> = cells
        .into_iter()
        .filter(|&cell| ball_meets_cell(c, r, dynamic.inv_cell, cell))
        .flat_map(|cell| dynamic.cells[&cell].clone())
        .collect();
    assert_eq!(walked, visited);
    // Huge and infinite radii return at once with every point.
    for r in [1e30, f32::INFINITY] {
        let mut n = 0;
        grid.for_each_within(c, r, |_, _| n += 1);
        assert_eq!(n, pts.len());
        let mut n = 0;
        dynamic.for_each_candidate(c, r, |_| n += 1);
        assert_eq!(n, pts.len());
    }
}
