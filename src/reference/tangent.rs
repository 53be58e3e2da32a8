//! A receiver's normal and tangent elevation (CONVENTIONS.md), which the indirect scan's `ω_min`
//! and the exact lobe's visibility clip share (docs/indirect.md §2, docs/accuracy.md §6). GPU:
//! `hfgi_normal_at` in `glsl/inc/hfgi_pyramid.glsl`.

use crate::scene::model::Scene;

/// Receiver normal at level-0 position `p` (docs/indirect.md §2): the CONVENTIONS.md height
/// gradients of the four surrounding texels, bilinearly interpolated, then normalised.
pub fn receiver_normal(scene: &Scene, p: [f64; 2]) -> [f64; 3] {
    let f = &scene.field;
    let (w, h, s) = (f.width() as i64, f.height() as i64, scene.texel_size);
    let at = |i: i64, j: i64| f.get(i.rem_euclid(w) as usize, j.rem_euclid(h) as usize) as f64;
    let grad = |i: i64, j: i64| {
        let (i, j) =
            if scene.wrap { (i.rem_euclid(w), j.rem_euclid(h)) } else { (i.clamp(0, w - 1), j.clamp(0, h - 1)) };
        let (i0, i1, j0, j1) = if scene.wrap {
            (i - 1, i + 1, j - 1, j + 1)
        } else {
            ((i - 1).max(0), (i + 1).min(w - 1), (j - 1).max(0), (j + 1).min(h - 1))
        };
        [(at(i1, j) - at(i0, j)) / ((i1 - i0) as f64 * s), (at(i, j1) - at(i, j0)) / ((j1 - j0) as f64 * s)]
    };
    let (fx, fy) = (p[0].floor(), p[1].floor());
    let (tx, ty) = (p[0] - fx, p[1] - fy);
    let (x0, y0) = (fx as i64, fy as i64);
    let mut g = [0.0; 2];
    for (dx, dy, wgt) in
        [(0, 0, (1.0 - tx) * (1.0 - ty)), (1, 0, tx * (1.0 - ty)), (0, 1, (1.0 - tx) * ty), (1, 1, tx * ty)]
    {
        let gg = grad(x0 + dx, y0 + dy);
        g[0] += wgt * gg[0];
        g[1] += wgt * gg[1];
    }
    let len = (g[0] * g[0] + g[1] * g[1] + 1.0).sqrt();
    [-g[0] / len, -g[1] / len, 1.0 / len]
}

/// ω_min of a receiver with normal `normal` along azimuth `phi`: its tangent plane (§3), the
/// paper's `−asin(N·d)` or, with `tangent`, the exact tangent elevation `atan2(−N·d, N_z)`
/// (CONVENTIONS.md, docs/accuracy.md §4).
pub fn omega_min(normal: [f64; 3], phi: f64, tangent: bool) -> f64 {
    let nd = normal[0] * phi.cos() + normal[1] * phi.sin();
    if tangent {
        (-nd).atan2(normal[2])
    } else {
        -nd.clamp(-1.0, 1.0).asin()
    }
}

/// The lowest elevation the visible window starts at along `phi` for a receiver of normal
/// `normal`: with `gi.diffuse_lobe = "exact"` its tangent elevation (`V` zero below the tangent
/// plane, docs/accuracy.md §6), else unbounded (`None`).
pub fn tangent_clip(normal: Option<[f64; 3]>, phi: f64) -> f64 {
    normal.map_or(f64::NEG_INFINITY, |nrm| omega_min(nrm, phi, true))
}
