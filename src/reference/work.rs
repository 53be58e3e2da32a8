//! What the ground truth would cost, checked before any of it is done (docs/robustness.md,
//! "Bounded inputs and work"): `hfgi reference --march --step 1e-9` would march 10²¹ samples
//! and never finish, printing nothing.

use super::truth::TruthSettings;
use crate::error::{Error, Result};
use crate::scene::model::Scene;

/// Most ray steps (cells crossed, or march samples) one reference run may take: about eight
/// hours at the ~30 ns per step measured on lavapipe (2 CPU cores: a 128² exact reference,
/// 256 azimuths, 2 bounces, 6·10⁹ steps in 100–170 s), minutes on a GPU.
pub const MAX_RAY_STEPS: f64 = 1e12;

/// Nanoseconds per ray step on lavapipe, for the time estimate in messages.
const LAVAPIPE_NS_PER_STEP: f64 = 30.0;

/// The reference's work, as the count of ray steps and its factors.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct TruthWork {
    /// Receivers (every texel).
    pub receivers: f64,
    /// Rays per receiver and pass: the uniform azimuths plus each key light's cap azimuths
    /// plus, per local light, `max(azimuths, cap_nodes)` (its cap's samples: `cap_nodes`, or
    /// the uniform azimuths where it holds a pole; both variants) plus, per sphere blocker, as
    /// many (its cap's samples, a ray each, in the direct pass of both variants).
    pub rays: f64,
    /// Passes: the direct light and each bounce.
    pub passes: f64,
    /// Steps along one ray: cells crossed (exact) or march samples.
    pub steps_per_ray: f64,
}

impl TruthWork {
    /// Total ray steps.
    pub fn steps(&self) -> f64 {
        self.receivers * self.rays * self.passes * self.steps_per_ray
    }
}

impl TruthSettings {
    /// An upper estimate of the work of [`super::truth::render_truth`] (and the GPU version) on
    /// `scene`. A ray runs at most the field's diagonal (`max(W, H)` with `wrap`); exactly it
    /// crosses at most `|d_x| + |d_y| ≤ √2` cells per texel of travel, marched it takes one
    /// sample per `step` texels.
    pub fn work(&self, scene: &Scene) -> TruthWork {
        let (w, h) = (scene.field.width() as f64, scene.field.height() as f64);
        let reach = if scene.wrap { w.max(h) } else { w.hypot(h) };
        let steps_per_ray = if self.march { reach / self.step } else { reach * std::f64::consts::SQRT_2 };
        let caps = if self.sh_visibility { 0.0 } else { scene.key_lights.len() as f64 * f64::from(self.cap_nodes) };
        let per_cap = f64::from(self.azimuths.max(self.cap_nodes));
        let locals = scene.local_lights.len() as f64 * per_cap;
        let spheres = scene.spheres.len() as f64 * per_cap;
        TruthWork {
            receivers: w * h,
            rays: f64::from(self.azimuths) + caps + locals + spheres,
            passes: 1.0 + f64::from(scene.gi.bounces),
            steps_per_ray,
        }
    }

    /// Rejects settings whose [`TruthSettings::work`] exceeds [`MAX_RAY_STEPS`], saying what
    /// they would cost and how to proceed.
    pub fn check_work(&self, scene: &Scene) -> Result<()> {
        let work = self.work(scene);
        let steps = work.steps();
        if steps <= MAX_RAY_STEPS {
            return Ok(());
        }
        let seconds = steps * LAVAPIPE_NS_PER_STEP * 1e-9;
        let how = if self.march {
            "use a larger --step (the default is 0.125 texel) or the exact intersection (no --march)"
        } else {
            "use fewer --azimuths or --cap-nodes, fewer bounces, or a smaller field"
        };
        Err(Error::param(
            "reference work",
            format!(
                "{steps:.1e} ray steps ({:.0} receivers × {:.0} rays × {:.0} passes × {:.3e} steps per ray)",
                work.receivers, work.rays, work.passes, work.steps_per_ray
            ),
            format!(
                "at most {MAX_RAY_STEPS:.0e} (this would take about {} on lavapipe at ~{LAVAPIPE_NS_PER_STEP:.0} ns \
                 per step); {how}",
                human_duration(seconds)
            ),
        ))
    }
}

/// An order-of-magnitude duration: seconds, minutes, hours, days or years.
pub fn human_duration(seconds: f64) -> String {
    const UNITS: [(f64, &str); 5] =
        [(365.25 * 86400.0, "years"), (86400.0, "days"), (3600.0, "hours"), (60.0, "minutes"), (1.0, "seconds")];
    for (unit, name) in UNITS {
        if seconds >= unit {
            let v = seconds / unit;
            return if v >= 1e4 { format!("{v:.0e} {name}") } else { format!("{v:.0} {name}") };
        }
    }
    format!("{seconds:.1} seconds")
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_tiny_march_step_is_rejected_with_its_cost() {
        let scene = crate::scene::file::parse_scene(
            "",
            std::path::Path::new("."),
            "t",
            &["heightfield.size=128".into(), "gi.bounces=2".into()],
        )
        .unwrap();
        let tiny = TruthSettings { march: true, step: 1e-9, ..TruthSettings::default() };
        let msg = tiny.check_work(&scene).unwrap_err().to_string();
        assert!(msg.contains("ray steps") && msg.contains("years") && msg.contains("--step"), "{msg}");
        assert!(msg.len() < 600, "{msg}");
        // The defaults at 128² pass, with and without the march.
        TruthSettings::default().check_work(&scene).unwrap();
        TruthSettings { march: true, ..TruthSettings::default() }.check_work(&scene).unwrap();
        // Too many azimuths on a large field: rejected, naming what to lower.
        let big = crate::scene::file::parse_scene(
            "",
            std::path::Path::new("."),
            "t",
            &["heightfield.size=1024".into(), "gi.bounces=16".into()],
        )
        .unwrap();
        let wide = TruthSettings { azimuths: 4096, ..TruthSettings::default() };
        let msg = wide.check_work(&big).unwrap_err().to_string();
        assert!(msg.contains("--azimuths"), "{msg}");
    }

    #[test]
    fn local_lights_count_in_the_work() {
        let mut scene = crate::scene::file::parse_scene(
            "[[local_light]]\nposition = [4.0, 4.0, 3.0]\n",
            std::path::Path::new("."),
            "t",
            &["heightfield.size=32".into()],
        )
        .unwrap();
        let settings = TruthSettings::default();
        let shv = TruthSettings { sh_visibility: true, ..settings };
        let (with, with_shv) = (settings.work(&scene).rays, shv.work(&scene).rays);
        scene.local_lights.clear();
        // max(256 azimuths, 64 cap nodes) per local light, in both variants.
        assert_eq!(with - settings.work(&scene).rays, 256.0);
        assert_eq!(with_shv - shv.work(&scene).rays, 256.0);
    }

    #[test]
    fn spheres_count_in_the_work() {
        let mut scene = crate::scene::file::parse_scene(
            "[[sphere]]\ncenter = [4.0, 4.0, 3.0]\nradius = 1.0\n[[sphere]]\ncenter = [9.0, 4.0, 3.0]\nradius = 2.0\n",
            std::path::Path::new("."),
            "t",
            &["heightfield.size=32".into()],
        )
        .unwrap();
        let settings = TruthSettings::default();
        let with = settings.work(&scene).rays;
        scene.spheres.clear();
        // max(256 azimuths, 64 cap nodes) per sphere.
        assert_eq!(with - settings.work(&scene).rays, 512.0);
    }

    #[test]
    fn durations_are_orders_of_magnitude() {
        assert_eq!(human_duration(30.0), "30 seconds");
        assert_eq!(human_duration(7200.0), "2 hours");
        assert!(human_duration(1e13).ends_with("years"));
    }
}
