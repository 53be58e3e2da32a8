//! Reading back what is stored in `gi.storage` ([`Storage`]; glsl/inc/hfgi_store.glsl): `V`
//! of the visibility pass, `U` of the indirect scan and the radiance stack, as 32-bit words
//! holding one f32 or two IEEE halves (the even value in the low half). Diagnostics and tests
//! only; the passes read them on the GPU.

use crate::error::Result;
use crate::scene::model::Storage;
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
    fn the_stride_keeps_pairs_inside_a_receiver() {
        for values in 1..80 {
            assert_eq!(Storage::F32.stride(values), values);
            let s = Storage::F16.stride(values);
            assert!(s % 2 == 0 && s >= values && s <= values + 1);
            assert_eq!(Storage::F16.bytes((3 * s) as u64), (3 * s * 2) as u64);
        }
    }
}
