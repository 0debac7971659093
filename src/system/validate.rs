//! Checking a system's current coat: the exact validation, whole or for a
//! part of the mesh, and the last call's figures for a part.

use super::System;
use crate::error::Result;
use crate::feather::{FeatherTriangles, feather_triangles, pose_change};
use crate::progress::Progress;
use crate::stats::{PartReport, ValidationReport};
use crate::validation::{
    CheckAudit, ProbeSkin, Validation, ValidationInput, audit_checks, validate_part, validate_with_progress,
};

/// Probes per feather for the coverage figure of [`System::validate`].
const COVERAGE_PROBES_PER_FEATHER: usize = 4;
/// Bounds on the number of coverage probes.
const COVERAGE_PROBES_MIN: usize = 2_000;
const COVERAGE_PROBES_MAX: usize = 200_000;

impl System {
    /// Exact validation of the current feathers (DESIGN.md §6).
    pub fn validate(&self) -> Option<ValidationReport> {
        self.validate_with_progress(&Progress::none()).expect("validation without a progress sink is never interrupted")
    }

    /// As [`System::validate`], reporting to `progress`, which may stop it
    /// (`Interrupted`; validation never changes the system).
    pub fn validate_with_progress(&self, progress: &Progress) -> Result<Option<ValidationReport>> {
        self.maybe_test_panic();
        let n = self.dressing.len();
        let tris = self.feather_triangle_sets();
        let skin = ProbeSkin {
            positions: &self.coat.positions,
            triangles: &self.dressing.triangles,
            feathered: &self.dressing.feathered,
        };
        let input = self.validation_input(&tris, &skin, coverage_probes(n));
        let v = self.pool.install(|| validate_with_progress(&input, progress))?;
        Ok(Some(validation_report(&v)))
    }

    /// [`System::validate`] restricted to the part of the mesh made of the
    /// caller's triangles `triangles` (e.g. one of several meshes dressed as
    /// one system): the pairs with at least one of its feathers (every other
    /// feather counts as an obstacle), its feathers' body penetrations, pitch,
    /// tip heights and tip stacks, and coverage probes drawn on its skin (covered by
    /// any feather), as many per feather as the whole validation draws.
    pub fn validate_part(&self, triangles: std::ops::Range<u32>) -> Option<ValidationReport> {
        self.maybe_test_panic();
        let member: Vec<bool> = self.records.iter().map(|r| triangles.contains(&r.triangle)).collect();
        let members = member.iter().filter(|&&m| m).count();
        let skin: Vec<[u32; 3]> = (self.dressing.triangles.iter().zip(&self.dressing.source_triangle))
            .filter(|&(_, s)| triangles.contains(s))
            .map(|(&t, _)| t)
            .collect();
        let tris = self.feather_triangle_sets();
        let skin = ProbeSkin { positions: &self.coat.positions, triangles: &skin, feathered: &self.dressing.feathered };
        let input = self.validation_input(&tris, &skin, coverage_probes(members));
        let v = self.pool.install(|| validate_part(&input, &member));
        Some(validation_report(&v))
    }

    /// The exact checks of the current coat made with the adjuster's
    /// shortcuts and without them (see [`crate::validation::audit_checks`]):
    /// how many answers differ. For the tests; slow (every skin face is
    /// measured).
    #[doc(hidden)]
    pub fn audit_exact_checks(&self) -> CheckAudit {
        let tris = self.feather_triangle_sets();
        let c = &self.coat;
        self.pool.install(|| audit_checks(&tris, &c.frames, &self.dressing.shapes, &c.poses, &c.body))
    }

    /// What a validation of the current coat looks at, with the coverage
    /// probes drawn on `skin`.
    fn validation_input<'a>(
        &'a self,
        feather_triangles: &'a [FeatherTriangles],
        skin: &'a ProbeSkin<'a>,
        probes: usize,
    ) -> ValidationInput<'a> {
        let c = &self.coat;
        ValidationInput {
            feather_triangles,
            frames: &c.frames,
            shapes: &self.dressing.shapes,
            poses: &c.poses,
            body: &c.body,
            skin,
            probes,
            seed: self.dressing.config.seed,
        }
    }

    /// The last create, step or evaluate's figures restricted to the
    /// feathers rooted on the caller's triangles `triangles`.
    pub fn part_report(&self, triangles: std::ops::Range<u32>) -> PartReport {
        let readjusted = self.readjusted();
        let mut r = PartReport::default();
        for (i, record) in self.records.iter().enumerate() {
            if !triangles.contains(&record.triangle) {
                continue;
            }
            r.feathers += 1;
            r.placed += usize::from(record.length > 0.0);
            r.adjusted += usize::from(readjusted.get(i).copied().unwrap_or(false));
            if let (Some(before), Some(after)) = (self.previous_poses.get(i), self.coat.poses.get(i)) {
                let change = pose_change(before, after);
                r.pops += usize::from(change > self.dressing.config.pop_threshold);
                r.largest_pose_change = r.largest_pose_change.max(change);
            }
        }
        r
    }

    /// Each feather's triangles at the current pose, as the validation takes
    /// them: posed again from the coat (the same floats the export gave the
    /// host), not read back from the host's float layout.
    fn feather_triangle_sets(&self) -> Vec<FeatherTriangles> {
        let (coat, shapes) = (&self.coat, &self.dressing.shapes);
        coat.frames.iter().zip(shapes).zip(&coat.poses).map(|((f, s), p)| feather_triangles(f, s, *p)).collect()
    }
}

/// Coverage probes for a validation of `feathers` feathers.
fn coverage_probes(feathers: usize) -> usize {
    (COVERAGE_PROBES_PER_FEATHER * feathers).clamp(COVERAGE_PROBES_MIN, COVERAGE_PROBES_MAX)
}

fn validation_report(v: &Validation) -> ValidationReport {
    ValidationReport {
        intersecting_pairs: v.intersecting_pairs.len(),
        body_penetrations: v.body_penetrations.len(),
        coverage: v.coverage,
        probes: v.probes,
        buried_probes: v.buried_probes,
        mean_pitch_deg: v.mean_pitch_deg,
        tip_height_median: v.tip_heights.median,
        tip_height_p90: v.tip_heights.p90,
        bristle_percent: v.tip_heights.bristle_percent,
        stack_efficiency: v.tip_stacks.efficiency,
        stack_depth_median: v.tip_stacks.depth_median,
        discord_percent: v.groom.discord_percent,
    }
}
