//! The rule that moves a coat from one frame to the next, decided once
//! from the configuration ([`FrameRule::of`]); everything a frame does
//! differently by mode asks it.

use crate::adjustment::AdjustSteps;
use crate::config::{Config, Mode};

/// How a frame after the first is made (DESIGN.md §5).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum FrameRule {
    /// The paper's rule (§3.3; the incremental mode with `drift_tolerance`
    /// at or below `theta_s`): the order is updated incrementally, a
    /// feather is readjusted once its surroundings moved relative to it by
    /// θs times its length (summed over frames), and a readjusted feather
    /// that turned past θs makes those lying on it readjust. No exact
    /// checks.
    Paper,
    /// The verifying rule (the incremental mode with `drift_tolerance`
    /// above `theta_s`, the default): every feather whose surroundings
    /// moved is checked exactly and readjusted only if it intersects
    /// something; a feather is re-seeded once its surroundings drifted by
    /// the drift tolerance times its length (net, since it was adjusted).
    Verifying,
    /// The 2015 method (the legacy mode): the order fixed at the first
    /// frame, fine pitch only, the paper's propagation.
    Legacy,
    /// Everything solved from scratch every frame (the rebuild mode).
    Rebuild,
}

impl FrameRule {
    /// The rule `config` asks for.
    pub fn of(config: &Config) -> Self {
        match config.mode {
            Mode::Incremental if config.drift_tolerance > config.theta_s => Self::Verifying,
            Mode::Incremental => Self::Paper,
            Mode::Legacy => Self::Legacy,
            Mode::Rebuild => Self::Rebuild,
        }
    }

    /// Whether the order is updated frame to frame (the paper's rule or
    /// the verifying one): only then may the neighbourhoods follow the
    /// pose and do feathers settle.
    pub fn incremental(self) -> bool {
        matches!(self, Self::Paper | Self::Verifying)
    }

    /// Whether feathers whose surroundings moved are checked exactly.
    pub fn verifies(self) -> bool {
        self == Self::Verifying
    }

    /// Whether the neighbourhoods and obstacle candidates are rebuilt at
    /// each frame's pose (incremental, with `recompute_neighbourhoods`).
    pub fn follows_pose(self, config: &Config) -> bool {
        self.incremental() && config.recompute_neighbourhoods
    }

    /// The adjustment's steps: fine pitch only for the legacy rule.
    pub fn steps(self) -> AdjustSteps {
        if self == Self::Legacy { AdjustSteps::FinePitchOnly } else { AdjustSteps::Full }
    }

    /// How far a readjusted feather settles toward its solved pose a frame
    /// (radians): the configuration's settle rate when incremental, else 0
    /// (the solved pose at once).
    pub fn settle_rate(self, config: &Config) -> f32 {
        if self.incremental() { config.settle_rate } else { 0.0 }
    }

    /// The motion of its surroundings (radians, times its length) past
    /// which a feather is re-seeded: the drift tolerance when verifying,
    /// else θs.
    pub fn drift(self, config: &Config) -> f32 {
        if self.verifies() { config.drift_tolerance } else { config.theta_s }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_rule_follows_the_mode_and_the_drift_tolerance() {
        let rule = |mode, drift_tolerance| FrameRule::of(&Config { mode, drift_tolerance, ..Config::default() });
        assert_eq!(FrameRule::of(&Config::default()), FrameRule::Verifying);
        assert_eq!(rule(Mode::Incremental, 0.05), FrameRule::Paper);
        assert_eq!(rule(Mode::Incremental, 0.06), FrameRule::Verifying);
        assert_eq!(rule(Mode::Legacy, 0.3), FrameRule::Legacy);
        assert_eq!(rule(Mode::Rebuild, 0.3), FrameRule::Rebuild);
        assert_eq!(FrameRule::Legacy.settle_rate(&Config::default()), 0.0);
        assert_eq!(FrameRule::Paper.drift(&Config::default()), Config::default().theta_s);
    }
}
