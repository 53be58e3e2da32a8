//! The stage table (docs/plan.md §1): every stage hfgi records, with its name (the scope name
//! of `Recorder::stages`, the timestamp scope and the debug label), the pass that records it
//! and the rule that decides when. One table: the planner plans [`Stage`]s and names them from
//! it, `Renderer::record` records each under [`Stage::name`] (a debug assertion compares the
//! recorded names with the plan), `hfgi plan --stages` prints [`STAGES`], and each pass's
//! `STAGE_*` constant is its row's name.

/// One row of the stage table.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct StageInfo {
    pub name: &'static str,
    /// The pass (or call) that records it.
    pub pass: &'static str,
    /// When it is recorded.
    pub rule: &'static str,
    /// Planned by [`crate::frame::Planner`] and recorded by `Renderer::record` (else the host
    /// records it with its own call).
    pub planned: bool,
}

const fn row(name: &'static str, pass: &'static str, rule: &'static str, planned: bool) -> StageInfo {
    StageInfo { name, pass, rule, planned }
}

/// Every stage, the planned ones first in recording order.
pub const STAGES: &[StageInfo] = &[
    row(
        "inputs.update",
        "Renderer (live inputs)",
        "a set_* call changed one of hfgi's buffers: vkCmdUpdateBuffer between two barriers",
        true,
    ),
    row("pyramid.decimate", "HeightPyramid", "the heights changed (always on the first frame)", true),
    row("pyramid.synthesize", "HeightPyramid", "the heights changed, gi.pyramid = \"stack\"", true),
    row(
        "pyramid.max",
        "MaxPyramid (IndirectPass)",
        "the heights changed; indirect light with radial probes, a bilinear level 0, no wrap",
        true,
    ),
    row("visibility.environment", "VisibilityPass", "the heights changed, and the environment is non-zero", true),
    row(
        "visibility.key_lights",
        "VisibilityPass",
        "key lights, and the heights changed or a key light moved or changed size",
        true,
    ),
    row(
        "visibility.blockers",
        "BlockerPass",
        "sphere blockers, and the heights changed or a sphere moved (set_spheres)",
        true,
    ),
    row(
        "shade.direct",
        "ShadePass",
        "the heights changed, or the direct light is out of date (amortised: an even frame when both halves are)",
        true,
    ),
    row(
        "shade.local_lights",
        "LocalLightPass",
        "local lights, right after every shade.direct (adds their diffuse light to the direct planes it wrote)",
        true,
    ),
    row(
        "radiance.gather",
        "RadiancePyramid (IndirectPass)",
        "as radiance.decimate, for bounce 1 only (the indirect shade of bounce b writes bounce b + 1's level 0), or every bounce when sub-sampled (level 0 is the working grid)",
        true,
    ),
    row(
        "radiance.decimate",
        "RadiancePyramid (IndirectPass)",
        "per bounce: indirect light, and the heights changed or the indirect light is out of date (amortised: an \
         odd frame when both halves are)",
        true,
    ),
    row(
        "radiance.synthesize",
        "RadiancePyramid (IndirectPass)",
        "as radiance.decimate, with the scalar pyramid in stack mode",
        true,
    ),
    row("indirect.scan", "IndirectPass", "as radiance.decimate", true),
    row("indirect.shade", "IndirectPass", "as radiance.decimate", true),
    row("heights.copy", "Renderer::record_heights_from_image", "the host's call, before Renderer::record", false),
    row("heights.upload", "Renderer::record_heights_upload", "the host's call, before Renderer::record", false),
    row("water.step", "WaterSim::record_step", "the host's call, before Renderer::record", false),
    row("view.raster", "ViewPass::record", "the host's call, after Renderer::record", false),
    row("shade.readback", "Renderer::record_read_layers", "the host's call, after Renderer::record", false),
    row("reference.truth", "frame::truth (hfgi reference)", "the ground truth; not part of a frame", false),
];

/// The row named `name` (`const`: the passes' `STAGE_*` constants come from it).
const fn index_of(name: &str) -> usize {
    let mut i = 0;
    while i < STAGES.len() {
        if eq(STAGES[i].name, name) {
            return i;
        }
        i += 1;
    }
    panic!("no such stage in STAGES");
}

const fn eq(a: &str, b: &str) -> bool {
    let (a, b) = (a.as_bytes(), b.as_bytes());
    if a.len() != b.len() {
        return false;
    }
    let mut i = 0;
    while i < a.len() {
        if a[i] != b[i] {
            return false;
        }
        i += 1;
    }
    true
}

/// The name of the row `name`, checked at compile time (a typo does not build).
pub const fn stage_name(name: &'static str) -> &'static str {
    STAGES[index_of(name)].name
}

/// Stage name of the live inputs' buffer updates ([`Stage::InputsUpdate`]).
pub const STAGE_INPUTS: &str = stage_name("inputs.update");

/// One planned stage of a frame; the indirect stages carry their bounce (1-based).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Stage {
    /// `vkCmdUpdateBuffer` of the live inputs' new data (lights, material) into hfgi's buffers.
    InputsUpdate,
    PyramidDecimate,
    PyramidSynthesize,
    PyramidMax,
    VisibilityEnvironment,
    VisibilityKeyLights,
    /// The sphere blockers' log-SH visibility, exponentiated.
    VisibilityBlockers,
    ShadeDirect,
    /// The local lights' diffuse light, added to what `ShadeDirect` wrote.
    ShadeLocalLights,
    RadianceGather(u32),
    RadianceDecimate(u32),
    RadianceSynthesize(u32),
    IndirectScan(u32),
    IndirectShade(u32),
}

impl Stage {
    /// Its row of [`STAGES`] (the planned rows, in order).
    pub const fn info(self) -> &'static StageInfo {
        &STAGES[match self {
            Stage::InputsUpdate => 0,
            Stage::PyramidDecimate => 1,
            Stage::PyramidSynthesize => 2,
            Stage::PyramidMax => 3,
            Stage::VisibilityEnvironment => 4,
            Stage::VisibilityKeyLights => 5,
            Stage::VisibilityBlockers => 6,
            Stage::ShadeDirect => 7,
            Stage::ShadeLocalLights => 8,
            Stage::RadianceGather(_) => 9,
            Stage::RadianceDecimate(_) => 10,
            Stage::RadianceSynthesize(_) => 11,
            Stage::IndirectScan(_) => 12,
            Stage::IndirectShade(_) => 13,
        }]
    }

    /// The scope name the stage records (timestamps, debug labels, `Recorder::stages`).
    pub const fn name(self) -> &'static str {
        self.info().name
    }
}

/// The table as text, one row per line (`hfgi plan --stages`).
pub fn table_text() -> String {
    let mut s = String::from("stages (src/frame/stages.rs; planned ones in recording order):\n");
    for r in STAGES {
        let kind = if r.planned { "planned" } else { "host call" };
        s += &format!("  {:<24} {:<10} {:<36} {}\n", r.name, kind, r.pass, r.rule);
    }
    s
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_planned_variant_has_its_own_planned_row() {
        let all = [
            Stage::InputsUpdate,
            Stage::PyramidDecimate,
            Stage::PyramidSynthesize,
            Stage::PyramidMax,
            Stage::VisibilityEnvironment,
            Stage::VisibilityKeyLights,
            Stage::VisibilityBlockers,
            Stage::ShadeDirect,
            Stage::ShadeLocalLights,
            Stage::RadianceGather(1),
            Stage::RadianceDecimate(1),
            Stage::RadianceSynthesize(1),
            Stage::IndirectScan(1),
            Stage::IndirectShade(1),
        ];
        let planned: Vec<&str> = STAGES.iter().filter(|r| r.planned).map(|r| r.name).collect();
        assert_eq!(all.map(Stage::name).to_vec(), planned);
        let mut names: Vec<&str> = STAGES.iter().map(|r| r.name).collect();
        names.sort_unstable();
        names.dedup();
        assert_eq!(names.len(), STAGES.len(), "stage names are unique");
    }
}
