//! The passes part of the plan: which passes `Renderer::new` creates, and why (`hfgi plan`'s
//! first section).

use super::{plural, PlannedPass, Planner};
use crate::scene::model::{GlossyPyramid, PyramidMode};

impl Planner {
    pub(super) fn radiance_kind(&self) -> String {
        if self.vector {
            format!(
                "glossy SH vector pyramid, {} channels (glossy material, gi.glossy_pyramid = \"vector\")",
                self.channels
            )
        } else {
            let why = if self.glossy_pyramid == GlossyPyramid::Vector {
                " (gi.glossy_pyramid = \"vector\" asked for, but the material has no specular lobe)"
            } else {
                ""
            };
            format!("scalar RGB pyramid, 3 channels{why}, {} mode", self.mode)
        }
    }

    /// The passes `Renderer::new` creates (and the ones it does not), with reasons.
    pub fn passes(&self) -> Vec<PlannedPass> {
        let mut passes = self.direct_passes();
        passes.extend(self.indirect_passes());
        passes
    }

    /// The height pyramid, the visibility and the shading, and the optional direct passes.
    fn direct_passes(&self) -> Vec<PlannedPass> {
        let (w, h) = self.size;
        let (ww, wh) = self.work;
        let storage = match self.mode {
            PyramidMode::Stack => {
                let how = "the working grid halved while it keeps each level's texels";
                format!(
                    "stack mode: {} planes of at most {ww}×{wh} (the levels the scans read; {how})",
                    self.stack_levels
                )
            }
            PyramidMode::Pyramid => "pyramid mode: decimated levels only".into(),
        };
        let mut sets = Vec::new();
        if self.environment {
            sets.push("environment".to_string());
        }
        if self.key_lights > 0 {
            sets.push(format!("{} key light{}", self.key_lights, plural(self.key_lights)));
        }
        let sets = if sets.is_empty() { "no environment or key light".into() } else { sets.join(", ") };
        vec![
            PlannedPass {
                name: "HeightPyramid",
                created: true,
                reason: format!(
                    "always: {w}×{h} heights, {} levels (k_v = {}), {storage}",
                    self.levels, self.level_step
                ),
            },
            PlannedPass {
                name: "VisibilityPass",
                created: true,
                reason: format!(
                    "always: {} light set{} ({sets})",
                    self.light_sets(),
                    plural(self.light_sets() as usize)
                ),
            },
            PlannedPass {
                name: "ShadePass",
                created: true,
                reason: if self.glossy_planes {
                    "always: the shading texture (total, direct, indirect, glossy and 2 internal glossy planes)".into()
                } else {
                    "always: the shading texture (total, direct, indirect; no glossy planes: no specular colour)".into()
                },
            },
            PlannedPass {
                name: "BlockerPass",
                created: self.spheres > 0,
                reason: if self.spheres > 0 {
                    format!("{} sphere blocker{} ({})", self.spheres, plural(self.spheres), self.blockers)
                } else {
                    "no sphere blockers".into()
                },
            },
            PlannedPass {
                name: "LocalLightPass",
                created: self.local_lights > 0,
                reason: if self.local_lights > 0 {
                    format!(
                        "{} local light{}: horizons marched up to each light, {} azimuths per light and texel",
                        self.local_lights,
                        plural(self.local_lights),
                        self.local_light_azimuths
                    )
                } else {
                    "no local lights".into()
                },
            },
        ]
    }

    /// The indirect pass and the pyramids it owns, or why there are none.
    fn indirect_passes(&self) -> Vec<PlannedPass> {
        let mut passes = Vec::new();
        match self.no_indirect() {
            Some(why) => {
                passes.push(PlannedPass { name: "IndirectPass", created: false, reason: why.clone() });
                passes.push(PlannedPass { name: "RadiancePyramid", created: false, reason: "no IndirectPass".into() });
            }
            None => {
                let reflects = match (self.albedo, self.specular) {
                    (true, true) => "albedo and specular non-zero",
                    (true, false) => "albedo non-zero",
                    _ => "specular non-zero",
                };
                passes.push(PlannedPass {
                    name: "IndirectPass",
                    created: true,
                    reason: format!("gi.bounces = {} and the surface reflects light ({reflects})", self.bounces),
                });
                passes.push(PlannedPass {
                    name: "MaxPyramid",
                    created: self.no_max_bound.is_none(),
                    reason: match self.no_max_bound {
                        None => "part of IndirectPass: level-0 maxima; their top stops the scans' rays early".into(),
                        Some(why) => why.into(),
                    },
                });
                passes.push(PlannedPass {
                    name: "RadiancePyramid",
                    created: true,
                    reason: format!(
                        "part of IndirectPass: {}{}, {} levels (k_u = {}){}",
                        self.radiance_kind(),
                        if self.vector { ", always a true pyramid" } else { "" },
                        self.radiance_levels,
                        self.radiance_level_step,
                        if !self.vector && self.mode == PyramidMode::Stack {
                            let shared = if self.shared_levels {
                                "; its levels kept in hfgi.pyramid.levels after level 0 (docs/pyramid.md, \
                                 \"Shared levels\")"
                            } else {
                                ""
                            };
                            format!(", a stack of the {} the scan reads{shared}", self.radiance_stack_levels)
                        } else {
                            String::new()
                        }
                    ),
                });
            }
        }
        passes
    }

    pub(super) fn light_sets(&self) -> u32 {
        self.environment as u32 + self.key_lights as u32
    }
}
