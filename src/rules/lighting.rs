//! Light sets and their SH lighting (docs/direct.md §4–5): which sets a scene has, their
//! azimuth samples, and the lighting each set's visibility is shaded with. The visibility and
//! shading passes and the CPU twins (`reference::direct`) both follow these.

use std::f64::consts::PI;

use crate::math::azimuth::{self, AzimuthSet};
use crate::scene::model::{GiSettings, Scene};

/// Which light a set of azimuth samples belongs to.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum SetKind {
    Environment,
    KeyLight(usize),
}

/// Whether the scene has an environment light (some SH coefficient is non-zero).
pub fn has_environment(scene: &Scene) -> bool {
    scene.environment.sh.iter().any(|c| c.iter().any(|v| *v != 0.0))
}

/// The environment's azimuth set with `m` samples as `gi` turns it (`gi.azimuth_offset`): the
/// set of the environment's visibility (`m = gi.azimuths`) and of every indirect scan
/// (`gi.scan_azimuths(b)`), on the GPU and in the twins alike (docs/direct.md §4).
pub fn environment_set(gi: &GiSettings, m: u32) -> AzimuthSet {
    azimuth::environment_set(m as usize, gi.azimuth_offset, gi.interpolation)
}

/// The light sets of a scene with their azimuth samples (docs/direct.md §4).
pub fn light_sets(scene: &Scene) -> Vec<(SetKind, AzimuthSet)> {
    light_sets_with(scene, has_environment(scene))
}

/// [`light_sets`] with the environment set present or not as `environment` says (a renderer
/// keeps the sets it was created with while its lights change: `Renderer::set_environment`).
pub fn light_sets_with(scene: &Scene, environment: bool) -> Vec<(SetKind, AzimuthSet)> {
    let gi = &scene.gi;
    let mut sets = Vec::new();
    if environment {
        sets.push((SetKind::Environment, environment_set(gi, gi.azimuths)));
    }
    for (i, l) in scene.key_lights.iter().enumerate() {
        sets.push((SetKind::KeyLight(i), azimuth::key_light_set(l, gi.key_light_azimuths as usize, gi.interpolation)));
    }
    sets
}

/// SH lighting of one light set, `n²` RGB coefficients (docs/direct.md §5): the environment's
/// coefficients, or a key light's power spread uniformly over its azimuth/elevation window.
pub fn set_lighting(scene: &Scene, kind: SetKind, set: &AzimuthSet) -> Vec<[f64; 3]> {
    let n = scene.gi.sh_order;
    match kind {
        SetKind::Environment => (0..n * n).map(|k| scene.environment.sh.get(k).copied().unwrap_or([0.0; 3])).collect(),
        SetKind::KeyLight(i) => {
            let l = &scene.key_lights[i];
            let scale = cap_solid_angle(l.angular_radius) / window_solid_angle(set) * (4.0 * PI).sqrt();
            let mut c = vec![[0.0; 3]; n * n];
            c[0] = [l.radiance[0] * scale, l.radiance[1] * scale, l.radiance[2] * scale];
            c
        }
    }
}

/// Solid angle of a cap of angular radius `alpha`: `2π(1 − cos α)`.
pub fn cap_solid_angle(alpha: f64) -> f64 {
    2.0 * PI * (1.0 - alpha.cos())
}

/// Solid angle of a set's azimuth × elevation window.
pub fn window_solid_angle(set: &AzimuthSet) -> f64 {
    let span: f64 = set.wedges.iter().map(|w| w.width).sum();
    span * (set.hi.sin() - set.lo.sin())
}
