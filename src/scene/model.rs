//! The in-memory scene: what a scene file (`docs/scene-format.md`) describes, after validation.
//! Passes and the CPU reference read these types; the TOML layer only fills them.

use std::str::FromStr;

use glam::DVec3;

use crate::error::{Error, Result};
pub use crate::scene::animated::Animation;
use crate::scene::HeightField;

/// How the height pyramid is stored and sampled (`gi.pyramid`).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum PyramidMode {
    /// Every level B-spline-synthesized to the working resolution (NS09 §9).
    #[default]
    Stack,
    /// Decimated levels only, B-spline filtered on the fly (NS09 §10).
    Pyramid,
}

impl FromStr for PyramidMode {
    type Err = Error;
    fn from_str(s: &str) -> Result<Self> {
        match s {
            "stack" => Ok(Self::Stack),
            "pyramid" => Ok(Self::Pyramid),
            _ => Err(Error::param("gi.pyramid", s, "`stack` or `pyramid`")),
        }
    }
}

impl std::fmt::Display for PyramidMode {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(match self {
            Self::Stack => "stack",
            Self::Pyramid => "pyramid",
        })
    }
}

/// Azimuthal interpolation of the per-direction NLP vectors inside a wedge (`gi.interpolation`).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum Interpolation {
    /// `M_lin` (eq. 20).
    #[default]
    Linear,
    /// `M_bspl` (Appendix A).
    Bspline,
}

impl FromStr for Interpolation {
    type Err = Error;
    fn from_str(s: &str) -> Result<Self> {
        match s {
            "linear" => Ok(Self::Linear),
            "bspline" => Ok(Self::Bspline),
            _ => Err(Error::param("gi.interpolation", s, "`linear` or `bspline`")),
        }
    }
}

impl std::fmt::Display for Interpolation {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(match self {
            Self::Linear => "linear",
            Self::Bspline => "bspline",
        })
    }
}

/// How glossy exit radiance enters the radiance pyramid (`gi.glossy_pyramid`, §5.3, fig. 5).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum GlossyPyramid {
    /// One RGB pyramid of diffuse + glossy-toward-the-camera exit radiance (the paper's
    /// cheaper approximation for mixtures).
    #[default]
    Scalar,
    /// The diffuse RGB pyramid plus a pyramid of the incident SH radiance; the glossy lobe is
    /// evaluated toward each receiver (converges to the ground truth).
    Vector,
}

impl FromStr for GlossyPyramid {
    type Err = Error;
    fn from_str(s: &str) -> Result<Self> {
        match s {
            "scalar" => Ok(Self::Scalar),
            "vector" => Ok(Self::Vector),
            _ => Err(Error::param("gi.glossy_pyramid", s, "`scalar` or `vector`")),
        }
    }
}

impl std::fmt::Display for GlossyPyramid {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(match self {
            Self::Scalar => "scalar",
            Self::Vector => "vector",
        })
    }
}

/// Declares a settings enum parsed from and printed as its TOML strings.
macro_rules! settings_enum {
    ($(#[$doc:meta])* $name:ident, $key:literal, $expected:literal, { $($(#[$vdoc:meta])* $var:ident = $text:literal),+ $(,)? }) => {
        $(#[$doc])*
        #[derive(Clone, Copy, Debug, PartialEq, Eq)]
        pub enum $name {
            $($(#[$vdoc])* $var),+
        }
        impl FromStr for $name {
            type Err = Error;
            fn from_str(s: &str) -> Result<Self> {
                match s {
                    $($text => Ok(Self::$var),)+
                    _ => Err(Error::param($key, s, $expected)),
                }
            }
        }
        impl std::fmt::Display for $name {
            fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
                f.write_str(match self {
                    $(Self::$var => $text),+
                })
            }
        }
    };
}

settings_enum!(
    /// Quality preset (`gi.quality`, docs/accuracy.md §4): a ladder of every accuracy knob.
    /// Explicit knobs override the preset's values.
    Quality, "gi.quality", "`draft`, `default`, `high`, `ultra` or `paper`", {
        Draft = "draft",
        Default = "default",
        High = "high",
        Ultra = "ultra",
        /// NS09 as published (§9 defaults, every accuracy fix off).
        Paper = "paper",
    }
);

settings_enum!(
    /// What level 0 of the height and radiance pyramids is (`gi.level0`).
    Level0, "gi.level0", "`bspline` or `bilinear`", {
        /// The approximating cubic B-spline of the samples (the paper's: smooths a one-texel
        /// cliff by a sixth of its height at top and foot).
        Bspline = "bspline",
        /// The bilinear surface of the samples themselves (CONVENTIONS.md's surface).
        Bilinear = "bilinear",
    }
);

settings_enum!(
    /// How `ω_max` follows from the scan's blocking angles (`gi.horizon`).
    Horizon, "gi.horizon", "`bspline` or `samples`", {
        /// Maximum of the cubic B-spline through the `ω_i` (eq. 17; never above the largest sample).
        Bspline = "bspline",
        /// The largest `ω_i` (consistent with the casting set, which uses the raw `ω_i`).
        Samples = "samples",
    }
);

settings_enum!(
    /// The far end of the scan ladder (`gi.scan_reach`).
    ScanReach, "gi.scan_reach", "`side` or `diagonal`", {
        /// `t ≤ max(W, H)` texels (the paper's ladder).
        Side = "side",
        /// `⌈k/2⌉` more samples, to `√2·max(W, H)`: diagonal rays reach the far corner.
        Diagonal = "diagonal",
    }
);

settings_enum!(
    /// The per-azimuth elevation basis (`gi.elevation_basis`, `math::elevation`).
    ElevationBasis, "gi.elevation_basis", "`nlp` or `legendre`", {
        /// `n` normalised Legendre polynomial coefficients in `z = sin ω` (the paper's §4).
        Nlp = "nlp",
        /// The `n(n+1)/2` integrals of `P_l^m` over each elevation interval: exact SH projection.
        Legendre = "legendre",
    }
);

settings_enum!(
    /// Lower end `ω_min` of the casting set (`gi.omega_min`).
    OmegaMin, "gi.omega_min", "`asin` or `tangent`", {
        /// `−asin(N · (cos φ, sin φ, 0))` (the paper's §3).
        Asin = "asin",
        /// The exact tangent elevation `atan2(−N·d, N_z)` (CONVENTIONS.md).
        Tangent = "tangent",
    }
);

settings_enum!(
    /// How environment and key-light visibility finds each receiver's horizon (`gi.visibility`,
    /// docs/direct.md §7).
    VisibilityMethod, "gi.visibility", "`ladder` or `sweep`", {
        /// The paper's multi-resolution scan of the height pyramid (eq. 14–17).
        Ladder = "ladder",
        /// Swept horizons: the level-0 surface marched exactly along each receiver's own ray for
        /// `sweep_near` texels, and beyond it line sweeps with a convex-hull stack (Timonen &
        /// Westerholm 2010) interpolated between the two lines beside a receiver; non-periodic
        /// fields only. The indirect casting set keeps the ladder.
        Sweep = "sweep",
    }
);

settings_enum!(
    /// The diffuse lobe the shading dots the incident SH radiance with (`gi.diffuse_lobe`,
    /// docs/accuracy.md §6).
    DiffuseLobe, "gi.diffuse_lobe", "`sh` or `exact`", {
        /// The clamped cosine `max(N·ω, 0)` as an order-n ZH (the paper's §7): truncated, it
        /// misses bands `l ≥ n` of the lobe, whose terms do not vanish where the incident light
        /// starts sharply at the tangent plane (the indirect light, an open sky).
        Sh = "sh",
        /// The cosine `N·ω` itself, a band-1 function: exact once the incident radiance is zero
        /// below the tangent plane, which the casting set is (`ω_min` tangent) and the
        /// visibility is made (its window starts no lower than the tangent elevation). Then only
        /// band 1 of the incident radiance matters: of `U` (stored to band 1) and of `L ⊛ V`,
        /// which is exact for lighting of order `n − 1` (use `sh_order` one above the lighting's).
        /// Diffuse shading only (a glossy lobe stays SH); full resolution (`subsample = 1`) and
        /// the tangent `ω_min` only; not with sphere blockers.
        Exact = "exact",
    }
);

settings_enum!(
    /// Storage of the visibility vectors `V`, the IR vectors `U` and the radiance stack
    /// (`gi.storage`, docs/performance.md §9): what the scans and the synthesis write and the
    /// scan and the shading read. The height pyramid is always f32.
    Storage, "gi.storage", "`f32` or `f16`", {
        /// 32-bit floats.
        F32 = "f32",
        /// IEEE half floats, two to a 32-bit word (`packHalf2x16`): half the memory, about
        /// 2⁻¹¹ relative rounding per stored value; the scans and the shading compute in f32.
        /// `U` and the radiance stack are pre-exposed (`frame::storage::pre_exposure`), so any
        /// light units fit the half's range. Every preset's default (docs/performance.md §14).
        F16 = "f16",
    }
);

impl Storage {
    /// Values one receiver's vector of `values` numbers occupies: rounded up to even with f16,
    /// so that a packed pair never straddles two receivers.
    pub fn stride(self, values: usize) -> usize {
        match self {
            Storage::F32 => values,
            Storage::F16 => values.div_ceil(2) * 2,
        }
    }
    /// Bytes of `values` stored values (whole 32-bit words).
    pub fn bytes(self, values: u64) -> u64 {
        match self {
            Storage::F32 => values * 4,
            Storage::F16 => values.div_ceil(2) * 4,
        }
    }
    /// The shaders' `HFGI_HALF` specialization constant.
    pub fn spec(self) -> u32 {
        u32::from(self == Storage::F16)
    }
}

settings_enum!(
    /// How a sphere blocker's log-SH visibility is exponentiated (`gi.blocker_exp`,
    /// docs/blockers.md §3; Ren et al. 2006).
    BlockerExp, "gi.blocker_exp", "`quadrature` or `linear`", {
        /// Exact SH exponentiation: `exp(f(ω))` at a product quadrature of the sphere,
        /// projected back to order n.
        Quadrature = "quadrature",
        /// Ren et al.'s optimal linear approximation with DC isolation:
        /// `e^{f_0/√4π}·(a(‖f̂‖)·1 + b(‖f̂‖)·f̂)`.
        Linear = "linear",
    }
);

settings_enum!(
    /// How sphere blockers shadow key lights (`gi.blocker_key_lights`, docs/blockers.md §3).
    BlockerKeyLights, "gi.blocker_key_lights", "`overlap` or `product`", {
        /// Per texel, the fraction of each key light's cap the spheres leave open (the exact
        /// solid angle of cap–cap overlap, `math::overlap`): sharp shadows.
        Overlap = "overlap",
        /// The key light's incident radiance times the spheres' order-n visibility `V_s` (an
        /// SH product): order-n soft shadows.
        Product = "product",
    }
);

settings_enum!(
    /// Which log-ZH stands for a sphere blocker's cap in the log modes (`gi.blocker_log_cap`,
    /// docs/blockers.md §2).
    BlockerLogCap, "gi.blocker_log_cap", "`epsilon` or `matched`", {
        /// Seed 001 eq. 24–26: `ln ε` times the cap's ZH (with `gi.blocker_ratio`, times `r/d`).
        Epsilon = "epsilon",
        /// Moment-matched (`math::logcap`): the log-ZH whose exponential has the n first
        /// Legendre moments of the sphere's true visibility `1 − cap`; no `ε`, no ratio.
        Matched = "matched",
    }
);

settings_enum!(
    /// How the sphere blockers' visibility is formed and meets the height field's
    /// (`gi.blocker_shading`, docs/blockers.md §4).
    BlockerShading, "gi.blocker_shading", "`log`, `log_field`, `log_brdf` or `primal`", {
        /// Log space (seed 001): the spheres' log-SH vectors summed, one exponentiation
        /// `V_s = exp*(Σ f_i)`; the incident radiance `T` times `V_s` (one SH product per texel).
        Log = "log",
        /// As `log`, and the environment's visibility joins the sum (seed 001 in full):
        /// `exp*(f_hf + Σ f_i)` with `f_hf = log ε·(1 − V_env)`; key lights as in `log`.
        LogField = "log_field",
        /// As `log_field`, and the environment's diffuse light in log space too (seed 001 §5):
        /// the transfer `exp*(f_hf + Σ f_i + f_ρ(N))` with the log-SH diffuse BRDF
        /// `f_ρ = ln max(cos θ/π, ε_ρ)` (`ε_ρ` = [`LOG_BRDF_EPSILON`]) dotted with the
        /// lighting: no triple product for it.
        LogBrdf = "log_brdf",
        /// Primal space: each sphere's exact visibility `1 − cap` (its order-n projection),
        /// multiplied together by SH products; no `ε`, no exponentiation.
        Primal = "primal",
    }
);

/// The floor `ε_ρ` of the log-SH diffuse BRDF `ln max(cos θ/π, ε_ρ)` (`gi.blocker_shading =
/// "log_brdf"`): small, since every direction where the cosine lobe is below it lets `ε_ρ`
/// through (`ε_ρ = 0.2` would add 2.5× the lobe's own weight over the sphere).
pub const LOG_BRDF_EPSILON: f64 = 0.01;

/// `gi.visibility = "sweep"` needs a non-periodic field: the error when `wrap` and `gi` combine
/// them (the scene parser and [`Scene::check_limits`] both ask here).
pub fn check_sweep(wrap: bool, gi: &GiSettings) -> Result<()> {
    if wrap && gi.visibility == VisibilityMethod::Sweep {
        return Err(Error::param(
            "gi.visibility",
            "sweep",
            "\"ladder\" on a periodic field (heightfield.wrap = true): the sweep supports non-periodic fields only",
        ));
    }
    Ok(())
}

/// The exact diffuse lobe needs the incident light zero below the shaded texel's tangent plane,
/// which the casting set is only with the tangent `ω_min` and at full resolution (a sub-sampled
/// receiver has its own normal: measured, `draft`'s indirect light went from 20–54% to 31–90%
/// error), and SH shading throughout, which the sphere blockers' log modes and transfers are not
/// (docs/accuracy.md §6).
pub fn check_lobe(gi: &GiSettings, spheres: usize) -> Result<()> {
    if gi.diffuse_lobe != DiffuseLobe::Exact {
        return Ok(());
    }
    if gi.omega_min != OmegaMin::Tangent {
        return Err(Error::param(
            "gi.diffuse_lobe",
            "exact",
            "\"sh\" with gi.omega_min = \"asin\": the exact lobe needs the tangent ω_min (gi.omega_min = \"tangent\")",
        ));
    }
    if gi.subsample != 1 {
        return Err(Error::param(
            "gi.diffuse_lobe",
            "exact",
            "\"sh\" with gi.subsample > 1: a sub-sampled receiver's tangent plane is not the shaded texel's (gi.subsample = 1)",
        ));
    }
    if spheres > 0 {
        return Err(Error::param("gi.diffuse_lobe", "exact", "\"sh\" in a scene with sphere blockers"));
    }
    Ok(())
}

/// Local lights need a non-periodic field (a periodic one would need every light repeated on
/// the torus; docs/local-lights.md).
pub fn check_local_wrap(wrap: bool, local_lights: usize) -> Result<()> {
    if wrap && local_lights > 0 {
        return Err(Error::param(
            "local_light",
            format!("{local_lights} local light(s) on a periodic field"),
            "a non-periodic field (heightfield.wrap = false): local lights are not repeated across a periodic field",
        ));
    }
    Ok(())
}

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
    /// wedges, in [0, 1): `φ_j = 2π(j + azimuth_offset)/m`. 0 is the paper's set, whose rays run
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
            Quality::Default => (4, (32, 32), 4, 6, 1, 4, 4, 4, (2, 0)),
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
            replay: true,
            scan_reach: if paper { ScanReach::Side } else { ScanReach::Diagonal },
            omega_min: if paper { OmegaMin::Asin } else { OmegaMin::Tangent },
            elevation_basis: if paper { ElevationBasis::Nlp } else { ElevationBasis::Legendre },
            visibility: VisibilityMethod::Ladder,
            diffuse_lobe: DiffuseLobe::Sh,
            storage: Storage::F16,
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
            sweep_near: self.sweep_near,
            replay: self.replay,
            ..GiSettings::preset(q)
        }
    }

    /// Every accuracy knob, resolved, on one line (`hfgi plan` and `hfgi bench` print it):
    /// `quality=… sh_order=… azimuths=… level_step=… …`.
    pub fn describe(&self) -> String {
        format!(
            "quality={} sh_order={} azimuths={} level_step={} level_offset={} subsample={} interpolation={} \
             pyramid={} radiance_level_step={} radiance_level_offset={} level0={} horizon={} near_steps={} \
             radial_probes={} radial_probes_later={} azimuths_later={} scan_reach={} omega_min={} elevation_basis={} visibility={} storage={} sweep_near={} key_light_azimuths={} bounces={} \
             local_light_azimuths={} blocker_epsilon={} blocker_ratio={} blocker_exp={} blocker_shading={} blocker_log_cap={} blocker_key_lights={} replay={} \
             diffuse_lobe={} azimuth_offset={}",
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
            self.azimuth_offset
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

/// Surface albedo: one RGB value or one per texel (linear RGB).
#[derive(Clone, Debug, PartialEq)]
pub enum Albedo {
    Constant([f32; 3]),
    /// Row-major, one RGB per height-field texel.
    Map(Vec<[f32; 3]>),
}

/// `[material]`: diffuse albedo plus an optional normalised Phong lobe.
#[derive(Clone, Debug, PartialEq)]
pub struct Material {
    pub albedo: Albedo,
    /// Phong specular colour k_s (None: diffuse only).
    pub specular: Option<[f32; 3]>,
    /// Phong exponent S (> 0).
    pub exponent: f32,
}

impl Default for Material {
    fn default() -> Self {
        Self { albedo: Albedo::Constant([0.8; 3]), specular: None, exponent: 32.0 }
    }
}

/// `[environment]`: SH radiance, `n²` RGB coefficients already multiplied by `intensity`
/// (index `k = l(l+1)+m`, CONVENTIONS.md). May hold more or fewer coefficients than the
/// rendering order: extra bands are ignored, missing ones are zero.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Environment {
    pub sh: Vec<[f64; 3]>,
}

/// `[[key_light]]`: a spherical cap light.
#[derive(Clone, Debug, PartialEq)]
pub struct KeyLight {
    /// Unit direction from the surface toward the light centre.
    pub direction: DVec3,
    /// Angular radius α in radians, in (0, π/2].
    pub angular_radius: f64,
    /// Uniform RGB radiance inside the cap.
    pub radiance: [f64; 3],
}

/// `[[local_light]]`: a sphere of uniform radiance at a finite distance (CONVENTIONS.md
/// "Lighting"; docs/local-lights.md). From a point at distance `d > r` from its centre it
/// subtends a cap of half-angle `asin(r/d)`.
#[derive(Clone, Debug, PartialEq)]
pub struct LocalLight {
    /// World position of the centre.
    pub position: DVec3,
    /// Radius in world units (> 0).
    pub radius: f64,
    /// Uniform RGB radiance of its surface.
    pub radiance: [f64; 3],
}

/// `[[sphere]]`: an opaque sphere blocker (CONVENTIONS.md "Lighting"; docs/blockers.md): it
/// blocks every ray that intersects it. Spheres do not reflect light onto the field (their
/// albedo shades them in the view image).
#[derive(Clone, Debug, PartialEq)]
pub struct SphereBlocker {
    /// World position of the centre.
    pub center: DVec3,
    /// Radius in world units (> 0).
    pub radius: f64,
    /// Diffuse albedo (view image).
    pub albedo: [f64; 3],
}

impl SphereBlocker {
    /// Sphere `k` of a scene of texel size `texel_size`: a centre within
    /// ±[`limits::MAX_COORDINATE`], a radius of [`limits::LOCAL_RADIUS_TEXELS`] texels, an
    /// albedo in [0, 1].
    pub fn check(&self, k: usize, texel_size: f64) -> Result<()> {
        let c = limits::MAX_COORDINATE;
        if !self.center.to_array().iter().all(|x| within(*x, -c, c)) {
            return Err(Error::param(
                format!("sphere {k} center"),
                format!("{:?}", self.center),
                format!("each within ±{c:e}"),
            ));
        }
        let (lo, hi) = limits::LOCAL_RADIUS_TEXELS;
        if !within(self.radius, lo * texel_size, hi * texel_size) {
            return Err(Error::param(
                format!("sphere {k} radius"),
                self.radius,
                format!(
                    "a number in [{:e}, {:e}] world units ({lo:e}..{hi:e} texels)",
                    lo * texel_size,
                    hi * texel_size
                ),
            ));
        }
        if !self.albedo.iter().all(|v| within(*v, 0.0, 1.0)) {
            return Err(Error::param(format!("sphere {k} albedo"), format!("{:?}", self.albedo), "each in [0, 1]"));
        }
        Ok(())
    }
}

/// `[camera]`: a pinhole camera for the view image and for view-dependent (glossy) shading.
#[derive(Clone, Debug, PartialEq)]
pub struct Camera {
    /// World position.
    pub position: DVec3,
    /// World point looked at.
    pub target: DVec3,
    /// Vertical field of view in degrees.
    pub fov_deg: f64,
    /// View image size in pixels.
    pub width: u32,
    pub height: u32,
    /// Tone-mapping exposure (stops) of the PNG.
    pub exposure: f32,
}

impl Camera {
    /// A camera looking at the middle of a `w × h` field (texel size `s`, height range
    /// `lo..hi`) from the south-west and above.
    pub fn default_for(w: usize, h: usize, s: f64, lo: f64, hi: f64) -> Self {
        let (cx, cy) = ((w as f64 - 1.0) * s * 0.5, (h as f64 - 1.0) * s * 0.5);
        let extent = (w.max(h) as f64) * s;
        let mid = 0.5 * (lo + hi);
        Self {
            position: DVec3::new(cx - 0.9 * extent, cy - 0.9 * extent, hi + 0.8 * extent),
            target: DVec3::new(cx, cy, mid),
            fov_deg: 40.0,
            width: 960,
            height: 540,
            exposure: -1.5,
        }
    }
}

/// Magnitude limits of a scene's numbers (docs/robustness.md, "No non-finite output"): within
/// them every stage — pyramids, scans, SH products, Phong lobes, bounces, the view image and
/// the tone map at ±[`MAX_EXPOSURE_STOPS`] — stays inside f32's range, so finite input never
/// gives NaN or infinite output. One table, used by the scene parser's messages.
pub mod limits {
    /// Largest |height| in world units, after `height_scale` and `height_offset` (hard cases
    /// use offsets of 10⁷ and amplitudes of 10⁶).
    pub const MAX_HEIGHT: f64 = 1e9;
    /// `heightfield.texel_size` range, world units.
    pub const TEXEL_SIZE: (f64, f64) = (1e-6, 1e6);
    /// Largest radiance: each environment SH coefficient (after `intensity`), each key light's
    /// radiance component. The sun is about 1.6·10⁹ W m⁻² sr⁻¹.
    pub const MAX_RADIANCE: f64 = 1e12;
    /// Largest `environment.intensity`.
    pub const MAX_INTENSITY: f64 = 1e6;
    /// Largest Phong specular colour component `k_s`.
    pub const MAX_SPECULAR: f64 = 1e3;
    /// Largest Phong exponent `S` (its lobe is a delta far below this at SH order 8).
    pub const MAX_EXPONENT: f64 = 1e4;
    /// Largest |coordinate| of the camera's position and target, world units.
    pub const MAX_COORDINATE: f64 = 1e10;
    /// Largest |exposure| in stops (`camera.exposure`, `--exposure`).
    pub const MAX_EXPOSURE_STOPS: f64 = 64.0;
    /// `material.exponent` range (below it the lobe's normalisation loses every digit in f32).
    pub const EXPONENT: (f64, f64) = (1e-3, MAX_EXPONENT);
    /// `key_light.N.angular_radius_deg` range, degrees (the sun is 0.27°; a radius that
    /// rounds to 0 in f32 would make a zero-width cap).
    pub const ANGULAR_RADIUS_DEG: (f64, f64) = (1e-3, 90.0);
    /// `camera.fov_deg` range, degrees (the projection's `1/tan(fov/2)` stays in f32).
    pub const FOV_DEG: (f64, f64) = (0.01, 179.0);
    /// `animation.radius` range (bumps), fraction of the width (a radius that rounds to 0
    /// divides by zero in the bump profile).
    pub const BUMP_RADIUS: (f64, f64) = (1e-3, 1.0);
    /// `local_light.N.radius` range as a multiple of the texel size (a radius that rounds to
    /// 0 in f32 would make a zero-size light; one over 10⁶ texels is no longer local).
    pub const LOCAL_RADIUS_TEXELS: (f64, f64) = (1e-3, 1e6);
    /// Largest |azimuth| in degrees (`key_light.N.azimuth_deg`).
    pub const MAX_AZIMUTH_DEG: f64 = 360.0;
    /// Largest |world units per simulation unit| of the water (`animation.scale`), and of it
    /// times the drop amplitude (`animation.drop_amplitude`): the waves stay far inside
    /// [`MAX_HEIGHT`].
    pub const MAX_MOTION: f64 = 1e6;
    /// Largest |bump amplitude| as a fraction of the width (`animation.amplitude`): at most
    /// 1.6·10⁷ world units on a 16384-wide field of unit texels.
    pub const MAX_BUMP_AMPLITUDE: f64 = 1e3;

    /// Every height of `field` within ±[`MAX_HEIGHT`], else an error naming the first texel
    /// past it (heights near f32's limit pass the finiteness check but overflow in the scans).
    pub fn check_heights(field: &crate::scene::HeightField) -> crate::Result<()> {
        let Some(k) = field.data().iter().position(|v| f64::from(*v).abs() > MAX_HEIGHT) else { return Ok(()) };
        let (x, y) = (k % field.width(), k / field.width());
        Err(crate::Error::param(
            format!("height at (x={x}, y={y})"),
            field.data()[k],
            format!("within ±{MAX_HEIGHT:e} world units (scale the heights down or use larger units)"),
        ))
    }
}

fn within(v: f64, lo: f64, hi: f64) -> bool {
    v.is_finite() && v >= lo && v <= hi
}

impl Environment {
    /// The environment rotated by `r` (row-major rotation matrix): the radiance it had in
    /// direction `d` arrives from `R·d` (exact per SH band, [`crate::math::sh::rotate`]);
    /// order `n` = the coefficients given, rounded down to a square.
    pub fn rotated(&self, r: [[f64; 3]; 3]) -> Environment {
        let n = (self.sh.len() as f64).sqrt().floor() as usize;
        if n == 0 {
            return self.clone();
        }
        let per: Vec<Vec<f64>> =
            (0..3).map(|c| crate::math::sh::rotate(n, &self.sh.iter().map(|v| v[c]).collect::<Vec<_>>(), r)).collect();
        Environment { sh: (0..n * n).map(|k| [per[0][k], per[1][k], per[2][k]]).collect() }
    }

    /// The environment times `intensity` (every coefficient).
    pub fn scaled(&self, intensity: f64) -> Environment {
        Environment { sh: self.sh.iter().map(|c| c.map(|v| v * intensity)).collect() }
    }

    /// Every coefficient within ±[`limits::MAX_RADIANCE`] (also for live changes,
    /// `Renderer::set_environment`).
    pub fn check(&self) -> Result<()> {
        let m = limits::MAX_RADIANCE;
        if let Some(k) = self.sh.iter().position(|c| !c.iter().all(|v| within(*v, -m, m))) {
            return Err(Error::param(
                format!("environment SH coefficient {k}"),
                format!("{:?}", self.sh[k]),
                format!("each within ±{m:e}"),
            ));
        }
        Ok(())
    }
}

impl KeyLight {
    /// Key light `k`: radiance in [0, [`limits::MAX_RADIANCE`]], a finite non-zero direction,
    /// an angular radius within [`limits::ANGULAR_RADIUS_DEG`].
    pub fn check(&self, k: usize) -> Result<()> {
        let m = limits::MAX_RADIANCE;
        if !self.radiance.iter().all(|v| within(*v, 0.0, m)) {
            return Err(Error::param(
                format!("key light {k} radiance"),
                format!("{:?}", self.radiance),
                format!("each in [0, {m:e}]"),
            ));
        }
        let d = self.direction;
        if !(d.is_finite() && d.length() > 1e-12) {
            return Err(Error::param(
                format!("key light {k} direction"),
                format!("{d:?}"),
                "a finite, non-zero vector",
            ));
        }
        let (lo, hi) = limits::ANGULAR_RADIUS_DEG;
        if !within(self.angular_radius, lo.to_radians() * (1.0 - 1e-12), hi.to_radians() * (1.0 + 1e-12)) {
            return Err(Error::param(
                format!("key light {k} angular radius"),
                format!("{}°", self.angular_radius.to_degrees()),
                format!("a number in [{lo}, {hi}] degrees"),
            ));
        }
        Ok(())
    }
}

impl LocalLight {
    /// Local light `k` of a scene of texel size `texel_size`: radiance in [0,
    /// [`limits::MAX_RADIANCE`]], a position within ±[`limits::MAX_COORDINATE`], a radius of
    /// [`limits::LOCAL_RADIUS_TEXELS`] texels.
    pub fn check(&self, k: usize, texel_size: f64) -> Result<()> {
        let m = limits::MAX_RADIANCE;
        if !self.radiance.iter().all(|v| within(*v, 0.0, m)) {
            return Err(Error::param(
                format!("local light {k} radiance"),
                format!("{:?}", self.radiance),
                format!("each in [0, {m:e}]"),
            ));
        }
        let c = limits::MAX_COORDINATE;
        if !self.position.to_array().iter().all(|x| within(*x, -c, c)) {
            return Err(Error::param(
                format!("local light {k} position"),
                format!("{:?}", self.position),
                format!("each coordinate within ±{c:e}"),
            ));
        }
        let (lo, hi) = limits::LOCAL_RADIUS_TEXELS;
        if !within(self.radius, lo * texel_size, hi * texel_size) {
            return Err(Error::param(
                format!("local light {k} radius"),
                self.radius,
                format!(
                    "a number in [{:e}, {:e}] world units ({lo:e}..{hi:e} texels)",
                    lo * texel_size,
                    hi * texel_size
                ),
            ));
        }
        Ok(())
    }
}

impl Material {
    /// The Phong exponent within [`limits::EXPONENT`], specular within [0,
    /// [`limits::MAX_SPECULAR`]], a constant albedo finite and ≥ 0.
    pub fn check(&self) -> Result<()> {
        let (elo, ehi) = limits::EXPONENT;
        if !within(f64::from(self.exponent), elo, ehi) {
            return Err(Error::param("material exponent", self.exponent, format!("a number in [{elo}, {ehi}]")));
        }
        if let Some(sp) = self.specular {
            if !sp.iter().all(|v| within(f64::from(*v), 0.0, limits::MAX_SPECULAR)) {
                return Err(Error::param(
                    "material specular",
                    format!("{sp:?}"),
                    format!("each in [0, {:e}]", limits::MAX_SPECULAR),
                ));
            }
        }
        if let Albedo::Constant(a) = self.albedo {
            if !a.iter().all(|v| within(f64::from(*v), 0.0, f64::from(f32::MAX))) {
                return Err(Error::param("material albedo", format!("{a:?}"), "finite, each ≥ 0"));
            }
        }
        Ok(())
    }
}

impl Camera {
    /// Position and target within ±[`limits::MAX_COORDINATE`].
    pub fn check(&self) -> Result<()> {
        let c = limits::MAX_COORDINATE;
        for (name, v) in [("camera position", self.position), ("camera target", self.target)] {
            if !v.to_array().iter().all(|x| within(*x, -c, c)) {
                return Err(Error::param(name, format!("{v:?}"), format!("each coordinate within ±{c:e}")));
            }
        }
        Ok(())
    }
}

/// A complete, validated scene.
#[derive(Clone, Debug)]
pub struct Scene {
    pub field: HeightField,
    /// World size of one texel (`s` in CONVENTIONS.md).
    pub texel_size: f64,
    /// Periodic height field.
    pub wrap: bool,
    pub material: Material,
    pub environment: Environment,
    pub key_lights: Vec<KeyLight>,
    /// `[[local_light]]`s (docs/local-lights.md).
    pub local_lights: Vec<LocalLight>,
    /// `[[sphere]]` blockers (docs/blockers.md).
    pub spheres: Vec<SphereBlocker>,
    pub gi: GiSettings,
    pub camera: Camera,
    /// `[animation]`: what moves (`Animation::None` for a static scene).
    pub animation: Animation,
}

impl Scene {
    /// The magnitude limits of [`limits`] on a scene built in code (the scene parser checks
    /// them key by key with the key's name): heights, texel size, radiances, the Phong lobe,
    /// the camera. `Renderer::new` calls it, so an embedder's scene cannot reach NaN through
    /// magnitudes either.
    pub fn check_limits(&self) -> Result<()> {
        limits::check_heights(&self.field)?;
        let (lo, hi) = limits::TEXEL_SIZE;
        if !within(self.texel_size, lo, hi) {
            return Err(Error::param("texel_size", self.texel_size, format!("a number in [{lo:e}, {hi:e}]")));
        }
        self.environment.check()?;
        for (k, l) in self.key_lights.iter().enumerate() {
            l.check(k)?;
        }
        for (k, l) in self.local_lights.iter().enumerate() {
            l.check(k, self.texel_size)?;
        }
        check_local_wrap(self.wrap, self.local_lights.len())?;
        for (k, b) in self.spheres.iter().enumerate() {
            b.check(k, self.texel_size)?;
        }
        self.material.check()?;
        self.camera.check()?;
        check_sweep(self.wrap, &self.gi)?;
        check_lobe(&self.gi, self.spheres.len())
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
