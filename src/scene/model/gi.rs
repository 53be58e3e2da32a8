//! [`GiSettings`]: the `[gi]` table, its quality presets and its checks.

use super::{
    BlockerExp, BlockerKeyLights, BlockerLogCap, BlockerShading, DiffuseLobe, ElevationBasis, GlossyPyramid, Horizon,
    Interpolation, Level0, OmegaMin, PyramidMode, Quality, ScanReach, ShadingFormat, ShadingStorage, Storage,
    VisibilityMethod,
};
use crate::error::{Error, Result};

/// Algorithm settings (`[gi]`). Defaults are the paper's (§9).
#[derive(Clone, Debug, PartialEq)]
pub struct GiSettings {
    /// SH order n (bands 0..n−1, n² coefficients), 2..=8.
    pub sh_order: usize,
    /// Azimuthal samples m for environment visibility and the first bounce's indirect scan,
    /// 4..=256.
    pub azimuths: u32,
    /// Azimuthal samples of the indirect scans of bounces 2 and later, 4..=256, at most
    /// [`GiSettings::azimuths`] ([`GiSettings::scan_azimuths`]): later bounces carry less light
    /// (docs/performance.md §12).
    pub azimuths_later: u32,
    /// Rotation of the environment's azimuth set (its visibility and every indirect scan), in
    /// wedges of the first set, in [0, 1): `φ_j = 2π(j + azimuth_offset)/m`; a set of
    /// `gi.azimuths_later` samples is turned by the same angle, so that it is a subset of the
    /// first when its count divides `m` (`rules::lighting::environment_set`). 0 is the paper's set, whose rays run
    /// along the grid's axes and diagonals; `default` uses 0.5, every ray between them, which
    /// lowered its direct and indirect error on every field measured (docs/accuracy.md §7); the
    /// other presets 0 (mixed there).
    pub azimuth_offset: f64,
    /// Azimuthal samples per key light, 2..=64.
    pub key_light_azimuths: u32,
    /// Azimuthal samples per local light and receiver, 2..=64 (docs/local-lights.md).
    pub local_light_azimuths: u32,
    /// Pyramid level step k_v, 1..=32.
    pub level_step: u32,
    /// Level offset o_v, 0..=8.
    pub level_offset: u32,
    /// Visibility sub-sampling: 1, 2 or 4.
    pub subsample: u32,
    pub interpolation: Interpolation,
    pub pyramid: PyramidMode,
    /// Indirect bounces, 0..=16 (0: direct light only).
    pub bounces: u32,
    /// Radiance-pyramid level step k_u, 1..=16 (§5.3).
    pub radiance_level_step: u32,
    /// Radiance-pyramid level offset o_u, 0..=8 (§5.3).
    pub radiance_level_offset: u32,
    /// Amortised shading (§7): with static heights, even frames update the direct shading
    /// and odd frames the indirect; when heights change, both.
    pub amortize: bool,
    /// Glossy radiance pyramid (§5.3): scalar approximation or SH vector pyramid.
    pub glossy_pyramid: GlossyPyramid,
    /// The preset the knobs below (and m, k, o, sub-sampling, radiance k_u, o_u) came from.
    pub quality: Quality,
    /// Level 0 of the pyramids: B-spline or the bilinear surface (docs/accuracy.md §4).
    pub level0: Level0,
    /// `ω_max` from the blocking angles: eq. 17's spline or the largest sample.
    pub horizon: Horizon,
    /// Scan samples inside the first texel, `t = 2^(−j/k)` for `j = 1..=near_steps`, 0..=64.
    pub near_steps: u32,
    /// Level-0 probes between two ladder samples more than a texel apart, 0..=16, at most one
    /// per texel of the gap (docs/accuracy.md §4: thin spikes between the ladder's samples), in
    /// the first bounce's indirect scan.
    pub radial_probes: u32,
    /// The same for the scans of bounces 2 and later (which carry less light), 0..=16.
    pub radial_probes_later: u32,
    /// The cast merge `δ` of the first bounce's indirect scan (radians, [0, 0.2]): a
    /// casting-set member less than `δ` above the last member cast is not cast; the next one
    /// cast covers its interval with its own radiance (the ray's last member held is cast at its
    /// end). 0: every member is cast (docs/indirect.md §2, "Merged casts"; docs/performance.md
    /// §33). The later bounces cast every member.
    pub cast_merge: f64,
    /// Bounces 2 and later cast the casting sets the first bounce's walk recorded instead of
    /// walking their rays (the same members; `rules::scene::replays`: without later probes,
    /// within a memory budget; docs/indirect.md §2).
    pub replay: bool,
    /// Far end of the ladder.
    pub scan_reach: ScanReach,
    /// Lower end of the casting set.
    pub omega_min: OmegaMin,
    /// Elevation basis of the per-azimuth vectors.
    pub elevation_basis: ElevationBasis,
    /// Horizons of the environment and key-light visibility: the ladder scan or line sweeps.
    pub visibility: VisibilityMethod,
    /// The diffuse lobe of the shading: the order-n clamped-cosine ZH or the exact cosine.
    pub diffuse_lobe: DiffuseLobe,
    /// Storage of the visibility and IR vectors and the radiance stack (f16 by default, at
    /// half the memory of f32).
    pub storage: Storage,
    /// The shading planes' storage: f32, RGBE (a third of the memory), or by default `auto`
    /// (f32 at full rate, RGBE sub-sampled; [`GiSettings::shading_format`]).
    pub shading_storage: ShadingStorage,
    /// With the sweep: texels along each receiver's own ray marched exactly (the near field,
    /// docs/direct.md §7), 0..=64; the sweep lines give the horizon beyond.
    pub sweep_near: u32,
    /// Sphere blockers: the visibility `ε` of a blocked direction in log space (`log ε`
    /// replaces `−∞`), in (0, 1); the paper's figures use 0.2 (docs/blockers.md).
    pub blocker_epsilon: f64,
    /// Sphere blockers: scale each sphere's log-SH vector by `r/d` (seed 001's "ratio
    /// attenuation").
    pub blocker_ratio: bool,
    pub blocker_exp: BlockerExp,
    pub blocker_shading: BlockerShading,
    /// Sphere blockers, log modes: the spheres' log-ZH (seed 001's `ε` form or moment-matched).
    pub blocker_log_cap: BlockerLogCap,
    /// Sphere blockers: key lights shadowed by the exact cap overlap or the SH product.
    pub blocker_key_lights: BlockerKeyLights,
}

impl Default for GiSettings {
    /// The `default` preset.
    fn default() -> Self {
        Self::preset(Quality::Default)
    }
}

impl GiSettings {
    /// The knobs of a quality preset (docs/accuracy.md §4 documents and measures the ladder).
    /// Scene content (bounces, key-light azimuths, glossy pyramid, amortisation, the pyramid
    /// mode) is not part of a preset; the SH order is (`high` uses order 6 and `ultra` order 8,
    /// which lowers the SH truncation floor against the exact reference; an order-4 environment
    /// is used as given, its higher bands zero).
    pub fn preset(q: Quality) -> Self {
        // (n, m: first bounce and later, k, o, sub-sampling, k_u, o_u, near steps, radial
        // probes: first bounce, later)
        let (n, (m, m_later), k, o, sub, ku, ou, near, probes) = match q {
            Quality::Draft => (4, (16, 16), 2, 4, 2, 2, 2, 2, (0, 0)),
            Quality::Default => (4, (32, 16), 4, 6, 1, 4, 4, 4, (2, 0)),
            Quality::Paper => (4, (32, 32), 4, 2, 1, 4, 2, 0, (0, 0)),
            Quality::High => (6, (64, 64), 12, 8, 1, 8, 6, 16, (4, 0)),
            Quality::Ultra => (8, (128, 128), 24, 8, 1, 16, 8, 64, (0, 0)),
        };
        // Azimuths per local light (docs/local-lights.md §5: direct error 0.13–0.9% at 8,
        // 0.02–0.26% at 16 on the hard fields).
        let local = match q {
            Quality::Draft => 4,
            Quality::Default | Quality::Paper => 8,
            Quality::High => 16,
            Quality::Ultra => 32,
        };
        let paper = q == Quality::Paper;
        Self {
            sh_order: n,
            azimuths: m,
            azimuths_later: m_later,
            // Where it was measured to lower the error (docs/accuracy.md §7).
            azimuth_offset: if q == Quality::Default { 0.5 } else { 0.0 },
            key_light_azimuths: 3,
            local_light_azimuths: local,
            level_step: k,
            level_offset: o,
            subsample: sub,
            interpolation: Interpolation::Linear,
            pyramid: PyramidMode::Stack,
            bounces: 0,
            radiance_level_step: ku,
            radiance_level_offset: ou,
            amortize: true,
            glossy_pyramid: GlossyPyramid::Scalar,
            quality: q,
            level0: if paper { Level0::Bspline } else { Level0::Bilinear },
            horizon: if paper { Horizon::Bspline } else { Horizon::Samples },
            near_steps: if paper { 0 } else { near },
            radial_probes: probes.0,
            radial_probes_later: probes.1,
            // Measured on `default` only (docs/performance.md §33).
            cast_merge: if q == Quality::Default { 0.01 } else { 0.0 },
            replay: true,
            scan_reach: if paper { ScanReach::Side } else { ScanReach::Diagonal },
            omega_min: if paper { OmegaMin::Asin } else { OmegaMin::Tangent },
            elevation_basis: if paper { ElevationBasis::Nlp } else { ElevationBasis::Legendre },
            visibility: VisibilityMethod::Ladder,
            diffuse_lobe: DiffuseLobe::Sh,
            storage: Storage::F16,
            shading_storage: ShadingStorage::Auto,
            sweep_near: 16,
            blocker_epsilon: 0.2,
            blocker_ratio: true,
            blocker_exp: BlockerExp::Quadrature,
            blocker_shading: BlockerShading::Primal,
            blocker_log_cap: BlockerLogCap::Epsilon,
            blocker_key_lights: BlockerKeyLights::Overlap,
        }
    }

    /// The knobs of preset `q` with this configuration's scene content (bounces, key-light
    /// azimuths, pyramid mode, glossy pyramid, amortisation), which presets do not set.
    pub fn with_quality(&self, q: Quality) -> GiSettings {
        GiSettings {
            bounces: self.bounces,
            key_light_azimuths: self.key_light_azimuths,
            blocker_epsilon: self.blocker_epsilon,
            blocker_ratio: self.blocker_ratio,
            blocker_exp: self.blocker_exp,
            blocker_shading: self.blocker_shading,
            blocker_log_cap: self.blocker_log_cap,
            blocker_key_lights: self.blocker_key_lights,
            pyramid: self.pyramid,
            glossy_pyramid: self.glossy_pyramid,
            amortize: self.amortize,
            visibility: self.visibility,
            storage: self.storage,
            shading_storage: self.shading_storage,
            sweep_near: self.sweep_near,
            replay: self.replay,
            ..GiSettings::preset(q)
        }
    }

    /// The shading planes' texel format: `gi.shading_storage` resolved against `gi.subsample`.
    pub fn shading_format(&self) -> ShadingFormat {
        self.shading_storage.resolve(self.subsample)
    }

    /// Every accuracy knob, resolved, on one line (`hfgi plan` and `hfgi bench` print it):
    /// `quality=… sh_order=… azimuths=… level_step=… …`.
    pub fn describe(&self) -> String {
        format!(
            "quality={} sh_order={} azimuths={} level_step={} level_offset={} subsample={} interpolation={} \
             pyramid={} radiance_level_step={} radiance_level_offset={} level0={} horizon={} near_steps={} \
             radial_probes={} radial_probes_later={} azimuths_later={} scan_reach={} omega_min={} elevation_basis={} visibility={} storage={} shading_storage={} sweep_near={} key_light_azimuths={} bounces={} \
             local_light_azimuths={} blocker_epsilon={} blocker_ratio={} blocker_exp={} blocker_shading={} blocker_log_cap={} blocker_key_lights={} replay={} \
             diffuse_lobe={} azimuth_offset={} cast_merge={}",
            self.quality,
            self.sh_order,
            self.azimuths,
            self.level_step,
            self.level_offset,
            self.subsample,
            self.interpolation,
            self.pyramid,
            self.radiance_level_step,
            self.radiance_level_offset,
            self.level0,
            self.horizon,
            self.near_steps,
            self.radial_probes,
            self.radial_probes_later,
            self.azimuths_later,
            self.scan_reach,
            self.omega_min,
            self.elevation_basis,
            self.visibility,
            self.storage,
            self.shading_format(),
            self.sweep_near,
            self.key_light_azimuths,
            self.bounces,
            self.local_light_azimuths,
            self.blocker_epsilon,
            self.blocker_ratio,
            self.blocker_exp,
            self.blocker_shading,
            self.blocker_log_cap,
            self.blocker_key_lights,
            self.replay,
            self.diffuse_lobe,
            self.azimuth_offset,
            self.cast_merge
        )
    }

    /// Radial probes of bounce `bounce` (1-based) ([`GiSettings::radial_probes`], `_later`).
    pub fn probes(&self, bounce: u32) -> u32 {
        if bounce <= 1 {
            self.radial_probes
        } else {
            self.radial_probes_later
        }
    }

    /// The cast merge of bounce `bounce` (1-based): [`GiSettings::cast_merge`] in the first
    /// bounce, 0 in the later ones (docs/indirect.md §2, "Merged casts").
    pub fn merge(&self, bounce: u32) -> f64 {
        if bounce <= 1 {
            self.cast_merge
        } else {
            0.0
        }
    }

    /// Azimuths of bounce `bounce`'s indirect scan (1-based): [`GiSettings::azimuths`] for the
    /// first, [`GiSettings::azimuths_later`] (at most `azimuths`) for the later ones.
    pub fn scan_azimuths(&self, bounce: u32) -> u32 {
        if bounce <= 1 {
            self.azimuths
        } else {
            self.azimuths_later.min(self.azimuths)
        }
    }

    /// Scan samples past `t = max(W, H)` texels: `⌈k/2⌉` with [`ScanReach::Diagonal`].
    pub fn far_steps(&self) -> u32 {
        match self.scan_reach {
            ScanReach::Side => 0,
            ScanReach::Diagonal => self.level_step.div_ceil(2),
        }
    }
}

impl GiSettings {
    /// Checks every range; errors name the key (`gi.azimuths` ...).
    pub fn validate(&self) -> Result<()> {
        let check = |key: &str, v: u32, lo: u32, hi: u32| {
            if v < lo || v > hi {
                Err(Error::param(key, v, format!("an integer in {lo}..={hi}")))
            } else {
                Ok(())
            }
        };
        check("gi.sh_order", u32::try_from(self.sh_order).unwrap_or(u32::MAX), 2, crate::constants::MAX_SH_ORDER)?;
        check("gi.azimuths", self.azimuths, 4, 256)?;
        check("gi.azimuths_later", self.azimuths_later, 4, 256)?;
        check("gi.key_light_azimuths", self.key_light_azimuths, 2, 64)?;
        check("gi.local_light_azimuths", self.local_light_azimuths, 2, 64)?;
        check("gi.level_step", self.level_step, 1, 32)?;
        check("gi.level_offset", self.level_offset, 0, 8)?;
        if ![1, 2, 4].contains(&self.subsample) {
            return Err(Error::param("gi.subsample", self.subsample, "1, 2 or 4"));
        }
        check("gi.bounces", self.bounces, 0, 16)?;
        check("gi.radiance_level_step", self.radiance_level_step, 1, 16)?;
        check("gi.radiance_level_offset", self.radiance_level_offset, 0, 8)?;
        check("gi.near_steps", self.near_steps, 0, 64)?;
        check("gi.radial_probes", self.radial_probes, 0, 16)?;
        check("gi.radial_probes_later", self.radial_probes_later, 0, 16)?;
        check("gi.sweep_near", self.sweep_near, 0, 64)?;
        let a = self.azimuth_offset;
        if !(a.is_finite() && (0.0..1.0).contains(&a)) {
            return Err(Error::param("gi.azimuth_offset", a, "a number of wedges in [0, 1)"));
        }
        let c = self.cast_merge;
        if !(c.is_finite() && (0.0..=0.2).contains(&c)) {
            return Err(Error::param("gi.cast_merge", c, "an angle in [0, 0.2] radians"));
        }
        let e = self.blocker_epsilon;
        if !(e.is_finite() && (1e-6..1.0).contains(&e)) {
            return Err(Error::param("gi.blocker_epsilon", e, "a number in [1e-6, 1)"));
        }
        Ok(())
    }

    /// Working (visibility) grid for a `w × h` field: `ceil(w/s) × ceil(h/s)`, at least 2×2.
    pub fn working_size(&self, w: usize, h: usize) -> (usize, usize) {
        let s = self.subsample.max(1) as usize;
        (w.div_ceil(s).max(2), h.div_ceil(s).max(2))
    }
}
