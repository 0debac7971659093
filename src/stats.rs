//! Figures a system reports: sampling quality, ordering, per-frame costs and
//! exact validation. Plain data; the FFI layer copies them out.

/// Sampling quality of the roots (DESIGN.md §2).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct SamplingReport {
    /// Number of roots planted.
    pub roots: usize,
    /// Global Poisson-disk radius `d` used.
    pub spacing: f32,
    /// min over roots of (distance to nearest root on the same side) / d_i.
    pub relative_radius: f32,
    /// max over surface probes of (distance to nearest root) / local d.
    pub coverage_gap: f32,
    /// mean of cos 4(φ − θ) over each root's 4 nearest neighbours.
    pub alignment: f32,
    /// Faces of the feathered skin round which the rest orientation field
    /// turns ([`crate::validation::field_singularities`]).
    pub field_singularities: usize,
    /// Wall time of sampling.
    pub seconds: f64,
}

/// The static order (DESIGN.md §4).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct OrderingReport {
    /// Symmetric neighbour pairs.
    pub pairs: usize,
    /// Priority edges kept in the DAG.
    pub edges: usize,
    /// Edges dropped to break cycles.
    pub dropped_edges: usize,
    /// Edges whose head comes after their tail in the order (must be 0).
    pub violations: usize,
    /// Wall time of neighbourhoods, priorities and ordering.
    pub seconds: f64,
}

/// What one create, step or evaluate did (DESIGN.md §5 step 5).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct FrameReport {
    /// 0 for create, then 1, 2, ... for each step; evaluate keeps the index.
    pub frame_index: u64,
    /// Feathers re-adjusted in this call.
    pub adjusted: usize,
    /// Feathers whose surroundings moved relative to them, since they were
    /// last adjusted, by more than θs times their length (the paper's `R_k`,
    /// see [`crate::frame::step_coat`]).
    pub deformed: usize,
    /// Feathers readjusted in any case: those whose surroundings moved by
    /// more than the drift tolerance times their length (θs in the paper's
    /// rule, when `R*_k` = `R_k` plus what follows), plus those whose
    /// obstacles the reordering changed. The rest of `adjusted` came by
    /// propagation or failed the exact check.
    pub seeds: usize,
    /// Feathers whose surroundings moved but were only checked exactly
    /// (they still clear everything) and keep their pose: incremental mode
    /// with a drift tolerance above θs (see `Config::drift_tolerance`).
    pub verified: usize,
    /// Obstacle feathers rasterised in this call.
    pub collision_tests: u64,
    /// Pairs whose priority difference changed sign.
    pub priority_changes: usize,
    /// Edge reversals carried out.
    pub reversals: usize,
    /// Reversals refused by the cycle rule (old edge kept).
    pub reversals_refused: usize,
    /// Cycles broken by deleting their smallest-|ΔP| edge.
    pub cycles_broken: usize,
    /// Feathers whose pitch or roll hit a limit.
    pub clamped: usize,
    /// Re-adjusted segmented feathers whose bends were draped (DESIGN.md
    /// §4, bending).
    pub draped: usize,
    /// Of those, the ones the swept drape left to the descent by exact
    /// checks (it found no room, or its pose failed the exact check).
    pub drape_descents: usize,
    /// Re-adjusted segmented feathers kept where they lay rather than
    /// draped afresh (incremental steps): lifted in place as little as
    /// clears them, or lowered a step, or left resting.
    pub kept_in_place: usize,
    /// Seconds spent re-posing roots and reordering.
    pub reorder_seconds: f64,
    /// Seconds spent in the height-field adjustment.
    pub adjust_seconds: f64,
    /// Seconds for the whole call.
    pub step_seconds: f64,
    /// The part of `reorder_seconds` spent finding the neighbourhoods and
    /// obstacle candidates at the current pose: every create, evaluate and
    /// rebuild step, incremental steps with
    /// `Config::recompute_neighbourhoods`, never a legacy step.
    pub neighbourhood_seconds: f64,
    /// Levels the adjustment ran through (DESIGN.md §4): the longest chain,
    /// among the feathers the call may visit, of feathers each reading the
    /// one before as an obstacle, plus one per feather of a step's second
    /// pass (which runs one feather after another). A level's feathers run
    /// in parallel; levels close to the number of feathers visited mean the
    /// call ran nearly one feather at a time. A verifying step walks the
    /// order instead, its checks made ahead on the other threads: one
    /// level for those checks, plus one per feather adjusted.
    pub levels: usize,
}

impl FrameReport {
    /// Collision tests per adjusted feather (0 when none was adjusted).
    pub fn collision_tests_per_feather(&self) -> f64 {
        if self.adjusted == 0 { 0.0 } else { self.collision_tests as f64 / self.adjusted as f64 }
    }
}

/// Figures of the last create, step or evaluate restricted to a part of the
/// mesh (a range of the caller's triangles): its feathers are those rooted
/// there. Several meshes dressed as one system read their own figures so.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct PartReport {
    /// Feathers rooted on the part.
    pub feathers: usize,
    /// Of those, feathers placed (not left out at their root).
    pub placed: usize,
    /// Of those, feathers the last create, step or evaluate readjusted.
    pub adjusted: usize,
    /// Of those, feathers whose pose relative to the root changed by more
    /// than `Config::pop_threshold` in the last step or evaluate.
    pub pops: usize,
    /// The largest such change among them, radians.
    pub largest_pose_change: f32,
}

/// Exact validation of the current feathers (DESIGN.md §6).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct ValidationReport {
    /// Pairs of feathers whose triangles intersect.
    pub intersecting_pairs: usize,
    /// Feathers crossing the body more than 5 % of their length from the root.
    pub body_penetrations: usize,
    /// Fraction of the probes of the feathered, visible skin whose normal
    /// ray meets a feather within the longest feather length.
    pub coverage: f64,
    /// Probes behind `coverage`.
    pub probes: usize,
    /// Probes of the feathered skin left out because they lie inside the
    /// body (where the mesh passes through itself).
    pub buried_probes: usize,
    /// Mean pitch in degrees.
    pub mean_pitch_deg: f64,
    /// Median distance from a placed feather's tip to the body, in feather lengths.
    pub tip_height_median: f64,
    /// 90th percentile of the same.
    pub tip_height_p90: f64,
    /// Percentage of placed feathers whose tip stands more than half a length off the skin.
    pub bristle_percent: f64,
    /// Median over placed feathers of the tip height over the stack floor:
    /// the thicknesses of the feathers beneath the tip summed (at least the
    /// feather's own thickness), in feather lengths. 1 means the tips lie on
    /// the feathers stacked beneath them; larger, higher than the stack forces.
    pub stack_efficiency: f64,
    /// Median number of feathers beneath a placed feather's tip.
    pub stack_depth_median: f64,
    /// Percentage of feathers whose heading turns more than 45° from their
    /// 8 nearest neighbours' mean ([`crate::validation::groom`]).
    pub discord_percent: f64,
}

/// One feather as the host sees it.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct FeatherRecord {
    /// Stable id from the rest binding and the seed.
    pub id: u64,
    /// Position in the adjustment order.
    pub order_index: u32,
    /// The caller's triangle holding the root.
    pub triangle: u32,
    /// Barycentric weights of the root on that triangle's corners.
    pub barycentric: [f32; 3],
    /// Root position.
    pub root: [f32; 3],
    /// Surface normal at the root.
    pub normal: [f32; 3],
    /// Shaft direction after pitch and roll.
    pub direction: [f32; 3],
    /// Pitch, radians.
    pub pitch: f32,
    /// Roll, radians.
    pub roll: f32,
    /// Feather length as placed (shortened where it could not lie down; 0
    /// when left out).
    pub length: f32,
    /// Feather width as placed.
    pub width: f32,
    /// Feather thickness.
    pub thickness: f32,
}
