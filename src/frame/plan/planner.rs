//! The planner's rules (docs/plan.md §1): [`Planner::plan`], a frame's stages and their reasons.

use super::{plural, FrameState, Plan, PlannedStage, Planner, Stage};
use crate::scene::model::PyramidMode;

impl Planner {
    /// Whether `Renderer::new` creates the `IndirectPass` (and its radiance pyramid).
    pub fn creates_indirect(&self) -> bool {
        self.indirect
    }

    /// Indirect bounces each indirect frame records.
    pub fn bounces(&self) -> u32 {
        self.bounces
    }

    /// Why there is no indirect light, if there is none.
    pub(super) fn no_indirect(&self) -> Option<String> {
        if self.bounces == 0 {
            Some("gi.bounces = 0".into())
        } else if !self.indirect {
            Some("the surface reflects nothing (albedo 0 everywhere, no specular)".into())
        } else {
            None
        }
    }

    /// The stages of `frame`, in recording order, with reasons.
    pub fn plan(&self, frame: &FrameState) -> Plan {
        let mut l = StageLists::default();
        let pend = frame.inputs;
        if pend.upload_bytes > 0 {
            let what = (pend.direct | pend.indirect).describe();
            let what = if what.is_empty() { "live inputs".to_string() } else { what };
            let r = format!("{what} changed: {} B into hfgi's buffers (vkCmdUpdateBuffer)", pend.upload_bytes);
            l.run(Stage::InputsUpdate, r);
        }
        // 1. Heights: pyramid and visibility, only when the heights changed.
        if frame.heights_changed {
            self.new_heights(frame, &mut l);
        } else {
            self.kept_heights(frame, &mut l);
        }
        // 2. Direct shading and 3. the bounces, amortised over static frames (§7).
        let no_indirect = self.no_indirect();
        let (direct, indirect, when) = self.shading(frame, no_indirect.is_none());
        if direct {
            l.run(Stage::ShadeDirect, when.clone());
        } else {
            l.omit(Stage::ShadeDirect, when.clone());
        }
        if self.local_lights == 0 {
            l.omit(Stage::ShadeLocalLights, "no local lights".into());
        } else {
            let (k, a) = (self.local_lights, self.local_light_azimuths);
            let what = format!("{k} local light{} ({a} azimuths each, horizons up to each light)", plural(k));
            if direct {
                l.run(Stage::ShadeLocalLights, format!("{what}: added to the direct light just shaded"));
            } else {
                l.omit(Stage::ShadeLocalLights, format!("{what}: the direct light is kept"));
            }
        }
        let indirect_stages = [
            Stage::RadianceGather(0),
            Stage::RadianceDecimate(0),
            Stage::RadianceSynthesize(0),
            Stage::IndirectScan(0),
            Stage::IndirectShade(0),
        ];
        if let Some(why) = no_indirect {
            for s in indirect_stages {
                l.omit(s, format!("{why}: no indirect light"));
            }
        } else if !indirect {
            let synthesize = self.synthesizes_radiance();
            for s in indirect_stages.into_iter().filter(|s| synthesize || *s != Stage::RadianceSynthesize(0)) {
                l.omit(s, when.clone());
            }
        } else {
            for b in 1..=self.bounces {
                self.bounce(b, &when, &mut l);
            }
        }
        Plan { frame: *frame, stages: l.stages, omitted: l.omitted, passes: self.passes() }
    }

    /// The height stages of a frame whose heights changed (the first frame's too).
    fn new_heights(&self, frame: &FrameState, l: &mut StageLists) {
        let why = if frame.frame_index == 0 {
            "first frame: heights uploaded"
        } else {
            "heights changed since the last frame"
        };
        l.run(Stage::PyramidDecimate, format!("{why}; {} levels (k_v = {})", self.levels, self.level_step));
        match self.mode {
            PyramidMode::Stack => l.run(
                Stage::PyramidSynthesize,
                format!(
                    "stack mode: the {} of {} levels the scans read resampled to planes of at most {}×{}",
                    self.stack_levels, self.levels, self.work.0, self.work.1
                ),
            ),
            PyramidMode::Pyramid => {
                l.omit(Stage::PyramidSynthesize, "pyramid mode: the levels are B-spline filtered on the fly".into())
            }
        }
        if self.no_indirect().is_none() {
            match self.no_max_bound {
                None => {
                    let r = "the visibility and indirect scans stop each ray where nothing farther can \
                             rise above its horizon (level-0 maxima)";
                    l.run(Stage::PyramidMax, r.into());
                }
                Some(why) => l.omit(Stage::PyramidMax, why.into()),
            }
        }
        if self.environment {
            l.run(
                Stage::VisibilityEnvironment,
                format!("environment light is non-zero ({} azimuths); {why}", self.azimuths),
            );
        } else {
            l.omit(Stage::VisibilityEnvironment, "environment light is zero (all SH coefficients 0)".into());
        }
        if self.key_lights > 0 {
            let (k, a) = (self.key_lights, self.key_light_azimuths);
            l.run(Stage::VisibilityKeyLights, format!("{k} key light{} ({a} azimuths each); {why}", plural(k)));
        } else {
            l.omit(Stage::VisibilityKeyLights, "no key lights".into());
        }
        if self.spheres > 0 {
            let (k, b) = (self.spheres, &self.blockers);
            l.run(Stage::VisibilityBlockers, format!("{k} sphere blocker{} ({b}); {why}", plural(k)));
        } else {
            l.omit(Stage::VisibilityBlockers, "no sphere blockers".into());
        }
    }

    /// The height stages of a frame whose heights did not change: kept, but for moved key
    /// lights and sphere blockers.
    fn kept_heights(&self, frame: &FrameState, l: &mut StageLists) {
        let pend = frame.inputs;
        let why = "heights unchanged since the last frame: the pyramid is kept";
        l.omit(Stage::PyramidDecimate, why.into());
        if self.mode == PyramidMode::Stack {
            l.omit(Stage::PyramidSynthesize, why.into());
        }
        if self.no_max_bound.is_none() && self.no_indirect().is_none() {
            l.omit(Stage::PyramidMax, why.into());
        }
        let why = "heights unchanged since the last frame: the visibility is kept";
        if self.environment {
            l.omit(Stage::VisibilityEnvironment, why.into());
        }
        if self.key_lights > 0 && pend.key_lights_moved {
            let r = "key lights moved or resized: their visibility is recomputed (heights unchanged)";
            l.run(Stage::VisibilityKeyLights, r.into());
        } else if self.key_lights > 0 {
            l.omit(Stage::VisibilityKeyLights, why.into());
        }
        if self.spheres > 0 && pend.spheres_moved {
            let r = "sphere blockers moved or resized (or, log_brdf on a glossy surface, the camera or the Phong \
                     exponent changed): their visibility is recomputed (heights unchanged)";
            l.run(Stage::VisibilityBlockers, r.into());
        } else if self.spheres > 0 {
            l.omit(Stage::VisibilityBlockers, why.into());
        }
    }

    /// Whether the bounces synthesize a radiance stack (stack mode, scalar radiance pyramid).
    fn synthesizes_radiance(&self) -> bool {
        !self.vector && self.mode == PyramidMode::Stack
    }

    /// The stages of bounce `b` (of `self.bounces`), which the frame records; `when`: why the
    /// indirect light is shaded this frame.
    fn bounce(&self, b: u32, when: &str, l: &mut StageLists) {
        let n = self.bounces;
        let of = format!("gi.bounces = {n}, bounce {b} of {n}");
        let kind = self.radiance_kind();
        let gather = match (b, self.radiance_on_work) {
            (1, false) => Some(format!("{of}: gathers the direct exit radiance ({when})")),
            (1, true) => Some(format!("{of}: gathers the direct exit radiance, averaged to the working grid ({when})")),
            (_, true) => Some(format!("{of}: averages bounce {}'s exit radiance to the working grid", b - 1)),
            (_, false) => None,
        };
        if let Some(r) = gather {
            l.run(Stage::RadianceGather(b), r);
            l.run(Stage::RadianceDecimate(b), format!("{of}: {kind}"));
        } else {
            let r = format!("{of}: {kind}, from bounce {}'s exit radiance (its shade wrote level 0)", b - 1);
            l.run(Stage::RadianceDecimate(b), r);
        }
        if self.synthesizes_radiance() {
            let r = format!(
                "{of}: stack mode, scalar radiance pyramid: the {} of {} levels the scan reads",
                self.radiance_stack_levels, self.radiance_levels
            );
            l.run(Stage::RadianceSynthesize(b), r);
        } else if b == 1 {
            let why = if self.vector {
                "the glossy vector pyramid is always a true pyramid"
            } else {
                "pyramid mode: the radiance levels are B-spline filtered on the fly"
            };
            l.omit(Stage::RadianceSynthesize(0), why.into());
        }
        let m = if b == 1 { self.azimuths } else { self.azimuths_later };
        let replay = match (self.replay, b) {
            (false, _) => "",
            (true, 1) => "; records the later bounces' casting sets (gi.replay)",
            (true, _) => "; casts the casting sets bounce 1 recorded, without walking (gi.replay)",
        };
        l.run(Stage::IndirectScan(b), format!("{of}: IR vector per receiver ({m} azimuths){replay}"));
        let acc = if b == 1 { "writes the indirect planes" } else { "adds to the indirect planes" };
        l.run(Stage::IndirectShade(b), format!("{of}: {acc}"));
    }

    /// Whether the frame shades the direct light and the indirect light, and why (docs/plan.md
    /// §1): everything after new heights; otherwise what the live inputs left out of date,
    /// amortised (even frames direct, odd frames indirect) when both are.
    fn shading(&self, frame: &FrameState, has_indirect: bool) -> (bool, bool, String) {
        let pend = frame.inputs;
        let (d, i) = (!pend.direct.is_empty(), has_indirect && !pend.indirect.is_empty());
        if frame.heights_changed {
            let r = if has_indirect { "direct and indirect light both shaded" } else { "the direct light is shaded" };
            return (true, true, format!("heights changed: {r}"));
        }
        if !d && !i {
            return (false, false, "nothing changed since the last frame: the shading is kept".into());
        }
        if self.amortize && d && i {
            let what = (pend.direct | pend.indirect).describe();
            return if frame.frame_index % 2 == 1 {
                (false, true, format!("{what} changed; amortised: an odd frame shades the indirect light"))
            } else {
                (true, false, format!("{what} changed; amortised: an even frame shades the direct light"))
            };
        }
        let mut why = Vec::new();
        if d {
            why.push(format!("direct light out of date ({} changed)", pend.direct.describe()));
        }
        if i {
            why.push(format!("indirect light out of date ({} changed)", pend.indirect.describe()));
        }
        (d, i, why.join("; "))
    }
}

/// The stages a frame records and those it leaves out, each with its reason (Plan::stages,
/// Plan::omitted).
#[derive(Default)]
struct StageLists {
    stages: Vec<PlannedStage>,
    omitted: Vec<PlannedStage>,
}

impl StageLists {
    fn run(&mut self, stage: Stage, reason: String) {
        self.stages.push(PlannedStage { stage, name: stage.name(), reason })
    }

    fn omit(&mut self, stage: Stage, reason: String) {
        self.omitted.push(PlannedStage { stage, name: stage.name(), reason })
    }
}
