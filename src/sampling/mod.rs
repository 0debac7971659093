//! Planting the feather roots (DESIGN.md §2): the orientation-field-guided
//! sampler of the paper (Algorithm 1) and the 2015 random baseline, chosen by
//! `config.sampler`, both Poisson-disk samplers over a shared random pool.
//!
//! The global spacing `d` is `config.spacing` when set; otherwise it is
//! searched for so that the root count meets `config.target_feathers`
//! (2000 when that is 0 too): roots ∝ 1/d², so a few sampling passes with a
//! secant step on `log n` against `log d` land within a few percent. The
//! first guess is fitted to the shared models and lands within the
//! tolerance in most cases, so most searches run one pass.
//!
//! The pool holds `config.pool_factor` × the expected root count, taken as
//! `∫ dA / d(p)²` (one root per `d²`; the guided sampler's lattice packs
//! about 0.6–0.75 and dart throwing about 0.65 roots per `d²`).
//!
//! Same mesh, fields, config and seed give the same roots bit for bit at any
//! thread count: the pool is drawn in blocks with one random stream each,
//! the samplers themselves are sequential, and no hash-map order reaches
//! the output.

mod disk;
mod grid;
mod guided;
pub mod metrics;
mod pool;
mod random;

pub use metrics::{PlantedFor, SamplingMetrics, sampling_metrics};

use crate::config::{Config, SamplerKind};
use crate::error::{Error, ErrorKind, Result};
use crate::field::Fields;
use crate::interior::BuriedSkin;
use crate::mesh::WeldedMesh;
use crate::progress::{Phase, Progress};
use crate::rng::Rng;
use crate::roots::{RootBinding, edge_basis_coordinates, root_id};
use crate::surface::Surface;
use disk::DiskSampler;
use glam::Vec3;
use pool::{DensityField, MAX_POOL, SortedPool};
use std::time::Instant;

/// Root count aimed at when neither a spacing nor a target is given.
pub(crate) const DEFAULT_TARGET_FEATHERS: usize = 2000;

/// Roots per `d²` of (density-weighted) area the guided sampler's lattice
/// would pack with no gaps: the nominal feather length (`field.rs`) and the
/// refusal of a `config.spacing` that plants too many roots use them.
pub(crate) const GUIDED_PACKING: f64 = 0.75;
const RANDOM_PACKING: f64 = 0.67;

/// The spacing search's first guess: roots per `d²` of effective area each
/// sampler plants on a large count (`n → ∞`), and `EDGE_LOSS`: at `n` roots
/// a share `EDGE_LOSS/√n` of that is lost along the feathered region's
/// edges. Fitted to the first passes of the shared models at 2 000 and
/// 10 000 roots (BENCHMARKS.md, "Issue #20, second round"): the guided
/// sampler's counts per model lie within
/// about ±4 % of this, the random sampler's within about ±5 %, so most
/// requests need one pass.
const GUIDED_FIRST_GUESS: f64 = 0.696;
const RANDOM_FIRST_GUESS: f64 = 0.636;
const EDGE_LOSS: f64 = 3.1;

/// Spacing search: at most this many sampling passes, stopping early once
/// the count is within this relative error of the target.
const SEARCH_PASSES: usize = 6;
const SEARCH_TOLERANCE: f64 = 0.04;

/// Smallest pool drawn.
const MIN_POOL: usize = 16;

/// Stream tag of the samplers' random choices.
const SAMPLER_STREAM: u64 = 0x7361_6D70;

/// The planted roots and how they were obtained.
#[derive(Clone, Debug)]
pub struct Sampling {
    /// The roots, in the order they were placed.
    pub roots: Vec<RootBinding>,
    /// The global spacing `d` used (local `d_i = d × spacing_scale`).
    pub spacing: f32,
    /// Quality figures of the result.
    pub metrics: SamplingMetrics,
    /// Wall time of the sampling itself (every pass of a spacing search;
    /// not the metrics).
    pub seconds: f64,
    /// Sampling passes run: 1 with a given spacing, 1 to 6 in a search.
    pub passes: u32,
    /// Roots the first pass planted (the search's first guess).
    pub first_pass_roots: usize,
}

/// Plants roots on the welded rest mesh with the sampler, spacing or target
/// count, and seed of `config` (see the module notes).
pub fn sample_roots(mesh: &WeldedMesh, surface: &Surface, fields: &Fields, config: &Config) -> Result<Sampling> {
    sample_roots_with_progress(mesh, surface, fields, config, &Progress::none())
}

/// As [`sample_roots`], checking in with `progress` every few dozen
/// samples; fails with `Interrupted` when it says stop.
pub fn sample_roots_with_progress(
    mesh: &WeldedMesh,
    surface: &Surface,
    fields: &Fields,
    config: &Config,
    progress: &Progress,
) -> Result<Sampling> {
    let planted = plant_roots_with_progress(mesh, surface, fields, config, progress)?;
    let metrics = planted.metrics(surface, &mesh.positions, fields, &planted.roots, config.theta, progress)?;
    let Planted { roots, spacing, seconds, passes, first_pass_roots, .. } = planted;
    Ok(Sampling { roots, spacing, metrics, seconds, passes, first_pass_roots })
}

/// The roots planted, before their quality figures: what
/// [`sample_roots_with_progress`] returns without its metrics, and what the
/// metrics read besides the roots, so that a caller can measure them later
/// or beside other work ([`Planted::metrics`]).
pub struct Planted {
    /// The roots, in the order they were placed.
    pub roots: Vec<RootBinding>,
    /// The global spacing `d` used (local `d_i = d × spacing_scale`).
    pub spacing: f32,
    /// Wall time of the sampling (every pass of a spacing search).
    pub seconds: f64,
    /// Sampling passes run: 1 with a given spacing, 1 to 6 in a search.
    pub passes: u32,
    /// Roots the first pass planted (the search's first guess).
    pub first_pass_roots: usize,
    buried: BuriedSkin,
}

impl Planted {
    /// The quality figures of `roots` (these roots, wherever they are now
    /// kept) on the surface, rest positions and fields they were planted
    /// on, with stagger angle `theta`: the `metrics` of [`Sampling`].
    pub fn metrics(
        &self,
        surface: &Surface,
        positions: &[Vec3],
        fields: &Fields,
        roots: &[RootBinding],
        theta: f32,
        progress: &Progress,
    ) -> Result<SamplingMetrics> {
        let planted_for = PlantedFor { spacing: self.spacing, theta };
        let metrics = sampling_metrics(surface, positions, fields, &self.buried, roots, planted_for, progress);
        progress.check(Phase::Sampling, 1.0)?;
        // Probes judged after the burial budget ran out were taken as visible.
        self.buried.within_budget()?;
        Ok(metrics)
    }
}

/// As [`sample_roots_with_progress`] without the metrics (see [`Planted`]).
pub fn plant_roots_with_progress(
    mesh: &WeldedMesh,
    surface: &Surface,
    fields: &Fields,
    config: &Config,
    progress: &Progress,
) -> Result<Planted> {
    config.validate()?;
    if surface.face_count() != mesh.triangles.len()
        || surface.vertex_count() != mesh.positions.len()
        || fields.vertex_spacing_scales().len() != mesh.positions.len()
    {
        return Err(Error::new(ErrorKind::InvalidArgument, "surface and fields must be built from this welded mesh"));
    }
    let start = Instant::now();
    let positions = &mesh.positions;
    let mut normals = Vec::new();
    surface.vertex_normals(positions, &mut normals);
    let buried = BuriedSkin::new(positions, &mesh.triangles, roots_aimed(surface, config))?;
    progress.check(Phase::Sampling, 0.0)?;
    let density = DensityField::new(surface, fields, positions, &normals, &buried);
    let target = target_feathers(config);
    check_spacing_estimate(density.effective_area(), config)?;
    let mut passes = Passes::default();
    let (spacing, pool, samples) = if density.effective_area().is_nan() || density.effective_area() <= 0.0 {
        let nominal = (surface.rest_area().max(f64::MIN_POSITIVE) / target as f64).sqrt() as f32;
        (if config.spacing > 0.0 { config.spacing } else { nominal }, None, Vec::new())
    } else if config.spacing > 0.0 {
        let (pool, samples) = sampling_pass(&density, surface, positions, fields, config, config.spacing, progress);
        passes.record(samples.len());
        (config.spacing, Some(pool), samples)
    } else {
        search_spacing(&density, surface, positions, fields, config, target, progress, &mut passes)
    };
    // A pass cut short by the progress has set its stop flag.
    progress.check(Phase::Sampling, 0.9)?;
    buried.within_budget()?;
    let roots = match &pool {
        Some(pool) => bind_roots(surface, positions, fields, pool, &samples, config.seed),
        None => Vec::new(),
    };
    drop(density);
    let seconds = start.elapsed().as_secs_f64();
    progress.check(Phase::Sampling, 0.95)?;
    Ok(Planted { roots, spacing, seconds, passes: passes.count, first_pass_roots: passes.first_roots, buried })
}

/// How many sampling passes ran, and the first one's root count.
#[derive(Default)]
struct Passes {
    count: u32,
    first_roots: usize,
}

impl Passes {
    fn record(&mut self, roots: usize) {
        if self.count == 0 {
            self.first_roots = roots;
        }
        self.count += 1;
    }
}

/// Refuses a `config.spacing` whose estimated root count over
/// `effective_area` exceeds [`MAX_FEATHERS`](crate::limits::MAX_FEATHERS),
/// before any pool is drawn.
fn check_spacing_estimate(effective_area: f64, config: &Config) -> Result<()> {
    if config.spacing <= 0.0 || effective_area.is_nan() || effective_area <= 0.0 {
        return Ok(());
    }
    let packing = match config.sampler {
        SamplerKind::Guided => GUIDED_PACKING,
        SamplerKind::Random => RANDOM_PACKING,
    };
    let d = f64::from(config.spacing);
    let estimate = effective_area / (packing * d * d);
    if estimate > crate::limits::MAX_FEATHERS as f64 {
        return Err(Error::new(
            ErrorKind::LimitExceeded,
            format!(
                "config.spacing {} would plant about {estimate:.3e} feathers on this surface, more than the supported {}",
                config.spacing,
                crate::limits::MAX_FEATHERS
            ),
        ));
    }
    Ok(())
}

/// About how many roots `config` asks for: with a spacing, the rest area
/// over the area a root takes (at most the feather limit), else the target
/// count. Sizes the burial budget before the density (which needs the
/// burial) exists.
fn roots_aimed(surface: &Surface, config: &Config) -> usize {
    if config.spacing <= 0.0 {
        return target_feathers(config);
    }
    let packing = match config.sampler {
        SamplerKind::Guided => GUIDED_PACKING,
        SamplerKind::Random => RANDOM_PACKING,
    };
    let d = f64::from(config.spacing);
    let estimate = surface.rest_area() / (packing * d * d);
    if estimate.is_finite() { estimate.clamp(1.0, crate::limits::MAX_FEATHERS as f64) as usize } else { 1 }
}

/// The feather count aimed at: `config.target_feathers`, or the default
/// when that is 0.
pub(crate) fn target_feathers(config: &Config) -> usize {
    if config.target_feathers > 0 { config.target_feathers } else { DEFAULT_TARGET_FEATHERS }
}

/// One run of the configured sampler at global spacing `d`: the pool and
/// the pool indices that became roots.
fn sampling_pass(
    density: &DensityField<'_>,
    surface: &Surface,
    positions: &[Vec3],
    fields: &Fields,
    config: &Config,
    d: f32,
    progress: &Progress,
) -> (SortedPool, Vec<u32>) {
    let expected = density.effective_area() / (d as f64 * d as f64);
    // Pool size = pool_factor × expected root count.
    let size = (config.pool_factor as f64 * expected).ceil();
    let size = if size.is_finite() { (size as usize).clamp(MIN_POOL, MAX_POOL) } else { MAX_POOL };
    let keep_going = || progress.check(Phase::Sampling, 0.5).is_ok();
    let drawn = density.draw_pool(d, size, config.seed, &keep_going);
    // Cells of about d: a query of radius 2d then reads little beyond the ball.
    let cell = d * fields.median_spacing_scale();
    let pool = SortedPool::new(drawn, cell);
    let mut disk = DiskSampler::new(surface, positions, &pool, cell).with_keep_going(&keep_going);
    let mut rng = Rng::for_stream(config.seed, SAMPLER_STREAM);
    match config.sampler {
        SamplerKind::Guided => guided::sample_guided(&mut disk, fields, config.theta, config.randomness, &mut rng),
        SamplerKind::Random => random::sample_random(&mut disk, &pool.slots_in_draw_order()),
    }
    let samples = disk.into_samples();
    (pool, samples)
}

/// Finds the spacing whose root count is nearest `target` (secant steps on
/// `log n` against `log d`, slope −2 to start) and returns that pass.
#[allow(clippy::too_many_arguments)]
fn search_spacing(
    density: &DensityField<'_>,
    surface: &Surface,
    positions: &[Vec3],
    fields: &Fields,
    config: &Config,
    target: usize,
    progress: &Progress,
    passes: &mut Passes,
) -> (f32, Option<SortedPool>, Vec<u32>) {
    let mut d = first_guess(density.effective_area(), config.sampler, target);
    let mut best: Option<(f64, f32, SortedPool, Vec<u32>)> = None;
    let mut previous: Option<(f64, f64)> = None;
    for _ in 0..SEARCH_PASSES {
        let (pool, samples) = sampling_pass(density, surface, positions, fields, config, d, progress);
        if progress.check(Phase::Sampling, 0.5).is_err() {
            return (d, Some(pool), samples);
        }
        let n = samples.len();
        passes.record(n);
        let error = (n as f64 / target as f64 - 1.0).abs();
        let done = error <= SEARCH_TOLERANCE;
        let next = next_spacing(d, n, target, &mut previous);
        if best.as_ref().is_none_or(|b| error < b.0) {
            best = Some((error, d, pool, samples));
        }
        if done {
            break;
        }
        d = next;
    }
    let (_, d, pool, samples) = best.expect("at least one pass ran");
    (d, Some(pool), samples)
}

/// The spacing expected to plant `target` roots over `effective_area` (see
/// [`GUIDED_FIRST_GUESS`]).
fn first_guess(effective_area: f64, sampler: SamplerKind, target: usize) -> f32 {
    let packing = match sampler {
        SamplerKind::Guided => GUIDED_FIRST_GUESS,
        SamplerKind::Random => RANDOM_FIRST_GUESS,
    };
    let kept = (1.0 - EDGE_LOSS / (target.max(1) as f64).sqrt()).max(0.25);
    (effective_area * packing * kept / target.max(1) as f64).sqrt() as f32
}

/// The secant step of the spacing search; `previous` holds the last
/// (log d, log n) pair and is updated.
fn next_spacing(d: f32, n: usize, target: usize, previous: &mut Option<(f64, f64)>) -> f32 {
    if n == 0 {
        return d * 0.5;
    }
    let (ld, ln) = ((d as f64).ln(), (n as f64).ln());
    let slope = match *previous {
        Some((pd, pn)) if (ld - pd).abs() > 1e-9 && (ln - pn).abs() > 1e-9 => ((ln - pn) / (ld - pd)).clamp(-4.0, -1.0),
        _ => -2.0,
    };
    *previous = Some((ld, ln));
    (ld + ((target as f64).ln() - ln) / slope).exp() as f32
}

/// Turns the placed pool points into root bindings.
fn bind_roots(
    surface: &Surface,
    positions: &[Vec3],
    fields: &Fields,
    pool: &SortedPool,
    samples: &[u32],
    seed: u64,
) -> Vec<RootBinding> {
    samples
        .iter()
        .map(|&slot| {
            let p = &pool.points[slot as usize];
            let at = p.surface_point();
            let direction = fields.direction_at(surface, at, p.normal);
            RootBinding {
                id: root_id(p.face, pool.draw_index(slot) as u64, seed),
                point: at,
                rest_direction: edge_basis_coordinates(surface.corners(positions, p.face as usize), direction),
                spacing: p.spacing,
                length_scale: fields.length_scale_at(surface, at),
                width_scale: fields.width_scale_at(surface, at),
            }
        })
        .collect()
}
