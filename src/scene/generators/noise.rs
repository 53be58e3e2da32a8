//! The generators' deterministic noise: hashing, fbm octaves, plane waves and [`det_sin`].

use super::shapes::split;

const SALT_NOISE: u64 = 0x006e_6f69_7365;
const SALT_OFFSET: u64 = 0x6f66_6673_6574;
pub(super) const SALT_FEATURE: u64 = 0x6665_6174;
pub(super) const SALT_CITY: u64 = 0x6369_7479;

/// SplitMix64 finaliser: a bijective, well-mixing 64-bit hash.
fn mix(mut z: u64) -> u64 {
    z = z.wrapping_add(0x9E37_79B9_7F4A_7C15);
    z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
    z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
    z ^ (z >> 31)
}

/// Hash of a seed, two lattice coordinates and a salt.
pub(super) fn hash(seed: u64, a: i64, b: i64, salt: u64) -> u64 {
    mix(mix(mix(seed ^ salt) ^ a as u64) ^ (b as u64).rotate_left(32))
}

/// Uniform in `[0, 1)` from the top 53 bits of `h`.
pub(super) fn unit(h: u64) -> f64 {
    (h >> 11) as f64 * (1.0 / (1u64 << 53) as f64)
}

/// One fbm octave: seeded gradient noise at a given frequency, with a seeded fractional domain
/// offset (so lattice points, where gradient noise is 0, do not fall on texels).
pub(super) struct Octave {
    seed: u64,
    frequency: f64,
    offset: (f64, f64),
    pub(super) weight: f64,
}

impl Octave {
    pub(super) fn new(seed: u64, k: u32, frequency: f64) -> Self {
        let s = hash(seed, i64::from(k), 0, SALT_NOISE);
        let offset = (256.0 * unit(hash(s, 1, 0, SALT_OFFSET)), 256.0 * unit(hash(s, 2, 0, SALT_OFFSET)));
        let mut f = frequency;
        let mut weight = 1.0;
        for _ in 0..k {
            f *= 2.0;
            weight *= 0.5;
        }
        Self { seed: s, frequency: f, offset, weight }
    }

    /// Noise at `(u, v)` in units of the field width.
    pub(super) fn sample(&self, u: f64, v: f64) -> f64 {
        gradient_noise(self.seed, u * self.frequency + self.offset.0, v * self.frequency + self.offset.1)
    }
}

/// 2-D gradient (Perlin) noise with quintic fade, roughly in `[−1, 1]`; 0 at lattice points.
fn gradient_noise(seed: u64, x: f64, y: f64) -> f64 {
    const D: f64 = std::f64::consts::FRAC_1_SQRT_2;
    const GRAD: [(f64, f64); 8] =
        [(1.0, 0.0), (-1.0, 0.0), (0.0, 1.0), (0.0, -1.0), (D, D), (-D, D), (D, -D), (-D, -D)];
    let (ix, fx) = split(x);
    let (iy, fy) = split(y);
    let corner = |dx: i64, dy: i64| {
        let (gx, gy) = GRAD[(hash(seed, ix + dx, iy + dy, SALT_NOISE) >> 61) as usize];
        gx * (fx - dx as f64) + gy * (fy - dy as f64)
    };
    let fade = |t: f64| t * t * t * (t * (t * 6.0 - 15.0) + 10.0);
    let (sx, sy) = (fade(fx), fade(fy));
    let a = corner(0, 0) + sx * (corner(1, 0) - corner(0, 0));
    let b = corner(0, 1) + sx * (corner(1, 1) - corner(0, 1));
    std::f64::consts::SQRT_2 * (a + sy * (b - a))
}

/// One plane wave of [`Generator::Sines`](super::Generator::Sines).
pub(super) struct Wave {
    /// Wave vector in radians per texel.
    kx: f64,
    ky: f64,
    phase: f64,
}

impl Wave {
    pub(super) fn new(k: u32, frequency: f64, w: f64) -> Self {
        const GOLDEN_ANGLE: f64 = 2.399_963_229_728_653;
        let kf = f64::from(k);
        let angle = 0.6 + GOLDEN_ANGLE * kf;
        let omega = std::f64::consts::TAU * frequency * (1.0 + 0.5 * kf) / w;
        Self {
            kx: omega * det_sin(angle + std::f64::consts::FRAC_PI_2),
            ky: omega * det_sin(angle),
            phase: 0.4 + 1.7 * kf,
        }
    }

    pub(super) fn sample(&self, x: f64, y: f64) -> f64 {
        det_sin(self.kx * x + self.ky * y + self.phase)
    }
}

/// Platform-independent `sin` (absolute error < 1e-13 for |x| < 1e6): reduction to
/// `[−π/2, π/2]` with a two-part 2π, then a degree-19 Taylor polynomial, using only exactly
/// rounded IEEE operations (unlike `f64::sin`, which calls the platform libm).
pub fn det_sin(x: f64) -> f64 {
    const TAU_HI: f64 = std::f64::consts::TAU; // 2π rounded to f64; TAU_LO is the rest
    const TAU_LO: f64 = 2.449_293_598_294_706_4e-16;
    const PI: f64 = std::f64::consts::PI;
    if !x.is_finite() {
        return f64::NAN;
    }
    let k = (x / TAU_HI).round();
    let mut r = (x - k * TAU_HI) - k * TAU_LO; // in about [−π, π]
    if r > 0.5 * PI {
        r = PI - r;
    } else if r < -0.5 * PI {
        r = -PI - r;
    }
    let r2 = r * r;
    // Horner form of r·(1 − r²/(2·3)·(1 − r²/(4·5)·(… (1 − r²/(18·19))))), i.e. Taylor to r¹⁹.
    let mut p = 1.0;
    let mut n = 18.0;
    while n >= 2.0 {
        p = 1.0 - r2 / (n * (n + 1.0)) * p;
        n -= 2.0;
    }
    r * p
}
