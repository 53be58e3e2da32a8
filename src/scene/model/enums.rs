//! The `[gi]` settings enums, parsed from and printed as their TOML strings.

use std::str::FromStr;

use crate::error::{Error, Result};

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

/// The texel format of the shading planes, the renderer's output (docs/integration.md,
/// "Shading buffer"; docs/performance.md §36): what [`ShadingStorage`] resolves to, so not itself
/// a setting (no parser); printed as `gi.shading_storage`'s value. The EXR export is f32 either
/// way.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum ShadingFormat {
    /// One shared-exponent word per texel, 4 bytes (`crate::math::rgbe`, Ward's RGBE:
    /// 8-bit mantissas, an 8-bit exponent): a third of f32's memory, 8 significant bits of
    /// the largest channel (0.15–0.3% relative L2 per layer, which raises the total's error
    /// by 0.009–0.02 points on the hard fields), f32's range (no pre-exposure), negative
    /// channels clamped to 0, a non-finite texel read as NaN.
    Rgbe,
    /// An RGB `f32` triple per texel, 12 bytes.
    F32,
}

/// Printed as the `gi.shading_storage` value that forces it (one spelling, the setting's).
impl std::fmt::Display for ShadingFormat {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        ShadingStorage::from(*self).fmt(f)
    }
}

settings_enum!(
    /// How the shading planes are stored (`gi.shading_storage`; docs/performance.md §36–§37):
    /// a [`ShadingFormat`], or chosen from the sub-sampling.
    ShadingStorage, "gi.shading_storage", "`auto`, `f32` or `rgbe`", {
        /// [`ShadingFormat::F32`] with full-rate GI (`gi.subsample = 1`), [`ShadingFormat::Rgbe`]
        /// when it is sub-sampled: there the sub-sampling's interpolation adds 190–5400× the
        /// error RGBE's rounding does (docs/performance.md §37). Every preset's default.
        Auto = "auto",
        /// Always [`ShadingFormat::F32`].
        F32 = "f32",
        /// Always [`ShadingFormat::Rgbe`].
        Rgbe = "rgbe",
    }
);

/// The setting that forces a format.
impl From<ShadingFormat> for ShadingStorage {
    fn from(format: ShadingFormat) -> Self {
        match format {
            ShadingFormat::F32 => Self::F32,
            ShadingFormat::Rgbe => Self::Rgbe,
        }
    }
}

impl ShadingStorage {
    /// The planes' format with GI sub-sampled by `subsample` (`gi.subsample`).
    pub fn resolve(self, subsample: u32) -> ShadingFormat {
        match self {
            Self::Auto if subsample > 1 => ShadingFormat::Rgbe,
            Self::Auto | Self::F32 => ShadingFormat::F32,
            Self::Rgbe => ShadingFormat::Rgbe,
        }
    }
}

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
