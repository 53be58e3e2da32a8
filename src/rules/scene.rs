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
