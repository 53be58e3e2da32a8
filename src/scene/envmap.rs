//! Environment lighting as spherical harmonics: equirectangular HDR maps and analytic presets.
//!
//! Both produce RGB SH coefficients `c_k = ∫ L(ω) y_k(ω) dω` (index `k = l(l+1) + m`,
//! CONVENTIONS.md "Spherical harmonics"), which the renderer uses as they are, without clamping.
//!
//! **Equirectangular maps** (CONVENTIONS.md "Lighting"): image row `v` of `h` is the polar angle
//! `θ = π(v + 0.5)/h` from +z, so row 0 is the top (the zenith); column `u` of `w` is the azimuth
//! `φ = 2π(u + 0.5)/w` from +x toward +y. [`project_equirect`] is the pixel sum
//! `c_k = Σ_pixels L(ω_p) y_k(ω_p) ΔΩ_p` with `ΔΩ_p = sinθ · (π/h) · (2π/w)`.
//!
//! **Presets** ([`Preset`]) are analytic radiance functions projected with
//! [`sh::project`] at order [`PRESET_ORDER`].

use std::f64::consts::PI;
use std::path::Path;
use std::str::FromStr;
use std::sync::OnceLock;

use crate::error::{Error, Result};
use crate::io::exr::read_layers;
use crate::math::sh;

/// SH order of projected maps and presets (8 bands, 64 coefficients).
pub const PRESET_ORDER: usize = 8;

/// Gauss–Legendre nodes in `cosθ` used to project the presets ([`sh::project`]'s `quad`).
const PRESET_QUAD: usize = 128;

/// Half-width, in `cosθ`, of the `sky` preset's smooth blend from sky to ground (≈ ±6° about
/// the horizon), which keeps the order-8 projection from ringing below zero.
const SKY_BLEND: f64 = 0.1;

/// Elevation of the `sky` preset's sun glow, in degrees (where the default key light sits).
pub const SKY_SUN_ELEVATION_DEG: f64 = 35.0;
/// Azimuth of the `sky` preset's sun glow, in degrees from +x toward +y.
pub const SKY_SUN_AZIMUTH_DEG: f64 = 200.0;

/// Projects an equirectangular RGB map (`width × height` pixels, row-major, row 0 the top)
/// to SH order `n` (`n²` RGB coefficients) by the pixel sum with the solid angles of
/// CONVENTIONS.md (see the module docs), accumulated in f64.
///
/// The sum is separable: each row is first reduced to its azimuthal Fourier sums
/// `Σ_u L·cos(mφ_u)`, `Σ_u L·sin(mφ_u)` for `m < n`, so the cost is `O(w·h·n)`. With
/// `progress`, each row is reported to the progress hook ([`crate::progress`]; the scene
/// loader asks for it when the map has more than 256×128 pixels).
///
/// Accuracy: the solid angle `sinθ·(π/h)·(2π/w)` makes this the midpoint rule in θ (and φ),
/// so a constant map of 1 gives `c_0 = √(4π)·(1 + ε)` with `ε = (π/2h)/sin(π/2h) − 1`
/// (4.0e-4 at `h = 32`, 2.5e-5 at `h = 128`) and zonal terms of order `(l/h)²` (5.2e-3 for
/// `l = 6` at 64×32); the projection of a pure basis function `y_k`, `k < 64`, is the unit
/// vector `e_k` to within 3.8e-4 at 256×128 (`tests/scene_file.rs` measures both).
///
/// # Panics
/// If `rgb.len() != width·height` or `n ∉ 1..=16` (programmer errors; [`load_equirect_exr`]
/// returns matching sizes).
pub fn project_equirect(width: usize, height: usize, rgb: &[[f32; 3]], n: usize, progress: bool) -> Vec<[f64; 3]> {
    assert_eq!(rgb.len(), width * height, "project_equirect: {width}×{height} map needs {} pixels", width * height);
    assert!((1..=crate::math::MAX_ORDER).contains(&n), "project_equirect: order {n} outside 1..=16");
    let mut out = vec![[0.0f64; 3]; n * n];
    if width == 0 || height == 0 {
        return out;
    }
    let (dtheta, dphi) = (PI / height as f64, 2.0 * PI / width as f64);
    // cos(mφ_u), sin(mφ_u) for m < n.
    let mut cos_tab = vec![0.0f64; n * width];
    let mut sin_tab = vec![0.0f64; n * width];
    for u in 0..width {
        let phi = (u as f64 + 0.5) * dphi;
        for m in 0..n {
            let (s, c) = (m as f64 * phi).sin_cos();
            cos_tab[m * width + u] = c;
            sin_tab[m * width + u] = s;
        }
    }
    let mut fc = vec![[0.0f64; 3]; n];
    let mut fs = vec![[0.0f64; 3]; n];
    for v in 0..height {
        let theta = (v as f64 + 0.5) * dtheta;
        let (st, ct) = theta.sin_cos();
        let d_omega = st * dtheta * dphi;
        let row = &rgb[v * width..(v + 1) * width];
        for m in 0..n {
            let (ct_m, st_m) = (&cos_tab[m * width..(m + 1) * width], &sin_tab[m * width..(m + 1) * width]);
            let (mut a, mut b) = ([0.0f64; 3], [0.0f64; 3]);
            for ((px, &c), &s) in row.iter().zip(ct_m).zip(st_m) {
                for ch in 0..3 {
                    let x = f64::from(px[ch]);
                    a[ch] += x * c;
                    b[ch] += x * s;
                }
            }
            fc[m] = a;
            fs[m] = b;
        }
        // At φ = 0, y_l^m (m ≥ 0) is the θ factor F_lm(θ) of both y_l^m = F·cos(mφ) and
        // y_l^{−m} = F·sin(mφ).
        let f = sh::eval(n, [st, 0.0, ct]);
        for l in 0..n as i32 {
            for m in 0..=l {
                let w = f[sh::index(l, m)] * d_omega;
                let mu = m as usize;
                for ch in 0..3 {
                    out[sh::index(l, m)][ch] += w * fc[mu][ch];
                    if m > 0 {
                        out[sh::index(l, -m)][ch] += w * fs[mu][ch];
                    }
                }
            }
        }
        if progress {
            crate::progress::report(PROJECTION_TASK, v as u64 + 1, height as u64);
        }
    }
    out
}

/// The task name [`project_equirect`] reports progress under.
pub const PROJECTION_TASK: &str = "projecting environment map to SH";

/// Reads an equirectangular RGB environment map from an OpenEXR file: the channels `R`, `G`,
/// `B` of the default layer (or, if it has none, of the first layer that has all three), f16,
/// f32 or u32 samples. Returns `(width, height, pixels)`, row-major, row 0 the top row.
///
/// Errors: [`Error::Io`] / [`Error::Format`] for unreadable or corrupt files and missing
/// channels (the message lists the channels found), [`Error::NonFinite`] for a NaN or infinite
/// sample (naming its pixel), [`Error::Format`] for a file whose header claims more than
/// [`MAX_ENV_SAMPLES`] samples or blocks larger than
/// [`MAX_EXR_BLOCK_BYTES`](crate::scene::load::MAX_EXR_BLOCK_BYTES) (checked before any pixel
/// memory is allocated).
pub fn load_equirect_exr(path: &Path) -> Result<(usize, usize, Vec<[f32; 3]>)> {
    check_env_samples(path)?;
    let (w, h, channels) = read_layers(path)?;
    let find = |layer: &str, name: &str| {
        channels.iter().find(|(l, c, _)| l == layer && c == name).map(|(_, _, data)| data.as_slice())
    };
    let rgb_of = |layer: &str| Some([find(layer, "R")?, find(layer, "G")?, find(layer, "B")?]);
    let mut layers: Vec<&str> = vec![""];
    for (l, _, _) in &channels {
        if !layers.contains(&l.as_str()) {
            layers.push(l);
        }
    }
    let Some(planes) = layers.iter().find_map(|l| rgb_of(l)) else {
        let found: Vec<String> =
            channels.iter().map(|(l, c, _)| if l.is_empty() { c.clone() } else { format!("{l}.{c}") }).collect();
        return Err(Error::format(
            path,
            format!(
                "environment map has channels [{}]; expected R, G and B (an equirectangular RGB image)",
                found.join(", ")
            ),
        ));
    };
    let n = w * h;
    if planes.iter().any(|p| p.len() != n) {
        return Err(Error::format(path, format!("EXR channel lengths do not match its size {w}×{h}")));
    }
    let mut out = Vec::with_capacity(n);
    for (k, ((&r, &g), &b)) in planes[0].iter().zip(planes[1]).zip(planes[2]).enumerate() {
        if let Some(value) = [r, g, b].into_iter().find(|v| !v.is_finite()) {
            return Err(Error::NonFinite { source_name: path.display().to_string(), x: k % w, y: k / w, value });
        }
        out.push([r, g, b]);
    }
    Ok((w, h, out))
}

/// Most samples (pixels × channels, over every part) an environment map file may claim: three
/// channels of 8192×4096 pixels. The EXR reader allocates every channel at the size its header
/// claims before it decodes a pixel, so without this bound a 487-byte file claiming
/// 1073741815×4 pixels took more than 8 GB (found by fuzzing, docs/robustness.md "Fuzzing").
pub const MAX_ENV_SAMPLES: usize = 3 * 8192 * 4096;

/// Rejects a file whose headers claim more than [`MAX_ENV_SAMPLES`] samples or blocks larger
/// than [`crate::scene::load::MAX_EXR_BLOCK_BYTES`]. A header that cannot be read is left to
/// [`read_layers`], which reports it.
fn check_env_samples(path: &Path) -> Result<()> {
    let Ok(Ok(meta)) = std::panic::catch_unwind(|| exr::meta::MetaData::read_from_file(path, false)) else {
        return Ok(());
    };
    let mut samples = 0usize;
    for header in &meta.headers {
        let size = header.layer_size;
        let n = size.width().saturating_mul(size.height()).saturating_mul(header.channels.list.len());
        samples = samples.saturating_add(n);
    }
    if samples > MAX_ENV_SAMPLES {
        let h = &meta.headers[0];
        let (w, ht, c) = (h.layer_size.width(), h.layer_size.height(), h.channels.list.len());
        return Err(Error::format(
            path,
            format!(
                "environment map of {w}×{ht} pixels, {c} channel(s) ({} part(s) in all) holds more than \
                 {MAX_ENV_SAMPLES} samples (8192×4096 RGB); expected a smaller map",
                meta.headers.len()
            ),
        ));
    }
    crate::scene::load::check_exr_blocks(path, &meta.headers)
}

/// An analytic environment (`[environment] preset = "..."`), radiance in linear RGB.
///
/// - `uniform`: radiance 1 in every direction (`c_0 = √(4π)`, all other coefficients 0).
/// - `overcast`: a CIE-overcast-like sky, grey radiance `(1 + 2cosθ)/3` above the horizon
///   (1 at the zenith, 1/3 at the horizon) and a dark grey ground of 0.1 below.
/// - `sky`: a clear sky — a vertical gradient from a pale horizon `(0.80, 0.88, 1.00)` to a blue
///   zenith `(0.20, 0.40, 0.85)` (linear in `cosθ`), plus a warm glow around the sun,
///   `(1.0, 0.75, 0.45)·2·max(ω·s, 0)^8`, with `s` at elevation 35°, azimuth 200° (where the
///   default key light sits), over a dim warm ground `(0.15, 0.13, 0.11)`; sky and ground are
///   blended with a smoothstep over `cosθ ∈ [−0.1, 0.1]` (about ±6° about the horizon).
///
/// Each is projected to order [`PRESET_ORDER`] by [`Preset::sh`]. The steps at the horizon ring
/// a little at order 8 (the SH lighting is used as it is, not clamped); the ground values are
/// chosen so that every preset's order-8 expansion stays positive in every direction.
/// Irradiance on a horizontal surface (RGB): `sky` ≈ (1.98, 2.30, 3.15), `overcast` ≈ 2.44
/// (`7π/9`), `uniform` = π.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Preset {
    /// Radiance 1 everywhere.
    Uniform,
    /// CIE-overcast-like sky over a dark ground.
    Overcast,
    /// Clear blue sky with a warm sun glow over a dim ground.
    Sky,
}

impl Preset {
    /// Every preset, in [`Preset::names`] order.
    pub const ALL: [Preset; 3] = [Preset::Sky, Preset::Overcast, Preset::Uniform];

    /// The names accepted by [`Preset::from_str`].
    pub fn names() -> &'static [&'static str] {
        &["sky", "overcast", "uniform"]
    }

    /// The preset's name.
    pub fn name(self) -> &'static str {
        match self {
            Preset::Sky => "sky",
            Preset::Overcast => "overcast",
            Preset::Uniform => "uniform",
        }
    }

    /// Unit direction of the `sky` preset's sun glow.
    pub fn sky_sun_direction() -> [f64; 3] {
        let (el, az) = (SKY_SUN_ELEVATION_DEG.to_radians(), SKY_SUN_AZIMUTH_DEG.to_radians());
        [el.cos() * az.cos(), el.cos() * az.sin(), el.sin()]
    }

    /// Radiance toward the unit direction `d` (see the type's docs).
    pub fn radiance(self, d: [f64; 3]) -> [f64; 3] {
        let z = d[2];
        match self {
            Preset::Uniform => [1.0; 3],
            Preset::Overcast => {
                if z >= 0.0 {
                    [(1.0 + 2.0 * z) / 3.0; 3]
                } else {
                    [0.1; 3]
                }
            }
            Preset::Sky => {
                const GROUND: [f64; 3] = [0.15, 0.13, 0.11];
                const HORIZON: [f64; 3] = [0.80, 0.88, 1.00];
                const ZENITH: [f64; 3] = [0.20, 0.40, 0.85];
                const GLOW: [f64; 3] = [1.0, 0.75, 0.45];
                // Sky weight: 0 below −SKY_BLEND, 1 above +SKY_BLEND, smoothstep between.
                let t = ((z + SKY_BLEND) / (2.0 * SKY_BLEND)).clamp(0.0, 1.0);
                let w = t * t * (3.0 - 2.0 * t);
                let s = Self::sky_sun_direction();
                let c = (d[0] * s[0] + d[1] * s[1] + d[2] * s[2]).max(0.0);
                let glow = 2.0 * c.powi(8);
                let zs = z.max(0.0);
                [0, 1, 2].map(|i| {
                    let sky = HORIZON[i] + (ZENITH[i] - HORIZON[i]) * zs + GLOW[i] * glow;
                    w * sky + (1.0 - w) * GROUND[i]
                })
            }
        }
    }

    /// The preset's `PRESET_ORDER²` = 64 RGB SH coefficients, projected with [`sh::project`]
    /// (128 Gauss–Legendre nodes in `cosθ` × 256 azimuths), computed once and cached.
    pub fn sh(self) -> Vec<[f64; 3]> {
        static CACHE: [OnceLock<Vec<[f64; 3]>>; 3] = [OnceLock::new(), OnceLock::new(), OnceLock::new()];
        let slot = match self {
            Preset::Sky => 0,
            Preset::Overcast => 1,
            Preset::Uniform => 2,
        };
        CACHE[slot]
            .get_or_init(|| {
                let ch: Vec<Vec<f64>> =
                    (0..3).map(|c| sh::project(PRESET_ORDER, |d| self.radiance(d)[c], PRESET_QUAD)).collect();
                (0..PRESET_ORDER * PRESET_ORDER).map(|k| [ch[0][k], ch[1][k], ch[2][k]]).collect()
            })
            .clone()
    }
}

impl FromStr for Preset {
    type Err = Error;

    /// Parses a preset name (case-insensitive); an unknown name is [`Error::InvalidParameter`]
    /// listing the known ones.
    fn from_str(s: &str) -> Result<Self> {
        match s.trim().to_ascii_lowercase().as_str() {
            "sky" => Ok(Preset::Sky),
            "overcast" => Ok(Preset::Overcast),
            "uniform" => Ok(Preset::Uniform),
            _ => Err(Error::param(
                "environment.preset",
                format!("\"{s}\""),
                format!("one of {}", Self::names().join(", ")),
            )),
        }
    }
}

impl std::fmt::Display for Preset {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(self.name())
    }
}
