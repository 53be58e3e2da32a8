//! How the shading buffer stores one texel of a plane (docs/integration.md, "Shading buffer"):
//! [`ShadingFormat`] (`gi.shading_storage`), fixed at creation. docs/performance.md §36 measures
//! what RGBE adds to each layer's error.

use crate::math::rgbe;
use crate::scene::model::Scene;
pub use crate::scene::model::ShadingFormat;

impl ShadingFormat {
    /// The format `scene`'s shading buffer is created with (`gi.shading_storage` resolved:
    /// [`crate::scene::model::GiSettings::shading_format`]).
    pub fn of(scene: &Scene) -> Self {
        scene.gi.shading_format()
    }

    /// Bytes per texel of a plane.
    pub fn texel_bytes(self) -> u64 {
        match self {
            Self::F32 => 12,
            Self::Rgbe => 4,
        }
    }

    /// 1 for [`ShadingFormat::Rgbe`]: the shaders' `packed` flag (`hfgi_plane.glsl`).
    pub(crate) fn packed_flag(self) -> u32 {
        u32::from(self == Self::Rgbe)
    }

    /// The RGB texels of `bytes` (little-endian, a whole number of texels of this format).
    pub fn decode(self, bytes: &[u8]) -> Vec<[f32; 3]> {
        let word = |c: &[u8]| u32::from_le_bytes([c[0], c[1], c[2], c[3]]);
        match self {
            Self::F32 => {
                bytes.chunks_exact(12).map(|c| std::array::from_fn(|k| f32::from_bits(word(&c[4 * k..])))).collect()
            }
            Self::Rgbe => bytes.chunks_exact(4).map(|c| rgbe::unpack(word(c))).collect(),
        }
    }

    /// `texels` encoded in this format (what the shaders write; for a caller that fills a
    /// shading buffer itself, e.g. a [`crate::frame::view::ViewInputs`] of its own).
    pub fn encode(self, texels: &[[f32; 3]]) -> Vec<u8> {
        match self {
            Self::F32 => texels.iter().flatten().flat_map(|v| v.to_le_bytes()).collect(),
            Self::Rgbe => texels.iter().flat_map(|t| rgbe::pack(*t).to_le_bytes()).collect(),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn decode_inverts_encode_to_the_format_precision() {
        let t = [[1.0, 0.5, 0.25], [3.0e-3, 7.0, 0.0], [1.5, 1.5, 1.5]];
        for f in [ShadingFormat::F32, ShadingFormat::Rgbe] {
            let bytes = f.encode(&t);
            assert_eq!(bytes.len() as u64, 3 * f.texel_bytes());
            let back = f.decode(&bytes);
            for (a, b) in back.iter().zip(&t) {
                for k in 0..3 {
                    assert!((a[k] - b[k]).abs() <= b.iter().fold(0f32, |m, v| m.max(*v)) / 512.0, "{f:?}");
                }
            }
        }
        assert_eq!(ShadingFormat::F32.decode(&ShadingFormat::F32.encode(&t)), t.to_vec());
    }
}
