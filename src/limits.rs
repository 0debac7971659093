//! The documented limits of a request. Beyond them a call is refused with
//! `ErrorKind::LimitExceeded` (C: `PLUMAGE_STATUS_LIMIT_EXCEEDED`) before
//! anything large is allocated, so that a request the machine cannot hold
//! ends in a clear status instead of an out-of-memory kill or hours of work.

/// Most feathers a system may be asked for, by `target_feathers` or by a
/// `spacing` whose estimated root count (the surface's area over the area
/// one root takes at that spacing) exceeds it. State and workspaces take a
/// few kilobytes a feather, so this is a few gigabytes at most.
pub const MAX_FEATHERS: usize = 2_000_000;

/// Largest coordinate magnitude accepted in a mesh or a frame, and largest
/// length accepted in the configuration (spacing, feather length, width and
/// thickness), in model units (a spacing of f32::MAX gave NaN feathers).
/// Squared cross products of triangle edges (normals, areas) are computed
/// in f32: with coordinates beyond about 1e10 they overflow and the surface
/// can no longer be used (a cylinder scaled by 1e11 gave one feather after
/// 10 s and 880 MB). Meshes so small that their
/// triangles' areas underflow (about 1e-10 model units across) are refused
/// as degenerate.
pub const MAX_COORDINATE: f32 = 1e9;

/// Positive per-vertex multipliers (a spacing map times the curvature
/// refinement; length and width maps) are clamped to within this factor of
/// their median either way: a density ratio of 400 at most from the
/// median. Far wider ratios made the sampler's rejection and coverage
/// queries run for minutes, and a huge length multiplier gave NaN
/// feathers. The sampler's cost grows steeply with the ratio where one
/// vertex's multiplier is far below its neighbours' (its faces draw pool
/// points from their densest corner and reject the rest); at 20 the worst
/// case `fuzz_create` found takes under a second (BENCHMARKS.md,
/// "Measurements behind the code's constants"). 20 either way still spans
/// a density ratio of 160 000 between the sparsest and densest skin.
pub const MAX_MULTIPLIER_RATIO: f32 = 20.0;
