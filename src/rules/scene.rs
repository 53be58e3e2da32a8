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

/// Whether the indirect light uses the glossy SH vector pyramid (docs/indirect.md §1).
pub fn vector_pyramid(scene: &Scene) -> bool {
    use crate::scene::model::GlossyPyramid;
    needs_indirect(scene)
        && scene.gi.glossy_pyramid == GlossyPyramid::Vector
        && scene.material.specular.is_some_and(|k| k.iter().any(|v| *v != 0.0))
}

/// SH bands of the IR vector `U` the renderer stores (docs/indirect.md §4). The indirect shade
/// of a diffuse surface reads `U` only through the clamped-cosine lobe about the normal, whose
/// odd bands `l ≥ 3` are exactly zero ([`crate::math::zh::clamped_cosine`]): it stores the bands
/// up to the last non-zero one (order 4: 3 bands, 9 of 16 coefficients) and shades exactly the
/// same. All `n` bands when something else reads `U`: a specular colour (the Phong lobe and the
/// glossy vector pyramid) or sphere blockers (the triple product `U ⊛ V_s` mixes the bands).
/// Both are fixed at creation (`Renderer::set_material` and the sphere slots cannot add them).
pub fn u_bands(scene: &Scene) -> usize {
    let n = scene.gi.sh_order;
    if scene.material.specular.is_some() || !scene.spheres.is_empty() {
        return n;
    }
    let zh = crate::math::zh::clamped_cosine(n);
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
    use super::u_bands;

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
