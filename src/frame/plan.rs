//! The frame plan: which passes a scene needs and which stages a frame records, each with the
//! reason it is there (docs/plan.md). Pure: no Vulkan, so `hfgi plan` runs without a device.
//!
//! [`crate::frame::Renderer::new`] creates the passes [`Plan::passes`] lists as created, and
//! [`crate::frame::Renderer::record`] computes the plan of the frame and records exactly its
//! [`Plan::stages`], in order; [`crate::frame::Renderer::plan_next`] returns that plan before
//! recording. The rules (docs/plan.md §1):
//!
//! - heights changed since the last frame (always on the first): `pyramid.decimate`, in stack
//!   mode `pyramid.synthesize`, `pyramid.max` when the indirect scan bounds its rays with it
//!   (indirect light with radial probes, `gi.level0 = "bilinear"`, no wrap), then the
//!   visibility; unchanged
//!   heights keep all of them;
//! - `visibility.environment` only with a non-zero environment (some SH coefficient ≠ 0),
//!   `visibility.key_lights` only with key lights;
//! - `shade.direct`, then per bounce `b = 1..B`: `radiance.gather` (bounce 1 only: the shade
//!   of bounce `b − 1` writes the next bounce's level 0; every bounce when a sub-sampled scalar
//!   pyramid starts at the working grid, docs/indirect.md §1), `radiance.decimate`,
//!   `radiance.synthesize` (stack mode and scalar radiance pyramid only), `indirect.scan`,
//!   `indirect.shade` — the indirect stages only with `gi.bounces > 0` and a surface that
//!   reflects light (albedo or specular non-zero);
//! - live inputs (`Renderer::set_environment`, `set_key_lights`, `set_material`,
//!   `set_camera`; docs/integration.md §2): `inputs.update` first when a buffer must change;
//!   moved or resized key lights re-run `visibility.key_lights` (never the pyramid or the
//!   environment's visibility); the shading they leave out of date is re-shaded, and a frame
//!   with nothing out of date records nothing;
//! - amortisation (docs/indirect.md §5): with `gi.amortize` and unchanged heights, when both
//!   the direct and the indirect light are out of date, even frames record only `shade.direct`,
//!   odd frames only the indirect stages.

use std::fmt;

use super::pyramid::PyramidLayout;
use super::pyramid_max::why_no_max_bound;
use super::renderer::{needs_indirect, vector_pyramid};
use super::visibility::has_environment;
use crate::scene::model::{Albedo, GlossyPyramid, PyramidMode, Scene};

pub use super::stages::{Stage, StageInfo, STAGES, STAGE_INPUTS};

mod passes;

/// What the planner needs to know about the frame about to be recorded.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct FrameState {
    /// The heights changed since the last recorded frame (true for the first frame).
    pub heights_changed: bool,
    /// Frames recorded before this one (0 for the first).
    pub frame_index: u64,
    /// Live inputs changed since they were last used, and the shading they left out of date.
    pub inputs: Pending,
}

impl FrameState {
    /// The first frame of a renderer: heights just uploaded.
    pub fn first() -> Self {
        Self { heights_changed: true, ..Self::default() }
    }

    /// Frame `frame_index` of a static scene (the first frame has new heights; nothing else
    /// changes, so later frames record nothing).
    pub fn static_scene(frame_index: u64) -> Self {
        Self { heights_changed: frame_index == 0, frame_index, ..Self::default() }
    }
}

/// Which live inputs changed (bits; the reasons of a plan name them).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct Changes(pub u8);

impl Changes {
    pub const NONE: Changes = Changes(0);
    pub const ENVIRONMENT: Changes = Changes(1);
    pub const KEY_LIGHTS: Changes = Changes(2);
    pub const MATERIAL: Changes = Changes(4);
    pub const CAMERA: Changes = Changes(8);
    /// The direct light that the indirect bounces read was re-shaded after them (amortisation).
    pub const DIRECT_LIGHT: Changes = Changes(16);
    pub const LOCAL_LIGHTS: Changes = Changes(32);
    pub const SPHERES: Changes = Changes(64);
    const NAMES: [&'static str; 7] =
        ["environment", "key lights", "material", "camera", "the direct light it reads", "local lights", "spheres"];

    pub fn is_empty(self) -> bool {
        self.0 == 0
    }

    pub fn contains(self, other: Changes) -> bool {
        self.0 & other.0 == other.0
    }

    /// The changed inputs, comma-separated (`"environment, camera"`).
    pub fn describe(self) -> String {
        let names = Self::NAMES.iter().enumerate().filter(|(i, _)| self.0 & (1 << i) != 0);
        names.map(|(_, n)| *n).collect::<Vec<_>>().join(", ")
    }
}

impl std::ops::BitOr for Changes {
    type Output = Changes;
    fn bitor(self, o: Changes) -> Changes {
        Changes(self.0 | o.0)
    }
}

impl std::ops::BitOrAssign for Changes {
    fn bitor_assign(&mut self, o: Changes) {
        self.0 |= o.0;
    }
}

/// The live inputs' work a frame has to do ([`crate::frame::Renderer`] keeps it between
/// frames; docs/plan.md §1).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct Pending {
    /// Bytes `inputs.update` copies into hfgi's buffers (0: no such stage).
    pub upload_bytes: u64,
    /// Key lights moved or resized since their visibility was computed.
    pub key_lights_moved: bool,
    /// Sphere blockers moved or resized since their visibility was computed.
    pub spheres_moved: bool,
    /// Why the direct shading is out of date (empty: up to date).
    pub direct: Changes,
    /// Why the indirect shading is out of date (empty: up to date).
    pub indirect: Changes,
}

/// A stage the frame records, or one it leaves out, with the reason.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct PlannedStage {
    pub stage: Stage,
    pub name: &'static str,
    pub reason: String,
}

/// A pass of [`crate::frame::Renderer`]: whether `Renderer::new` creates it, and why.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct PlannedPass {
    pub name: &'static str,
    pub created: bool,
    pub reason: String,
}

/// The plan of one frame.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Plan {
    pub frame: FrameState,
    /// The stages the frame records, in order.
    pub stages: Vec<PlannedStage>,
    /// Stages the frame leaves out, with the reason (the bounce of an indirect stage is 0).
    pub omitted: Vec<PlannedStage>,
    passes: Vec<PlannedPass>,
}

impl Plan {
    /// The recorded stage names, in order (what `Recorder::stages` returns for the frame).
    pub fn names(&self) -> Vec<&'static str> {
        self.stages.iter().map(|s| s.name).collect()
    }

    /// The passes of the scene (frame-independent): which ones `Renderer::new` creates, and why.
    pub fn passes(&self) -> &[PlannedPass] {
        &self.passes
    }

    /// Whether the frame rebuilds the height pyramid.
    pub fn rebuilds_pyramid(&self) -> bool {
        self.stages.iter().any(|s| s.stage == Stage::PyramidDecimate)
    }

    /// The passes as text, one per line (the first part of `hfgi plan`).
    pub fn passes_text(&self) -> String {
        let mut s = String::from("passes (Renderer::new):\n");
        for p in &self.passes {
            let mark = if p.created { "created" } else { "not created" };
            s += &format!("  {:<16} {:<12} {}\n", p.name, mark, p.reason);
        }
        s
    }
}

impl fmt::Display for Plan {
    /// The frame's stages with their reasons, then the stages it leaves out.
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let state = if self.frame.heights_changed { "heights changed" } else { "heights unchanged" };
        let n = self.stages.len();
        writeln!(f, "frame {} ({state}): {n} stage{}", self.frame.frame_index, plural(n))?;
        for (i, s) in self.stages.iter().enumerate() {
            writeln!(f, "  {:>2}. {:<24} {}", i + 1, s.name, s.reason)?;
        }
        for s in &self.omitted {
            writeln!(f, "   -  {:<24} not recorded: {}", s.name, s.reason)?;
        }
        Ok(())
    }
}

/// What the plan depends on, taken from the scene once ([`crate::frame::Renderer`] keeps it).
#[derive(Clone, Debug, PartialEq)]
pub struct Planner {
    size: (usize, usize),
    work: (usize, usize),
    mode: PyramidMode,
    level_step: u32,
    levels: usize,
    /// Stack planes the renderer keeps (the levels the scans read; docs/pyramid.md).
    stack_levels: usize,
    radiance_level_step: u32,
    radiance_levels: usize,
    radiance_stack_levels: usize,
    environment: bool,
    azimuths: u32,
    /// The indirect scans' azimuths of bounces 2 and later (`gi.azimuths_later`, at most m).
    azimuths_later: u32,
    /// Whether the later bounces cast the casting sets bounce 1 recorded
    /// ([`crate::rules::scene::replays`]).
    replay: bool,
    key_lights: usize,
    key_light_azimuths: u32,
    local_lights: usize,
    local_light_azimuths: u32,
    spheres: usize,
    blockers: String,
    bounces: u32,
    albedo: bool,
    specular: bool,
    /// Whether the shading buffer has the glossy planes (`shade::glossy_planes`).
    glossy_planes: bool,
    indirect: bool,
    glossy_pyramid: GlossyPyramid,
    vector: bool,
    channels: u32,
    amortize: bool,
    /// Why the indirect scan does not read the max pyramid (`None`: it does; with indirect
    /// light only).
    no_max_bound: Option<&'static str>,
    /// The radiance pyramid's level 0 is the working grid ([`crate::rules::scene::radiance_base`]):
    /// every bounce gathers.
    radiance_on_work: bool,
    /// The radiance levels live in the height levels buffer (`radiance::shares_height_levels`).
    shared_levels: bool,
}

/// The plan of `frame` for `scene` (`Planner::new(scene).plan(frame)`).
pub fn plan(scene: &Scene, frame: &FrameState) -> Plan {
    Planner::new(scene).plan(frame)
}

impl Planner {
    pub fn new(scene: &Scene) -> Self {
        let gi = &scene.gi;
        let size = (scene.field.width(), scene.field.height());
        let count = |k| PyramidLayout::new(size.0, size.1, k).map_or(0, |l| l.count());
        let m = &scene.material;
        let albedo = match &m.albedo {
            Albedo::Constant(a) => a.iter().any(|v| *v != 0.0),
            Albedo::Map(map) => map.iter().any(|a| a.iter().any(|v| *v != 0.0)),
        };
        let n2 = (gi.sh_order * gi.sh_order) as u32;
        let vector = vector_pyramid(scene);
        let levels = count(gi.level_step);
        let ladder = crate::reference::direct::scan_steps(gi, levels);
        let radiance_stack =
            super::indirect::radiance_levels(scene, &ladder).map_or(0, |l| super::indirect::radiance_stack_levels(&l));
        let base = crate::rules::scene::radiance_base(scene);
        Self {
            size,
            work: gi.working_size(size.0, size.1),
            mode: gi.pyramid,
            level_step: gi.level_step,
            levels,
            stack_levels: super::pyramid::height_stack_levels(gi, levels),
            radiance_level_step: gi.radiance_level_step,
            radiance_levels: PyramidLayout::new(base.0, base.1, gi.radiance_level_step).map_or(0, |l| l.count()),
            radiance_on_work: base != size,
            radiance_stack_levels: radiance_stack,
            environment: has_environment(scene),
            azimuths: gi.azimuths,
            azimuths_later: gi.scan_azimuths(2),
            replay: crate::rules::scene::replays(scene, gi.working_size(size.0, size.1), ladder.len()),
            key_lights: scene.key_lights.len(),
            key_light_azimuths: gi.key_light_azimuths,
            local_lights: scene.local_lights.len(),
            local_light_azimuths: gi.local_light_azimuths,
            spheres: scene.spheres.len(),
            blockers: if gi.blocker_shading == crate::scene::model::BlockerShading::Primal {
                "primal: SH products of exact caps".to_string()
            } else if gi.blocker_log_cap == crate::scene::model::BlockerLogCap::Matched {
                format!("{}: moment-matched log-ZH, {} exponentiation", gi.blocker_shading, gi.blocker_exp)
            } else {
                format!(
                    "{}: ε = {}, {} exponentiation{}",
                    gi.blocker_shading,
                    gi.blocker_epsilon,
                    gi.blocker_exp,
                    if gi.blocker_ratio { ", ratio attenuation" } else { "" }
                )
            },
            bounces: gi.bounces,
            albedo,
            specular: m.specular.is_some_and(|k| k.iter().any(|v| *v != 0.0)),
            glossy_planes: super::shade::glossy_planes(scene),
            indirect: needs_indirect(scene),
            glossy_pyramid: gi.glossy_pyramid,
            vector,
            channels: if vector { 3 + 3 * n2 } else { 3 },
            amortize: gi.amortize,
            no_max_bound: why_no_max_bound(scene),
            shared_levels: super::radiance::shares_height_levels(scene),
        }
    }

    /// Whether `Renderer::new` creates the `IndirectPass` (and its radiance pyramid).
    pub fn creates_indirect(&self) -> bool {
        self.indirect
    }

    /// Indirect bounces each indirect frame records.
    pub fn bounces(&self) -> u32 {
        self.bounces
    }

    /// Why there is no indirect light, if there is none.
    fn no_indirect(&self) -> Option<String> {
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
                    let r = "the indirect scan stops each ray where nothing farther can rise above \
                             its horizon (level-0 maxima)";
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

fn plural(n: usize) -> &'static str {
    if n == 1 {
        ""
    } else {
        "s"
    }
}
