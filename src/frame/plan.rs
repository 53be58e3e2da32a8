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
mod planner;

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
}

fn plural(n: usize) -> &'static str {
    if n == 1 {
        ""
    } else {
        "s"
    }
}
