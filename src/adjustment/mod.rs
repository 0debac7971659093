//! Height-field adjustment of feathers (DESIGN.md §4, our reconstruction of
//! Liu et al. 2015 as outlined in §2.3 of the 2017 paper).
//!
//! One feather at a time ([`adjust_feather`]): its obstacles (earlier
//! feathers within reach, raised by their thickness) and the body near its
//! root are rasterised into a [`HeightField`] in the feather's own frame;
//! then three steps choose its pose:
//! 1. pitch: the smallest α that keeps the (unrolled) feather above every
//!    cell it covers;
//! 2. roll: towards the β that balances the free volume under the two
//!    vanes, as far as the re-pitched feather then lies nowhere above the
//!    unrolled one (rolling pivots it down onto its free side; it never
//!    lifts a vane corner that later feathers would have to climb);
//! 3. fine pitch: the smallest α above every cell with that roll, then the
//!    user's fluffiness (extra lift) or collision allowance (sinking into
//!    obstacles by a fraction of the thickness).
//!
//! Many feathers ([`Adjuster::adjust_in_order`]): in a given order, each
//! reading only earlier feathers, parallel by levels of the obstacle
//! relation, bitwise identical to the serial result at any thread count.

mod checks;
mod drape;
mod height_field;
mod levels;
pub(crate) mod obstacle;
mod pitch_roll;
mod raster;
mod settle;
mod steps;
mod sweep;

pub use height_field::HeightField;
pub use levels::{AdjustStats, Adjuster, OrderedRun, Selection, adjust_in_order};
pub use steps::adjust_feather;

use crate::feather::{FeatherPose, FeatherTriangles};

/// Default clearance kept between a feather and an obstacle's top, as a
/// fraction of the adjusted feather's thickness.
pub(crate) const DEFAULT_CLEARANCE: f32 = 0.1;
/// Default clearance angle above the body (radians): every body point at
/// distance x along the shaft stays at least x·tan(angle) below the feather.
pub(crate) const DEFAULT_BODY_CLEARANCE_ANGLE: f32 = 0.01;
/// Default lowest pitch (radians, −20°): a feather may droop this far where
/// the body falls away.
pub(crate) const DEFAULT_MIN_PITCH: f32 = -0.35;
/// Default highest pitch (radians, about 63°): beyond this a feather would
/// stand up from the coat; a feather that needs more is clamped and reported.
pub(crate) const DEFAULT_MAX_PITCH: f32 = 1.1;
/// Default largest roll magnitude (radians, about 34°).
pub(crate) const DEFAULT_MAX_ROLL: f32 = 0.6;
/// Default smallest size a feather is shortened to (fraction of its shape)
/// when it cannot lie down within the pitch limit.
pub(crate) const DEFAULT_MIN_SCALE: f32 = 0.15;
/// Default largest bend at a joint of a segmented shaft away from the skin
/// (radians, about 23°); see [`DOWN_BEND_PER_LIMIT`] for bends toward it.
pub const DEFAULT_BEND_LIMIT: f32 = 0.4;
/// A joint may bend toward the skin this many times `bend_limit` (46° at
/// the default): a feather curls down over a rounded body or a wing's rim
/// more readily than it rises over what lies beneath it (a real shaft is
/// curved toward the skin). Three joints then curl a feather by up to
/// about 140° down. Twice brings the tips closer to the skin than a
/// symmetric limit without the sharp kinks of three times (BENCHMARKS.md,
/// "Measurements behind the code's constants").
pub const DOWN_BEND_PER_LIMIT: f32 = 2.0;

/// Parameters of the height-field adjustment.
#[derive(Clone, Debug, PartialEq)]
pub struct AdjustParams {
    /// Height-field cells along the shaft (≥ 2).
    pub height_field_u: usize,
    /// Height-field cells across the vanes (≥ 3).
    pub height_field_v: usize,
    /// Clearance above obstacle tops, as a fraction of the adjusted
    /// feather's thickness.
    pub clearance: f32,
    /// Clearance angle above the body, radians.
    pub body_clearance_angle: f32,
    /// Extra lift added after the fine-pitch step, radians (≥ 0).
    pub fluffiness: f32,
    /// Allowed sinking into obstacles in the fine-pitch step, as a fraction
    /// of the adjusted feather's thickness (≥ 0). Never applies to the body.
    pub collision_allowance: f32,
    /// Lowest pitch, radians (< 0 lets feathers droop onto convex skin).
    pub min_pitch: f32,
    /// Highest pitch, radians (< π/2).
    pub max_pitch: f32,
    /// Largest roll magnitude, radians (< π/2).
    pub max_roll: f32,
    /// Smallest size, as a fraction of the feather's shape, that a feather
    /// needing more than `max_pitch` is shortened to (1 = never shorten).
    pub min_scale: f32,
    /// Largest bend at a joint of a segmented shaft away from the skin,
    /// radians (≥ 0; 0 keeps every feather straight); toward the skin,
    /// [`DOWN_BEND_PER_LIMIT`] times this.
    pub bend_limit: f32,
}

impl AdjustParams {
    /// The bends a joint of a segmented shaft may take, radians: from
    /// [`DOWN_BEND_PER_LIMIT`] times `bend_limit` toward the skin (negative)
    /// to `bend_limit` away from it.
    pub fn bend_range(&self) -> (f32, f32) {
        (-DOWN_BEND_PER_LIMIT * self.bend_limit, self.bend_limit)
    }
}

impl Default for AdjustParams {
    fn default() -> Self {
        Self {
            height_field_u: 32,
            height_field_v: 16,
            clearance: DEFAULT_CLEARANCE,
            body_clearance_angle: DEFAULT_BODY_CLEARANCE_ANGLE,
            fluffiness: 0.0,
            collision_allowance: 0.0,
            min_pitch: DEFAULT_MIN_PITCH,
            max_pitch: DEFAULT_MAX_PITCH,
            max_roll: DEFAULT_MAX_ROLL,
            min_scale: DEFAULT_MIN_SCALE,
            bend_limit: DEFAULT_BEND_LIMIT,
        }
    }
}

/// Which steps an adjustment runs.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum AdjustSteps {
    /// Pitch, roll, fine pitch (the 2017 paper, and every first placement).
    Full,
    /// Fine pitch only, keeping the previous roll (the 2015 incremental
    /// mode, the paper's "Previous" column).
    FinePitchOnly,
}

/// An already placed feather as seen by the one being adjusted.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ObstacleFeather {
    /// Its triangles in world space (see [`crate::feather::feather_triangles`]).
    pub triangles: FeatherTriangles,
    /// Its thickness: its top lies this far above its triangles.
    pub thickness: f32,
    /// Whether it grows from the far side of a thin part (its normal turned
    /// away from the adjusted feather's): a height field cannot represent
    /// it, so it is only checked exactly, never rasterised. The adjuster
    /// also sets it for obstacles wholly outside the column over the
    /// feather's grid, where rasterising would find nothing.
    pub far_side: bool,
}

/// The result of adjusting one feather.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct AdjustOutcome {
    /// The new pose.
    pub pose: FeatherPose,
    /// Obstacle feathers rasterised (one collision detection each, the
    /// figure of the paper's Table 1).
    pub collision_tests: u32,
    /// Whether a pitch or roll limit bound (the feather may then touch an
    /// obstacle or stand at its limit).
    pub clamped: bool,
    /// How a segmented feather's bends were found.
    pub drape: DrapeRoute,
}

/// How the adjustment found a feather's bends (DESIGN.md §4, bending).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum DrapeRoute {
    /// Not draped: a kite, a feather left straight (no bend limit) or left
    /// out.
    #[default]
    Straight,
    /// The swept drape, confirmed by one exact check.
    Swept,
    /// The descent by exact checks, where the swept drape found no room or
    /// its pose failed the check.
    Descent,
    /// Not solved: the pose of the last frame, which failed its exact
    /// check, repaired where it lay (incremental runs).
    Repaired,
    /// Not solved: the pose of the last frame, clear, lowered a step or
    /// kept (incremental runs).
    Lowered,
}
