//! The raw (serde) schema of a scene file: every table as deserialized, before validation.

use std::path::PathBuf;

use serde::de::{self, Deserializer, SeqAccess, Visitor};
use serde::Deserialize;
use toml::Table;

// ---------------------------------------------------------------------------------------------
// Raw (serde) schema. Every field is optional so that a one-key table deserializes on its own,
// which is how errors are attributed to a key (see `Ctx::de_table`).

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
pub(super) struct RawScene {
    pub(super) heightfield: Option<Table>,
    pub(super) material: Option<Table>,
    pub(super) environment: Option<Table>,
    pub(super) key_light: Option<Vec<Table>>,
    pub(super) local_light: Option<Vec<Table>>,
    pub(super) sphere: Option<Vec<Table>>,
    pub(super) gi: Option<Table>,
    pub(super) camera: Option<Table>,
    pub(super) animation: Option<Table>,
}

pub(super) const NODATA_TIFF_ONLY: &str = "heightfield.nodata applies to GeoTIFF files (.tif/.tiff) only";

#[derive(Deserialize, Default)]
#[serde(deny_unknown_fields)]
pub(super) struct RawHeightfield {
    pub(super) generator: Option<String>,
    pub(super) size: Option<SizeSpec>,
    pub(super) file: Option<PathBuf>,
    pub(super) raw_size: Option<SizeSpec>,
    pub(super) texel_size: Option<f64>,
    pub(super) height_scale: Option<f64>,
    pub(super) height_offset: Option<f64>,
    pub(super) wrap: Option<bool>,
    pub(super) nodata: Option<toml::Value>,
}

#[derive(Deserialize, Default)]
#[serde(deny_unknown_fields)]
pub(super) struct RawMaterial {
    pub(super) albedo: Option<[f64; 3]>,
    pub(super) albedo_map: Option<PathBuf>,
    pub(super) specular: Option<[f64; 3]>,
    pub(super) exponent: Option<f64>,
}

#[derive(Deserialize, Default)]
#[serde(deny_unknown_fields)]
pub(super) struct RawEnvironment {
    pub(super) sh: Option<Vec<[f64; 3]>>,
    pub(super) map: Option<PathBuf>,
    pub(super) preset: Option<String>,
    pub(super) intensity: Option<f64>,
}

#[derive(Deserialize, Default)]
#[serde(deny_unknown_fields)]
pub(super) struct RawKeyLight {
    pub(super) direction: Option<[f64; 3]>,
    pub(super) elevation_deg: Option<f64>,
    pub(super) azimuth_deg: Option<f64>,
    pub(super) angular_radius_deg: Option<f64>,
    pub(super) radiance: Option<[f64; 3]>,
}

#[derive(Deserialize, Default)]
#[serde(deny_unknown_fields)]
pub(super) struct RawLocalLight {
    pub(super) position: Option<[f64; 3]>,
    pub(super) radius: Option<f64>,
    pub(super) radiance: Option<[f64; 3]>,
}

#[derive(Deserialize, Default)]
#[serde(deny_unknown_fields)]
pub(super) struct RawGi {
    pub(super) sh_order: Option<u32>,
    pub(super) azimuths: Option<u32>,
    pub(super) key_light_azimuths: Option<u32>,
    pub(super) local_light_azimuths: Option<u32>,
    pub(super) level_step: Option<u32>,
    pub(super) level_offset: Option<u32>,
    pub(super) subsample: Option<u32>,
    pub(super) interpolation: Option<String>,
    pub(super) pyramid: Option<String>,
    pub(super) bounces: Option<u32>,
    pub(super) radiance_level_step: Option<u32>,
    pub(super) radiance_level_offset: Option<u32>,
    pub(super) amortize: Option<bool>,
    pub(super) glossy_pyramid: Option<String>,
    pub(super) quality: Option<String>,
    pub(super) level0: Option<String>,
    pub(super) horizon: Option<String>,
    pub(super) near_steps: Option<u32>,
    pub(super) radial_probes: Option<u32>,
    pub(super) radial_probes_later: Option<u32>,
    pub(super) cast_merge: Option<f64>,
    pub(super) replay: Option<bool>,
    pub(super) azimuths_later: Option<u32>,
    pub(super) azimuth_offset: Option<f64>,
    pub(super) scan_reach: Option<String>,
    pub(super) omega_min: Option<String>,
    pub(super) elevation_basis: Option<String>,
    pub(super) visibility: Option<String>,
    pub(super) diffuse_lobe: Option<String>,
    pub(super) storage: Option<String>,
    pub(super) shading_storage: Option<String>,
    pub(super) sweep_near: Option<u32>,
    pub(super) blocker_epsilon: Option<f64>,
    pub(super) blocker_ratio: Option<bool>,
    pub(super) blocker_exp: Option<String>,
    pub(super) blocker_shading: Option<String>,
    pub(super) blocker_log_cap: Option<String>,
    pub(super) blocker_key_lights: Option<String>,
}

#[derive(Deserialize, Default)]
#[serde(deny_unknown_fields)]
pub(super) struct RawSphere {
    pub(super) center: Option<[f64; 3]>,
    pub(super) radius: Option<f64>,
    pub(super) albedo: Option<[f64; 3]>,
}

#[derive(Deserialize, Default)]
#[serde(deny_unknown_fields)]
pub(super) struct RawCamera {
    pub(super) position: Option<[f64; 3]>,
    pub(super) target: Option<[f64; 3]>,
    pub(super) fov_deg: Option<f64>,
    pub(super) width: Option<u32>,
    pub(super) height: Option<u32>,
    pub(super) exposure: Option<f64>,
}

/// `[animation]`: the keys of every kind; [`Ctx::animation`](super::ctx::Ctx::animation) rejects those of another kind.
#[derive(Deserialize, Default)]
#[serde(deny_unknown_fields)]
pub(super) struct RawAnimation {
    pub(super) kind: Option<String>,
    pub(super) seed: Option<u64>,
    // water
    pub(super) speed: Option<f64>,
    pub(super) damping: Option<f64>,
    pub(super) steps_per_frame: Option<u32>,
    pub(super) rest_level: Option<f64>,
    pub(super) scale: Option<f64>,
    pub(super) rain_rate: Option<f64>,
    pub(super) drop_amplitude: Option<f64>,
    pub(super) drop_radius: Option<f64>,
    // bumps
    pub(super) count: Option<u32>,
    pub(super) radius: Option<f64>,
    pub(super) amplitude: Option<f64>,
    pub(super) period: Option<u32>,
    pub(super) travel: Option<f64>,
    pub(super) shape: Option<String>,
    // day
    pub(super) day_frames: Option<u32>,
    pub(super) max_elevation_deg: Option<f64>,
    pub(super) sweep_deg: Option<f64>,
    pub(super) orbit_turns: Option<f64>,
    // boulders
    pub(super) lap_frames: Option<u32>,
}

/// `n` (square) or `[w, h]`.
#[derive(Clone, Copy, Debug)]
pub(super) struct SizeSpec(pub(super) usize, pub(super) usize);

impl<'de> Deserialize<'de> for SizeSpec {
    fn deserialize<D: Deserializer<'de>>(d: D) -> std::result::Result<Self, D::Error> {
        struct V;
        impl<'de> Visitor<'de> for V {
            type Value = SizeSpec;
            fn expecting(&self, f: &mut std::fmt::Formatter) -> std::fmt::Result {
                f.write_str("a size n or [width, height] (non-negative integers)")
            }
            fn visit_i64<E: de::Error>(self, v: i64) -> std::result::Result<SizeSpec, E> {
                let n = usize::try_from(v).map_err(|_| E::invalid_value(de::Unexpected::Signed(v), &self))?;
                Ok(SizeSpec(n, n))
            }
            fn visit_u64<E: de::Error>(self, v: u64) -> std::result::Result<SizeSpec, E> {
                let n = usize::try_from(v).map_err(|_| E::invalid_value(de::Unexpected::Unsigned(v), &self))?;
                Ok(SizeSpec(n, n))
            }
            fn visit_seq<A: SeqAccess<'de>>(self, mut seq: A) -> std::result::Result<SizeSpec, A::Error> {
                let w: usize = seq.next_element()?.ok_or_else(|| de::Error::invalid_length(0, &self))?;
                let h: usize = seq.next_element()?.ok_or_else(|| de::Error::invalid_length(1, &self))?;
                if seq.next_element::<de::IgnoredAny>()?.is_some() {
                    return Err(de::Error::invalid_length(3, &self));
                }
                Ok(SizeSpec(w, h))
            }
        }
        d.deserialize_any(V)
    }
}
