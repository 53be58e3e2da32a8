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
///
/// Every set is turned by the same angle, `gi.azimuth_offset` wedges of the first set
/// (`2π·offset/gi.azimuths`): a set of `m` samples is `φ_j = 2π(j + offset·m/gi.azimuths)/m`.
/// So when `m` divides `gi.azimuths` its samples are every `(gi.azimuths/m)`-th of the first
/// set's, and the later bounces can cast the casting sets the first bounce's walk recorded
/// along those azimuths ([`crate::rules::scene::replays`]).
pub fn environment_set(gi: &GiSettings, m: u32) -> AzimuthSet {
    let offset = gi.azimuth_offset * f64::from(m) / f64::from(gi.azimuths.max(1));
    azimuth::environment_set(m as usize, offset, gi.interpolation)
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

#[cfg(test)]
mod tests {
    use super::environment_set;

    /// Every set is turned by the same angle (`gi.azimuth_offset` wedges of the first set), so
    /// a later set whose count divides the first's holds every `r`-th of its samples, whatever
    /// the offset (what the replay of fewer later azimuths needs: `rules::scene::replay_stride`);
    /// the first set itself is `φ_j = 2π(j + offset)/m`.
    #[test]
    fn a_later_set_that_divides_the_first_is_a_subset_of_it() {
        let mut gi = crate::scene::model::GiSettings::preset(crate::scene::model::Quality::Default);
        for offset in [0.0, 0.25, 0.5, 0.9] {
            gi.azimuth_offset = offset;
            let first = environment_set(&gi, 32).phi;
            for (j, p) in first.iter().enumerate() {
                let want = 2.0 * std::f64::consts::PI * (j as f64 + offset) / 32.0;
                assert!((p - want).abs() < 1e-12, "offset {offset}, φ_{j} = {p}, want {want}");
            }
            for (m, r) in [(16, 2), (8, 4), (4, 8)] {
                let later = environment_set(&gi, m).phi;
                assert_eq!(later.len(), m as usize);
                for (i, p) in later.iter().enumerate() {
                    let d = p - first[i * r];
                    assert!(
                        d.abs() < 1e-12,
                        "offset {offset}, {m} azimuths: φ_{i} = {p}, first set's φ_{} = {}",
                        i * r,
                        first[i * r]
                    );
                }
            }
        }
    }
}
