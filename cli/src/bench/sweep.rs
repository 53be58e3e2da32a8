//! The configurations `hfgi bench` measures for `--sweep knobs`, `ablation` and `presets`.

use hfgi::scene::model::{
    BlockerExp, BlockerKeyLights, BlockerLogCap, BlockerShading, GiSettings, Interpolation, PyramidMode, Quality,
    VisibilityMethod,
};

use super::Content;

/// The configurations: the baseline, then one knob at a time, the four presets, then (full
/// sweep) the m × k grid; swept horizons (`gi.visibility = "sweep"`) unless the field wraps;
/// the local lights' azimuths when the scene has local lights; the sphere blockers' settings
/// when it has spheres.
pub(super) fn configs(base: &GiSettings, quick: bool, base_wraps: bool, content: Content) -> Vec<(String, GiSettings)> {
    let mut c = Configs { base, out: vec![("baseline".to_string(), base.clone())] };
    c.knobs(quick);
    // Swept horizons (docs/direct.md §7), at the default near reach and along it.
    if !base_wraps {
        c.sweep(quick);
    }
    if content.spheres {
        c.blockers();
    }
    if content.local_lights {
        let ks: &[u32] = if quick { &[4] } else { &[2, 4, 8, 16, 32] };
        for &k in ks {
            c.push("local_light_azimuths", &|g| g.local_light_azimuths = k);
        }
    }
    // The presets, marked on the Pareto plot (one group each).
    for q in [Quality::Draft, Quality::Default, Quality::High, Quality::Ultra] {
        c.push(&format!("quality={q}"), &|g| *g = base.with_quality(q));
    }
    if !quick {
        for m in [8, 16, 32, 64, 128] {
            for k in [1, 2, 4, 8] {
                c.push("grid m×k", &|g| {
                    g.azimuths = m;
                    g.level_step = k;
                });
            }
        }
    }
    c.out
}

/// The configurations of [`configs`] as they are listed, around `base`.
struct Configs<'a> {
    base: &'a GiSettings,
    out: Vec<(String, GiSettings)>,
}

impl Configs<'_> {
    /// `base` changed by `f`, under `knob`, unless it is `base` or listed already.
    fn push(&mut self, knob: &str, f: &dyn Fn(&mut GiSettings)) {
        let mut g = self.base.clone();
        f(&mut g);
        if g != *self.base && !self.out.iter().any(|(_, o)| *o == g) {
            self.out.push((knob.to_string(), g));
        }
    }

    /// The scan's and the shading's knobs, one at a time.
    fn knobs(&mut self, quick: bool) {
        let ms: &[u32] = if quick { &[8, 16] } else { &[4, 8, 16, 32, 64, 128] };
        for &m in ms {
            self.push("azimuths", &|g| g.azimuths = m);
        }
        // The later bounces' azimuths (at most m; docs/performance.md §12).
        let later: &[u32] = if quick { &[8] } else { &[4, 8, 16, 32, 64] };
        for &m in later {
            self.push("azimuths_later", &|g| g.azimuths_later = m);
        }
        let ks: &[u32] = if quick { &[2] } else { &[1, 2, 4, 8, 16] };
        for &k in ks {
            self.push("level_step", &|g| g.level_step = k);
        }
        let os: &[u32] = if quick { &[0] } else { &[0, 1, 2, 3, 4, 5, 6, 8] };
        for &o in os {
            self.push("level_offset", &|g| g.level_offset = o);
        }
        if !quick {
            for o in [0, 2, 4, 6] {
                self.push("radiance_level_offset", &|g| g.radiance_level_offset = o);
            }
        }
        for s in [1, 2, 4] {
            self.push("subsample", &|g| g.subsample = s);
        }
        for i in [Interpolation::Linear, Interpolation::Bspline] {
            self.push("interpolation", &|g| g.interpolation = i);
        }
        let ns: &[usize] = if quick { &[3] } else { &[3, 4, 5, 6] };
        for &n in ns {
            self.push("sh_order", &|g| g.sh_order = n);
        }
        for p in [PyramidMode::Stack, PyramidMode::Pyramid] {
            self.push("pyramid", &|g| g.pyramid = p);
        }
        for b in 0..=3 {
            self.push("bounces", &|g| g.bounces = b);
        }
    }

    /// Swept horizons, and their near reach.
    fn sweep(&mut self, quick: bool) {
        self.push("visibility", &|g| g.visibility = VisibilityMethod::Sweep);
        let rs: &[u32] = if quick { &[0] } else { &[0, 4, 8, 32, 64] };
        for &r in rs {
            self.push("sweep_near", &|g| {
                g.visibility = VisibilityMethod::Sweep;
                g.sweep_near = r;
            });
        }
    }

    /// The sphere blockers' settings.
    fn blockers(&mut self) {
        let base = self.base;
        for e in [0.05, 0.1, 0.2, 0.5] {
            self.push("blocker_epsilon", &|g| g.blocker_epsilon = e);
        }
        self.push("blocker_ratio", &|g| g.blocker_ratio = !base.blocker_ratio);
        for x in [BlockerExp::Quadrature, BlockerExp::Linear] {
            self.push("blocker_exp", &|g| g.blocker_exp = x);
        }
        for m in [BlockerShading::Log, BlockerShading::LogField, BlockerShading::LogBrdf, BlockerShading::Primal] {
            self.push("blocker_shading", &|g| g.blocker_shading = m);
        }
        self.push("blocker_log_cap", &|g| g.blocker_log_cap = BlockerLogCap::Matched);
        self.push("blocker_key_lights", &|g| g.blocker_key_lights = BlockerKeyLights::Product);
        for m in [BlockerShading::LogField, BlockerShading::LogBrdf] {
            self.push("blocker_log_cap", &|g| {
                g.blocker_log_cap = BlockerLogCap::Matched;
                g.blocker_shading = m;
            });
        }
    }
}

fn with_preset(scene: &GiSettings, preset: Quality) -> GiSettings {
    scene.with_quality(preset)
}

/// The ablation of docs/accuracy.md §4: the paper, each fix alone on the paper's settings, all
/// fixes (the `default` preset); then the preset ladder.
pub(super) fn ablation(base: &GiSettings, presets_only: bool) -> Vec<(String, GiSettings)> {
    let paper = with_preset(base, Quality::Paper);
    let mut out = vec![("paper".to_string(), paper.clone())];
    if !presets_only {
        let all = with_preset(base, Quality::Default);
        let fix = |name: &str, f: &dyn Fn(&mut GiSettings)| {
            let mut g = paper.clone();
            f(&mut g);
            (name.to_string(), g)
        };
        out.push(fix("level0=bilinear", &|g| g.level0 = all.level0));
        out.push(fix("horizon=samples", &|g| g.horizon = all.horizon));
        out.push(fix(&format!("near_steps={}", all.near_steps), &|g| g.near_steps = all.near_steps));
        out.push(fix("scan_reach=diagonal", &|g| g.scan_reach = all.scan_reach));
        out.push(fix("omega_min=tangent", &|g| g.omega_min = all.omega_min));
        out.push(fix("elevation_basis=legendre", &|g| g.elevation_basis = all.elevation_basis));
    }
    for q in [Quality::Draft, Quality::Default, Quality::High, Quality::Ultra] {
        out.push((format!("quality={q}"), with_preset(base, q)));
    }
    out
}
