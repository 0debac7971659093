//! The method's parameters (safe Rust side). Every length is in model units;
//! a length of 0 means "derive it from the mesh or the spacing".

use crate::error::{Error, ErrorKind, Result};
use glam::Vec3;

/// Default pop threshold (`Config::pop_threshold`): 5° (radians).
pub const DEFAULT_POP_THRESHOLD: f32 = 5.0 * std::f32::consts::PI / 180.0;
/// Default settle rate (`Config::settle_rate`): 2° a frame (radians).
pub const DEFAULT_SETTLE_RATE: f32 = 2.0 * std::f32::consts::PI / 180.0;

/// How roots are planted (DESIGN.md §2).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum SamplerKind {
    /// Orientation-field-guided sampling (paper, Algorithm 1).
    Guided,
    /// Area-weighted dart throwing at the same density (the 2015 baseline).
    Random,
}

/// How frames after the first are handled (DESIGN.md §5).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum Mode {
    /// Incremental reordering and minimal readjustment (paper §3.3).
    Incremental,
    /// The 2015 method: order fixed at the first frame, Eq. 2, fine pitch only.
    Legacy,
    /// Everything recomputed every frame; the quality reference.
    Rebuild,
}

/// Shaft segments of the default feather: four, so that it bends over what
/// lies beneath it ([`Preset::Kite`] is the rigid one).
pub const DEFAULT_SHAFT_SEGMENTS: u32 = 4;

/// The configuration's fields, declared once: each with its documentation,
/// type and default; the `PlumageConfig` field(s) that carry it across the C
/// ABI and how (`by`, a carrier of `ffi/carry.rs`); and its
/// finiteness check (`check`: `length` = finite, ≥ 0 and within
/// [`MAX_COORDINATE`](crate::limits::MAX_COORDINATE); `nonneg` = finite and
/// ≥ 0; `none` = checked by hand in [`Config::validate`], if at all).
///
/// The X-macro pattern: `config_fields!(callback)` hands the table to
/// `callback!`, which generates from it. [`Config`], its `Default`, the
/// finiteness checks and [`Config::FIELD_NAMES`] are made here; the C
/// struct is written out in `src/ffi/config.rs` (cbindgen reads sources,
/// not expansions), and both conversions there are generated from this
/// table, so a field the C struct lacks, or a C field the table does not
/// name, is a compile error.
macro_rules! config_fields {
    ($callback:ident) => {
        $callback! {
            /// Seed of every random choice; same input and seed give the same bytes.
            seed: u64 = 1, c[seed] by Same, check none;
            /// Worker threads: 0 = all cores (one pool shared by every system made
            /// with 0), 1 = run inline on the caller's thread, N = N of its own.
            threads: usize = 0, c[threads] by Narrow, check none;
            /// Root sampler.
            sampler: SamplerKind = SamplerKind::Guided, c[sampler] by SamplerCode, check none;
            /// Frame-to-frame mode.
            mode: Mode = Mode::Incremental, c[mode] by ModeCode, check none;
            /// Poisson-disk radius `d` in model units; 0 = derived (from
            /// `target_feathers` when given, else from the mesh size).
            spacing: f32 = 0.0, c[spacing] by Same, check length;
            /// Wanted feather count (0 = use `spacing`); met within ±15 %.
            target_feathers: usize = 0, c[target_feathers] by Narrow, check none;
            /// Stagger angle θ of Algorithm 1, radians (default π/4).
            theta: f32 = std::f32::consts::FRAC_PI_4, c[theta] by Same, check none;
            /// Randomness `u0 ∈ [0, 1]` of Algorithm 1.
            randomness: f32 = 0.0, c[randomness] by Same, check none;
            /// Sample pool size as a multiple of the expected root count.
            pool_factor: f32 = 30.0, c[pool_factor] by Same, check none;
            /// Feather length; 0 = a multiple of the local spacing.
            feather_length: f32 = 0.0, c[feather_length] by Same, check length;
            /// Feather width; 0 = a multiple of the local spacing.
            feather_width: f32 = 0.0, c[feather_width] by Same, check length;
            /// Feather thickness; 0 = a fraction of the width.
            feather_thickness: f32 = 0.0, c[feather_thickness] by Same, check length;
            /// γ of Eq. 3 (and Eq. 2), `0 ≤ λ < γ < 1`.
            gamma: f32 = 0.6, c[gamma] by Same, check none;
            /// λ of Eq. 3.
            lambda: f32 = 0.3, c[lambda] by Same, check none;
            /// k of the k-nearest-root neighbourhoods.
            k_neighbours: usize = 10, c[k_neighbours] by Narrow, check none;
            /// Height-field cells along the shaft.
            height_field_u: usize = 32, c[height_field_u] by Narrow, check none;
            /// Height-field cells across the vanes.
            height_field_v: usize = 16, c[height_field_v] by Narrow, check none;
            /// Extra lift added in the fine-pitch step, radians (≥ 0); a bent
            /// feather's root segment is lifted by it above where it drapes.
            fluffiness: f32 = 0.0, c[fluffiness] by Same, check nonneg;
            /// Allowed penetration into obstacles, as a fraction of feather
            /// thickness (≥ 0), in the straight feather's fine-pitch step (the
            /// kite's); a bent feather's drape keeps its clearance.
            collision_allowance: f32 = 0.0, c[collision_allowance] by Same, check nonneg;
            /// Propagation threshold θs (radians): a readjusted feather whose pitch
            /// or roll moved more than this makes the feathers lying on it readjust
            /// too, and a feather whose surroundings moved relative to it by more
            /// than θs times its length (as far as such a turn moves its tip) is
            /// readjusted.
            theta_s: f32 = 0.05, c[theta_s] by Same, check nonneg;
            /// Incremental mode only, radians (default 0.3, about 17°). When it is
            /// above `theta_s`, every feather whose surroundings moved is checked
            /// each frame with the exact tests of the validation and readjusted at
            /// once if it intersects anything; otherwise it keeps its pose until
            /// what surrounds it has moved, relative to it, by this angle times its
            /// length, and only a readjusted feather that turned by more than this
            /// angle makes those lying on it readjust. Feathers then never
            /// intersect because of the motion, far fewer are readjusted each frame,
            /// and a feather may float above its place by up to about this angle.
            /// At or below `theta_s` the paper's rule applies (readjust at θs, no
            /// exact checks).
            drift_tolerance: f32 = 0.3, c[drift_tolerance] by Same, check nonneg;
            /// Flow axis used to derive the orientation field when the mesh gives no
            /// hints and `flow_source` is unset. Zero (the default) derives it from
            /// the mesh: its principal axis, pointing to −Z (glTF models face +Z),
            /// else down (−Y), else +X.
            flow_axis: Vec3 = Vec3::ZERO, c[flow_axis] by Triple, check none;
            /// Where the derived orientation field starts, when set (and the mesh
            /// gives no hints): feathers then point away from the mesh vertex
            /// nearest this point along the surface, e.g. from the beak tip down the
            /// neck, along the body and out to the tip of every wing, leg and tail.
            /// A constant `flow_axis` instead starts a flow at every rim that faces
            /// it (a wing's leading edge), where no feather can cover the rim.
            flow_source: Option<Vec3> = None, c[flow_source_enabled, flow_source] by OptionalPoint, check none;
            /// Recompute neighbourhoods and obstacle sets at the current pose each
            /// frame (beyond the paper, its Fig. 8 limitation).
            recompute_neighbourhoods: bool = true, c[recompute_neighbourhoods] by Flag, check none;
            /// Smallest spacing multiplier that the bending of the surface may set,
            /// in (0, 1]; 1 turns the adaptation off. Where the surface bends on a
            /// radius shorter than a feather (a thin leg or neck, a wing tip, a
            /// crease), roots are planted closer and their feathers (sized by the
            /// spacing) are shorter, down to this fraction, so they can wrap the
            /// part instead of standing off it. Multiplies the host's spacing
            /// multipliers; off when `feather_length` is set (feathers then do
            /// not follow the spacing).
            curvature_min_scale: f32 = 0.4, c[curvature_min_scale] by Same, check none;
            /// Shaft segments of every feather, 1 to 4 (see
            /// [`FeatherShape::segments`](crate::feather::FeatherShape::segments)):
            /// 1 is the rigid kite; with more, each joint may bend so the feather
            /// drapes over what lies beneath it.
            shaft_segments: u32 = DEFAULT_SHAFT_SEGMENTS, c[shaft_segments] by Same, check none;
            /// Largest bend at each joint of a segmented shaft away from the skin,
            /// radians, in [0, 1.2] (0 keeps feathers straight); toward the skin a
            /// joint may bend twice as far (see
            /// [`DOWN_BEND_PER_LIMIT`](crate::adjustment::DOWN_BEND_PER_LIMIT)).
            bend_limit: f32 = crate::adjustment::DEFAULT_BEND_LIMIT, c[bend_limit] by Same, check none;
            /// Feather length as a multiple of the local spacing, when
            /// `feather_length` is 0 (default 4: a feather reaches over three to
            /// four rows of neighbours), in (0, 20].
            length_per_spacing: f32 = crate::feather::LENGTH_PER_SPACING, c[length_per_spacing] by Same, check none;
            /// Feather width as a multiple of the local spacing, when
            /// `feather_width` is 0 (default 1.75), in (0, 20].
            width_per_spacing: f32 = crate::feather::WIDTH_PER_SPACING, c[width_per_spacing] by Same, check none;
            /// A feather whose pose relative to its root (pitch, roll, a bend)
            /// changes by more than this between frames counts as a pop in the
            /// frame figures (radians, default 5°). A figure only: it changes no
            /// result.
            pop_threshold: f32 = DEFAULT_POP_THRESHOLD, c[pop_threshold] by Same, check nonneg;
            /// Incremental mode: the most a readjusted feather's pose relative to
            /// its root (pitch, roll, a bend) may move toward its newly solved pose
            /// in one frame, radians (default 2°; 0 = no limit, the solved pose at
            /// once). A feather that must lift to stay clear still lifts at once
            /// (the smallest lift found clear by the exact checks, else the solved
            /// pose); only settling is spread over frames, so the coat does not
            /// pop (see [`crate::animation::coherence`]).
            settle_rate: f32 = DEFAULT_SETTLE_RATE, c[settle_rate] by Same, check nonneg;
            /// Keyframed checkpoints for scrubbing: every this many steps (and
            /// after create) the system keeps its state blob in memory, so
            /// [`System::seek`](crate::System::seek) can go back to the nearest
            /// one and the caller replays the frames from there, reaching any
            /// frame with the playback result. 0 (the default) keeps none. Changes
            /// no result.
            checkpoint_interval: u32 = 0, c[checkpoint_interval] by Same, check none;
            /// Most checkpoints kept besides the one after create (default 64, at
            /// least 1): past it, the oldest is dropped. Changes no result.
            checkpoint_cap: u32 = 64, c[checkpoint_cap] by Same, check none;
            /// Most heap bytes the system may hold ([`System::memory`](crate::System::memory)),
            /// 0 (the default) for no limit. Create refuses with `LimitExceeded`
            /// before its large allocations when the feathers' own arrays alone
            /// would pass it, and after building when the whole system does (then
            /// everything it built is freed); a step or evaluate that would leave
            /// the system above it is refused and undone. Under a limit (as with a
            /// progress callback) the system keeps a copy of the coat from call to
            /// call, to undo a call with, and counts it. Changes no result.
            memory_limit: usize = 0, c[memory_limit] by Bytes, check none;
        }
    };
}
pub(crate) use config_fields;

/// Makes [`Config`], its `Default`, its field names and its finiteness
/// checks from [`config_fields!`].
macro_rules! define_config {
    ($($(#[$doc:meta])* $name:ident: $ty:ty = $default:expr, c[$($cname:ident),+] by $carry:ident, check $check:ident;)*) => {
        /// All parameters of a system. `Config::default()` gives the documented defaults.
        #[derive(Clone, Debug, PartialEq)]
        pub struct Config {
            $($(#[$doc])* pub $name: $ty,)*
        }

        impl Default for Config {
            fn default() -> Self {
                Self { $($name: $default,)* }
            }
        }

        impl Config {
            /// Every field's name, in declaration order.
            pub const FIELD_NAMES: &'static [&'static str] = &[$(stringify!($name)),*];

            /// The names of the fields whose values differ from `other`'s.
            pub fn differing_fields(&self, other: &Config) -> Vec<&'static str> {
                let mut names = Vec::new();
                $(if self.$name != other.$name {
                    names.push(stringify!($name));
                })*
                names
            }

            /// The fields that must be finite and ≥ 0, in declaration
            /// order: (name, value, whether it is a length bounded by
            /// `MAX_COORDINATE`).
            fn nonnegative_fields(&self) -> Vec<(&'static str, f32, bool)> {
                [$(check_field!($check, $name, self.$name)),*].into_iter().flatten().collect()
            }
        }
    };
}

/// One entry of [`Config::nonnegative_fields`], by its `check` kind (none
/// for `none`).
macro_rules! check_field {
    (none, $name:ident, $value:expr) => {
        None
    };
    (nonneg, $name:ident, $value:expr) => {
        Some((stringify!($name), $value, false))
    };
    (length, $name:ident, $value:expr) => {
        Some((stringify!($name), $value, true))
    };
}

config_fields!(define_config);

/// What a system dresses a surface with: the defaults of [`Config`] for
/// each ([`Config::preset`]).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum Preset {
    /// Contour feathers that lie down (the defaults): long (4 rows),
    /// narrow, lying over three to four rows of their neighbours, with bent
    /// shafts (four segments), so that each feather drapes over what lies
    /// beneath it.
    Feathers,
    /// Fish scales: short and wide (2 spacings each), nearly rigid (two
    /// segments, a small bend), in staggered rows, each overlapping the
    /// next row by half.
    Scales,
    /// Another name for [`Preset::Feathers`]: always the same defaults.
    Sleek,
    /// The paper's feather: the defaults of [`Preset::Feathers`] with a
    /// rigid shaft (one segment, the flat kite). Cheaper to adjust than a
    /// bent feather, but a coat of them stands off the body (README, "The
    /// kite").
    Kite,
}

impl Config {
    /// The adjustment's parameters: its defaults with this configuration's
    /// height-field resolution, fluffiness, collision allowance and bend
    /// limit.
    pub fn adjust_params(&self) -> crate::adjustment::AdjustParams {
        crate::adjustment::AdjustParams {
            height_field_u: self.height_field_u,
            height_field_v: self.height_field_v,
            fluffiness: self.fluffiness,
            collision_allowance: self.collision_allowance,
            bend_limit: self.bend_limit,
            ..Default::default()
        }
    }
}

impl Config {
    /// The defaults for a preset ([`Config::default`] is
    /// [`Preset::Feathers`]).
    pub fn preset(preset: Preset) -> Self {
        match preset {
            Preset::Feathers | Preset::Sleek => Self::default(),
            Preset::Kite => Self { shaft_segments: 1, ..Self::default() },
            Preset::Scales => Self {
                length_per_spacing: 2.0,
                width_per_spacing: 2.0,
                shaft_segments: 2,
                bend_limit: 0.15,
                theta: std::f32::consts::FRAC_PI_4,
                ..Self::default()
            },
        }
    }
}

impl crate::feather::FeatherType {
    /// The proportions of `preset` (its length and width per spacing), for
    /// a type of a type map.
    pub fn of_preset(preset: Preset) -> Self {
        let c = Config::preset(preset);
        Self { length_per_spacing: c.length_per_spacing, width_per_spacing: c.width_per_spacing, thickness_scale: 1.0 }
    }
}

impl Config {
    /// Checks every field against its documented range.
    pub fn validate(&self) -> Result<()> {
        let bad = |msg: String| Err(Error::new(ErrorKind::InvalidArgument, msg));
        let nonnegative = self.nonnegative_fields();
        for &(name, v, _) in &nonnegative {
            if !v.is_finite() || v < 0.0 {
                return bad(format!("config.{name} must be finite and >= 0 (got {v})"));
            }
        }
        if self.checkpoint_cap == 0 {
            return Err(Error::new(ErrorKind::InvalidArgument, "config.checkpoint_cap must be at least 1"));
        }
        if !(1..=crate::feather::MAX_SEGMENTS as u32).contains(&self.shaft_segments) {
            return bad(format!(
                "config.shaft_segments must be in [1, {}] (got {})",
                crate::feather::MAX_SEGMENTS,
                self.shaft_segments
            ));
        }
        if !(self.bend_limit.is_finite() && (0.0..=1.2).contains(&self.bend_limit)) {
            return bad(format!("config.bend_limit must be in [0, 1.2] radians (got {})", self.bend_limit));
        }
        for (name, v) in
            [("length_per_spacing", self.length_per_spacing), ("width_per_spacing", self.width_per_spacing)]
        {
            if !(v.is_finite() && v > 0.0 && v <= 20.0) {
                return bad(format!("config.{name} must be in (0, 20] (got {v})"));
            }
        }
        let limit = crate::limits::MAX_COORDINATE;
        for &(name, v, _) in nonnegative.iter().filter(|(_, _, length)| *length) {
            if v > limit {
                return Err(Error::new(
                    ErrorKind::LimitExceeded,
                    format!("config.{name} is {v:e}, beyond the supported {limit:e} model units"),
                ));
            }
        }
        if !self.theta.is_finite() {
            return bad(format!("config.theta must be finite (got {})", self.theta));
        }
        if !(0.0..=1.0).contains(&self.randomness) {
            return bad(format!("config.randomness must be in [0, 1] (got {})", self.randomness));
        }
        if !(self.pool_factor.is_finite() && (1.0..=1000.0).contains(&self.pool_factor)) {
            return bad(format!("config.pool_factor must be in [1, 1000] (got {})", self.pool_factor));
        }
        if !(0.0 <= self.lambda && self.lambda < self.gamma && self.gamma < 1.0) {
            return bad(format!(
                "config needs 0 <= lambda < gamma < 1 (got gamma {}, lambda {})",
                self.gamma, self.lambda
            ));
        }
        if !(1..=64).contains(&self.k_neighbours) {
            return bad(format!("config.k_neighbours must be in [1, 64] (got {})", self.k_neighbours));
        }
        for (name, v) in [("height_field_u", self.height_field_u), ("height_field_v", self.height_field_v)] {
            if !(2..=1024).contains(&v) {
                return bad(format!("config.{name} must be in [2, 1024] (got {v})"));
            }
        }
        if self.threads > 1024 {
            return bad(format!("config.threads must be at most 1024 (got {})", self.threads));
        }
        if self.target_feathers > crate::limits::MAX_FEATHERS {
            return Err(Error::new(
                ErrorKind::LimitExceeded,
                format!(
                    "config.target_feathers is {} but at most {} feathers are supported",
                    self.target_feathers,
                    crate::limits::MAX_FEATHERS
                ),
            ));
        }
        if !self.flow_axis.is_finite() || (self.flow_axis != Vec3::ZERO && self.flow_axis.length_squared() < 1e-12) {
            return bad(format!(
                "config.flow_axis must be finite and zero (derive it) or not tiny (got {:?})",
                self.flow_axis
            ));
        }
        if !(self.curvature_min_scale > 0.0 && self.curvature_min_scale <= 1.0) {
            return bad(format!("config.curvature_min_scale must be in (0, 1] (got {})", self.curvature_min_scale));
        }
        if let Some(p) = self.flow_source.filter(|p| !p.is_finite()) {
            return bad(format!("config.flow_source must be finite (got {p:?})"));
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn defaults_are_valid() {
        Config::default().validate().unwrap();
    }

    #[test]
    fn gamma_lambda_order_is_enforced() {
        let cfg = Config { lambda: 0.7, ..Config::default() };
        assert_eq!(cfg.validate().unwrap_err().kind(), ErrorKind::InvalidArgument);
    }
}
