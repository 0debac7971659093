//! The root spacing a configuration asks for, before any sampling: the
//! feather count aimed at, how densely the guided sampler packs roots, and the
//! nominal spacing that spreads that count over a surface. The fields use
//! it for the nominal feather length (curvature spacing), the sampling for
//! its first guess of the spacing.
//!
//! `src/sampling/mod.rs` still holds its own copies of these constants and
//! of [`target_feathers`] (its owner is changing that folder; a test below
//! keeps the two equal until it imports them from here).

use crate::config::Config;

/// Root count aimed at when neither a spacing nor a target is given.
pub(crate) const DEFAULT_TARGET_FEATHERS: usize = 2000;

/// Roots per `d²` of (density-weighted) area the guided sampler typically
/// packs; only first guesses of the spacing use it.
pub(crate) const GUIDED_PACKING: f64 = 0.75;

/// The feather count aimed at: `config.target_feathers`, or the default
/// when that is 0.
pub(crate) fn target_feathers(config: &Config) -> usize {
    if config.target_feathers > 0 { config.target_feathers } else { DEFAULT_TARGET_FEATHERS }
}

/// The spacing before any multiplier: `config.spacing` when set, else the
/// guided sampler's spacing for the wanted count over `area`.
pub(crate) fn nominal_spacing(area: f64, config: &Config) -> f32 {
    if config.spacing > 0.0 {
        config.spacing
    } else {
        let target = target_feathers(config) as f64;
        (area / (GUIDED_PACKING * target)).sqrt() as f32
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_samplers_copies_agree() {
        // Until `sampling` imports these from here (module notes).
        assert_eq!(crate::sampling::GUIDED_PACKING, GUIDED_PACKING);
        assert_eq!(crate::sampling::DEFAULT_TARGET_FEATHERS, DEFAULT_TARGET_FEATHERS);
        let mut config = Config::default();
        assert_eq!(crate::sampling::target_feathers(&config), DEFAULT_TARGET_FEATHERS);
        config.target_feathers = 123;
        assert_eq!(target_feathers(&config), 123);
        assert_eq!(crate::sampling::target_feathers(&config), 123);
    }

    #[test]
    fn the_nominal_spacing_spreads_the_target_over_the_area() {
        let config = Config { target_feathers: 100, ..Config::default() };
        let d = nominal_spacing(75.0, &config) as f64;
        assert!((d - 1.0).abs() < 1e-6, "{d}");
        assert_eq!(nominal_spacing(75.0, &Config { spacing: 0.25, ..config }), 0.25);
    }
}
