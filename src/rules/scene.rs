//! What a scene implies for the frame, computed the same way by the renderer and the CPU twins:
//! the height origin, whether there is indirect light, whether it uses the glossy vector
//! pyramid.

use crate::scene::model::Scene;
use crate::scene::HeightField;

/// The height origin `z0` of a field (docs/pyramid.md, "Origin"): the midrange of its heights,
/// computed in f64 and rounded to f32. Level 0 is read relative to it, so every filtered height
/// keeps f32 precision relative to the field's relief rather than to its distance from 0
/// (a plateau at 1e4 or 1e7). Shading is invariant under a z-translation: the CPU twin
/// ([`crate::reference::direct::render_direct`]) uses the same origin.
pub fn height_origin(field: &HeightField) -> f32 {
    let (lo, hi) = field.range();
    ((lo as f64 + hi as f64) / 2.0) as f32
}

/// Whether the scene has indirect light to compute: bounces > 0 and a surface that reflects
/// something (non-zero albedo, or a specular lobe whose glossy light feeds the scalar radiance
/// pyramid).
pub fn needs_indirect(scene: &Scene) -> bool {
    use crate::scene::model::Albedo;
    let m = &scene.material;
    let albedo = match &m.albedo {
        Albedo::Constant(a) => a.iter().any(|v| *v != 0.0),
        Albedo::Map(map) => map.iter().any(|a| a.iter().any(|v| *v != 0.0)),
    };
    let specular = m.specular.is_some_and(|k| k.iter().any(|v| *v != 0.0));
    scene.gi.bounces > 0 && (albedo || specular)
}

/// The most memory the later bounces' recorded casting sets may take ([`replay_bytes`]);
/// beyond it they walk their rays (docs/indirect.md §2, "Replay").
pub const REPLAY_BUDGET: u64 = 32 << 20;

/// The longest ladder (samples per ray: `n_v` + near + far steps) whose casting set a ray
/// records: one bit per sample in two 32-bit words (`glsl/indirect/scan.comp.glsl`).
pub const REPLAY_STEPS: usize = 64;

/// Bytes of the recorded casting sets on a `work` grid: two 32-bit words per receiver and
/// azimuth of the later bounces (`gi.scan_azimuths(2)`: the first bounce records only the
/// azimuths they cast, every [`replay_stride`]-th of its own).
pub fn replay_bytes(scene: &Scene, work: (usize, usize)) -> u64 {
    work.0 as u64 * work.1 as u64 * scene.gi.scan_azimuths(2) as u64 * 8
}

/// Which of the first bounce's azimuths the later bounces' set holds: every `r`-th, `r =
/// gi.azimuths / gi.scan_azimuths(2)` when that divides ([`crate::rules::lighting::environment_set`]
/// turns every set by the same angle, so the later set is then a subset of the first); `None`
/// when it does not, and the later bounces cannot replay.
pub fn replay_stride(scene: &Scene) -> Option<u32> {
    let (first, later) = (scene.gi.azimuths, scene.gi.scan_azimuths(2));
    (later > 0 && first % later == 0).then(|| first / later)
}

/// Whether the indirect scans of bounces 2 and later cast a casting set the first bounce's scan
/// recorded instead of walking their rays (docs/indirect.md §2, "Replay"). The casting set of a
/// ray depends on the heights alone, and a later bounce's — the walk without radial probes — is
/// found by the first bounce's walk as well (the samples above that walk's own horizon), so the
/// later bounces cast exactly the members they would walk to. With `gi.replay`, two or more
/// bounces, none of the later ones probing (`gi.radial_probes_later = 0`), on azimuths of the
/// first one's set (`gi.azimuths_later` divides `gi.azimuths`: [`replay_stride`]), a ladder of
/// at most [`REPLAY_STEPS`] samples (`ladder`) and the sets within [`REPLAY_BUDGET`] on the
/// `work` grid.
pub fn replays(scene: &Scene, work: (usize, usize), ladder: usize) -> bool {
    let gi = &scene.gi;
    gi.replay
        && needs_indirect(scene)
        && gi.bounces >= 2
        && gi.probes(2) == 0
        && replay_stride(scene).is_some()
        && ladder <= REPLAY_STEPS
        && replay_bytes(scene, work) <= REPLAY_BUDGET
}

/// Whether the indirect light uses the glossy SH vector pyramid (docs/indirect.md §1).
pub fn vector_pyramid(scene: &Scene) -> bool {
    use crate::scene::model::GlossyPyramid;
    needs_indirect(scene)
        && scene.gi.glossy_pyramid == GlossyPyramid::Vector
        && scene.material.specular.is_some_and(|k| k.iter().any(|v| *v != 0.0))
}

/// The grid level 0 of the (scalar) radiance pyramid covers (docs/indirect.md §1, "Sub-sampled
/// radiance"): with `gi.subsample > 1` the working grid, whose texel averages the exit radiance
/// of the field texels in its cell ([`radiance_cell`]); the field otherwise, and always for the
/// glossy vector pyramid (its incident SH vectors are not averaged). The scans read the
/// pyramid at the working resolution, so the field-resolution levels finer than it only ever
/// reached them point-sampled; a working-grid base holds `s²` times fewer texels.
pub fn radiance_base(scene: &Scene) -> (usize, usize) {
    let (w, h) = (scene.field.width(), scene.field.height());
    if scene.gi.subsample > 1 && !vector_pyramid(scene) {
        scene.gi.working_size(w, h)
    } else {
        (w, h)
    }
}

/// The cell of a `to`-texel grid that texel `x` of a `from`-texel row falls in (texel centres,
/// domain edges aligned, as [`crate::reference::pyramid::rescale`]): `⌊(2x + 1)·to / (2·from)⌋`,
/// in integers. With `from = s·to` cell `c` holds texels `s·c … s·c + s − 1`.
pub fn radiance_cell(x: usize, from: usize, to: usize) -> usize {
    ((2 * x + 1) * to / (2 * from)).min(to - 1)
}

/// The diffuse lobe of `gi.diffuse_lobe` as order-n ZH (the shading's, GPU and twin):
/// [`crate::math::zh::clamped_cosine`] or [`crate::math::zh::cosine`].
pub fn diffuse_lobe(n: usize, lobe: crate::scene::model::DiffuseLobe) -> Vec<f64> {
    use crate::math::zh;
    use crate::scene::model::DiffuseLobe;
    match lobe {
        DiffuseLobe::Sh => zh::clamped_cosine(n),
        DiffuseLobe::Exact => zh::cosine(n),
    }
}

/// SH bands of the IR vector `U` the renderer stores (docs/indirect.md §4). The indirect shade
/// of a diffuse surface reads `U` only through the clamped-cosine lobe about the normal, whose
/// odd bands `l ≥ 3` are exactly zero ([`crate::math::zh::clamped_cosine`]): it stores the bands
/// up to the last non-zero one (order 4: 3 bands, 9 of 16 coefficients) and shades exactly the
/// same; with the exact lobe (`gi.diffuse_lobe = "exact"`, band 1 only) 2 bands, 4
/// coefficients. All `n` bands when something else reads `U`: a specular colour (the Phong lobe and the
/// glossy vector pyramid) or sphere blockers (the triple product `U ⊛ V_s` mixes the bands).
/// Both are fixed at creation (`Renderer::set_material` and the sphere slots cannot add them).
pub fn u_bands(scene: &Scene) -> usize {
    let n = scene.gi.sh_order;
    if scene.material.specular.is_some() || !scene.spheres.is_empty() {
        return n;
    }
    let zh = diffuse_lobe(n, scene.gi.diffuse_lobe);
    zh.iter().rposition(|z| *z != 0.0).map_or(n, |l| l + 1)
}

/// Coefficients per RGB channel of the stored `U`: [`u_bands`]² (the scan's and the shade's
/// `HFGI_NU`; a receiver's values are 3 × this).
pub fn u_coefficients(scene: &Scene) -> usize {
    let b = u_bands(scene);
    b * b
}

#[cfg(test)]
mod tests {
    use super::{replay_bytes, replay_stride, replays, u_bands};

    /// The replay's conditions (docs/indirect.md §2): the `default` preset with two bounces and
    /// 32 later azimuths replays at 128² (4 MiB of sets) and 256² (16 MiB), not at 512² (64 MiB,
    /// over the budget), nor with `gi.replay = false`, one bounce, later probes, a later set that
    /// is not a subset of the first (a count that does not divide 32) or a ladder longer than
    /// 64 samples (`high`'s 107 at 128²). 16 or 8 later azimuths replay every 2nd or 4th of
    /// the first set's, in half or a quarter of the memory.
    #[test]
    fn the_replay_applies_where_the_later_walks_are_recorded_and_fit() {
        let mut s = crate::scene::file::default_scene().unwrap();
        (s.gi.bounces, s.gi.azimuths, s.gi.azimuths_later) = (2, 32, 32);
        let ladder = 35; // n_v 29 + 4 near + 2 far steps at 128²
        assert!(replays(&s, (128, 128), ladder) && replays(&s, (256, 256), ladder + 4));
        assert_eq!(replay_bytes(&s, (128, 128)), 4 << 20);
        assert!(!replays(&s, (512, 512), ladder + 8), "64 MiB is over the budget");
        assert!(replays(&s, (512, 256), ladder + 8), "32 MiB is within it");
        assert!(!replays(&s, (128, 128), 65), "a ladder of 65 samples");
        let off = |f: &dyn Fn(&mut crate::scene::model::Scene)| {
            let mut t = s.clone();
            f(&mut t);
            !replays(&t, (128, 128), ladder)
        };
        assert!(off(&|t| t.gi.replay = false));
        assert!(off(&|t| t.gi.bounces = 1));
        assert!(off(&|t| t.gi.radial_probes_later = 1));
        assert!(off(&|t| t.gi.azimuths_later = 24));
        assert!(off(&|t| t.gi.azimuths_later = 12));
        for (later, stride) in [(32, 1), (16, 2), (8, 4), (4, 8)] {
            let mut t = s.clone();
            t.gi.azimuths_later = later;
            assert!(replays(&t, (128, 128), ladder), "{later} later azimuths");
            assert_eq!(replay_stride(&t), Some(stride), "{later} later azimuths");
            assert_eq!(replay_bytes(&t, (128, 128)), (4 << 20) / u64::from(stride));
        }
        assert!(!off(&|t| t.gi.radial_probes = 0), "bounce 1 without probes records its own set");
    }

    /// The clamped cosine's ZH vanishes in the odd bands l ≥ 3 (Ramamoorthi & Hanrahan 2001,
    /// A_l = 0 for odd l > 1), so a diffuse surface keeps bands up to the last even one below
    /// n (or band 1); a specular colour or a sphere blocker keeps all n.
    #[test]
    fn u_keeps_the_bands_up_to_the_last_nonzero_clamped_cosine_band() {
        let mut s = crate::scene::file::default_scene().unwrap();
        s.material.specular = None;
        s.spheres.clear();
        for (n, kept) in [(1, 1), (2, 2), (3, 3), (4, 3), (5, 5), (6, 5), (7, 7), (8, 7)] {
            s.gi.sh_order = n;
            assert_eq!(u_bands(&s), kept, "n = {n}");
            let mut glossy = s.clone();
            glossy.material.specular = Some([0.0; 3]);
            assert_eq!(u_bands(&glossy), n, "n = {n}, specular");
            let mut spheres = s.clone();
            let sphere =
                crate::scene::model::SphereBlocker { center: glam::DVec3::ZERO, radius: 1.0, albedo: [0.5; 3] };
            spheres.spheres.push(sphere);
            assert_eq!(u_bands(&spheres), n, "n = {n}, a sphere blocker");
        }
    }
}
