//! Reading back what is stored in `gi.storage` ([`Storage`]; glsl/inc/hfgi_store.glsl): `V`
//! of the visibility pass, `U` of the indirect scan and the radiance stack, as 32-bit words
//! holding one f32 or two IEEE halves (the even value in the low half). Diagnostics and tests
//! only; the passes read them on the GPU.
//!
//! And the pre-exposure of f16 storage ([`pre_exposure`]): `U` and the radiance stack scale with
//! the scene's radiance, so with f16 they are stored multiplied by a power of two that puts a
//! bound of their values at 2¹⁰, inside the half's range whatever the lights' units
//! (docs/performance.md §14).

use crate::error::Result;
use crate::scene::model::{Albedo, Scene, Storage};
use crate::vk::memory::{self, Buffer};
use crate::vk::Context;

/// `count` receivers' vectors of `values` numbers each, from receiver `first` on (receivers of
/// every set counted in one sequence), unpacked to f32 (waits).
pub fn download_vectors(
    ctx: &Context,
    buf: &Buffer,
    storage: Storage,
    first: usize,
    count: usize,
    values: usize,
) -> Result<Vec<f32>> {
    let stride = storage.stride(values);
    match storage {
        Storage::F32 => memory::download_f32(ctx, buf, (first * stride) as u64, (count * stride) as u64),
        Storage::F16 => {
            // A receiver's vector starts at an even value: whole words, `stride / 2` each.
            let words = memory::download(ctx, buf, (first * stride * 2) as u64, (count * stride * 2) as u64)?;
            let halves: Vec<f32> =
                words.chunks_exact(2).map(|c| f16_to_f32(u16::from_le_bytes([c[0], c[1]]))).collect();
            Ok(halves.chunks_exact(stride).flat_map(|r| r[..values].iter().copied()).collect())
        }
    }
}

/// log2 of where [`pre_exposure`] puts the bound of the stored values: 64× below the half's
/// largest value (65504), 2²⁴ above its smallest normal (6.1e-5).
const PRE_EXPOSED_LOG2: i32 = 10;

/// An upper bound of the radiance a surface point of `scene` reflects, in any bounce up to
/// `gi.bounces` (at least 1), with the live lights and material: every incident radiance is at
/// most `L` = the environment's bound (`Σ |c_lm| · max|Y_lm|`, `max|Y_lm| ≤ √((2l+1)/4π)`) plus
/// every key and local light's radiance; exit radiance is at most `f·L` with
/// `f = ρ_max + k_s,max` (diffuse: `ρ/π · E` with `E ≤ πL`; glossy: `k_s` times the incident
/// radiance weighted by the normalised Phong lobe, whose integral is 1: docs/direct.md §6), and
/// bounce `b` at most `f^b·L`. SH truncation can overshoot it a little; the pre-exposure
/// leaves 64× of headroom.
pub fn radiance_bound(scene: &Scene) -> f64 {
    let max3 = |v: [f64; 3]| v.into_iter().fold(0.0f64, |a, x| a.max(x.abs()));
    let mut env = [0.0f64; 3];
    for (k, c) in scene.environment.sh.iter().enumerate() {
        let l = (k as f64).sqrt().floor();
        let y = ((2.0 * l + 1.0) / (4.0 * std::f64::consts::PI)).sqrt();
        for (e, v) in env.iter_mut().zip(c) {
            *e += v.abs() * y;
        }
    }
    let lights = scene.key_lights.iter().map(|k| max3(k.radiance)).sum::<f64>()
        + scene.local_lights.iter().map(|k| max3(k.radiance)).sum::<f64>();
    let f32s = |v: [f32; 3]| max3(v.map(f64::from));
    let rho = match &scene.material.albedo {
        Albedo::Constant(a) => f32s(*a),
        Albedo::Map(m) => m.iter().fold(0.0f64, |a, v| a.max(f32s(*v))),
    };
    let ks = scene.material.specular.map_or(0.0, f32s);
    let f = rho + ks;
    (max3(env) + lights) * f.max(f.powi(scene.gi.bounces.max(1) as i32))
}

/// The pre-exposure of f16 storage: `U` and the radiance stack are stored multiplied by it and
/// read divided by it (glsl/inc/hfgi_store.glsl). A power of two, so that with f16 the stored
/// halves are those of the unscaled values wherever those were normal halves, and `1` with f32
/// (which is then bit-identical to no pre-exposure). It puts `√(4π)·`[`radiance_bound`] (`U`'s
/// coefficients are at most `√(4π)` times the largest radiance, by Cauchy–Schwarz) at 2¹⁰; a
/// dark scene gets 1. Lights scaled by `2^k` give exactly `2^−k` times the pre-exposure (the
/// exponent is read from the bound's bits, not from a rounded `log2`), so the same halves.
pub fn pre_exposure(scene: &Scene) -> f32 {
    let bound = (4.0 * std::f64::consts::PI).sqrt() * radiance_bound(scene);
    if scene.gi.storage == Storage::F32 || !(bound >= f64::MIN_POSITIVE && bound.is_finite()) {
        return 1.0;
    }
    // ⌈log2 bound⌉ of a normal f64: its exponent, plus one unless the mantissa is zero.
    let bits = bound.to_bits();
    let exp = ((bits >> 52) & 0x7ff) as i32 - 1023;
    let ceil_log2 = exp + i32::from(bits & ((1u64 << 52) - 1) != 0);
    2f32.powi((PRE_EXPOSED_LOG2 - ceil_log2).clamp(-120, 120))
}

/// The IEEE 754 binary16 value of the bits `h` (what `unpackHalf2x16` returns), exactly.
pub fn f16_to_f32(h: u16) -> f32 {
    let sign = if h & 0x8000 != 0 { -1.0 } else { 1.0 };
    let exp = i32::from((h >> 10) & 0x1f);
    let mant = f32::from(h & 0x3ff);
    sign * match exp {
        0 => mant * 2f32.powi(-24), // subnormal (and zero)
        31 if mant == 0.0 => f32::INFINITY,
        31 => f32::NAN,
        e => (1.0 + mant / 1024.0) * 2f32.powi(e - 15),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn half_bits_decode_to_their_values() {
        // Values from the binary16 definition, including the extremes.
        for (bits, v) in [
            (0x0000u16, 0.0f32),
            (0x3c00, 1.0),
            (0xc000, -2.0),
            (0x3555, 0.333_251_95),
            (0x7bff, 65504.0),
            (0x0001, 5.960_464_5e-8),
            (0x0400, 6.103_515_6e-5),
            (0x8000, -0.0),
        ] {
            assert_eq!(f16_to_f32(bits), v, "bits {bits:#06x}");
        }
        assert!(f16_to_f32(0x7c00).is_infinite() && f16_to_f32(0x7e00).is_nan());
    }

    #[test]
    fn the_pre_exposure_puts_the_bound_at_2_to_the_10() {
        use crate::scene::model::{Environment, KeyLight};
        let mut s = crate::scene::file::default_scene().expect("default scene");
        s.gi.storage = Storage::F16;
        s.gi.bounces = 1;
        s.environment = Environment { sh: vec![[0.0; 3]; 16] };
        s.key_lights = vec![KeyLight { direction: glam::DVec3::Z, angular_radius: 0.1, radiance: [3.0, 1.0, 0.5] }];
        s.local_lights.clear();
        s.material.albedo = Albedo::Constant([0.5, 0.8, 0.25]);
        s.material.specular = None;
        // L = 3, f = 0.8: bound 2.4 (one bounce), √(4π)·2.4 = 8.51 → ⌈log2⌉ = 4 → 2^(10 − 4).
        assert!((radiance_bound(&s) - 2.4).abs() < 1e-6, "{}", radiance_bound(&s)); // ρ is f32
        assert_eq!(pre_exposure(&s), 64.0);
        for k in [-30, -1, 1, 20, 60] {
            let mut t = s.clone();
            t.key_lights[0].radiance = [3.0, 1.0, 0.5].map(|v| v * 2f64.powi(k));
            assert_eq!(pre_exposure(&t), 64.0 * 2f32.powi(-k), "lights × 2^{k}");
        }
        // An environment's bound: |c_00| Y_00 + |c_1m| √(3/4π), times ρ_max = 0.8.
        let mut e = s.clone();
        e.key_lights.clear();
        e.environment.sh[0] = [2.0, 0.0, 0.0];
        e.environment.sh[2] = [-1.0, 0.0, 0.0];
        let want = 0.8 * (2.0 / (4.0 * std::f64::consts::PI).sqrt() + (3.0 / (4.0 * std::f64::consts::PI)).sqrt());
        assert!((radiance_bound(&e) - want).abs() < 1e-6, "{} vs {want}", radiance_bound(&e));
        // A glossy surface and two bounces: f = 0.8 + 0.3 > 1, so the second bounce bounds it.
        let mut g = s.clone();
        g.material.specular = Some([0.1, 0.3, 0.0]);
        g.gi.bounces = 2;
        assert!((radiance_bound(&g) - 3.0 * 1.1 * 1.1).abs() < 1e-6, "{}", radiance_bound(&g));
        // f32 storage and a dark scene: 1.
        let mut f = s.clone();
        f.gi.storage = Storage::F32;
        assert_eq!(pre_exposure(&f), 1.0);
        let mut d = s.clone();
        d.key_lights.clear();
        assert_eq!(pre_exposure(&d), 1.0);
    }

    #[test]
    fn the_stride_keeps_pairs_inside_a_receiver() {
        for values in 1..80 {
            assert_eq!(Storage::F32.stride(values), values);
            let s = Storage::F16.stride(values);
            assert!(s % 2 == 0 && s >= values && s <= values + 1);
            assert_eq!(Storage::F16.bytes((3 * s) as u64), (3 * s * 2) as u64);
        }
    }
}
