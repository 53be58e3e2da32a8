// hfgi — the per-azimuth elevation basis (src/math/elevation.rs; docs/accuracy.md §4).
// Requires the specialization constants HFGI_N (SH order n) and HFGI_NE (values per azimuth,
// math::elevation::gpu_size: n for the paper's NLP basis, the 2n + 1 Fourier moments for the
// `legendre` basis, whose wedge matrices the host has multiplied by the Fourier table).
#ifndef HFGI_ELEVATION_GLSL
#define HFGI_ELEVATION_GLSL
#include "hfgi_nlp.glsl"

// The 2n + 1 Fourier moments of the indicator of [a, b] (math::elevation::fourier_moments):
// [Δ, (2/k) sin(kΔ/2) cos kμ, (2/k) sin(kΔ/2) sin kμ], k = 1..n, Δ = b − a, μ = (a + b)/2. Every
// term is proportional to sin(kΔ/2), so a thin interval keeps its precision relative to its own
// width; sin(kΔ/2), cos kμ, sin kμ by rotation (angle addition). The integrals
// e_lm = Σ_f T[lm][f] · moment_f never appear: the host folds T into the wedge matrices.
void hfgi_fourier_moments(float a, float b, out float e[HFGI_NE]) {
    for (int i = 0; i < HFGI_NE; ++i) e[i] = 0.0;
    if (b <= a) return;
    float d = b - a;
    float h = 0.5 * d;
    float mu = 0.5 * (a + b);
    float sh1 = sin(h), ch1 = cos(h), sm1 = sin(mu), cm1 = cos(mu);
    float shk = sh1, chk = ch1, smk = sm1, cmk = cm1; // k = 1
    e[0] = d;
    for (int k = 1; k <= HFGI_N; ++k) {
        float w = 2.0 / float(k) * shk;
        e[k] = w * cmk;
        e[HFGI_N + k] = w * smk;
        float s2 = shk * ch1 + chk * sh1, c2 = chk * ch1 - shk * sh1;
        shk = s2;
        chk = c2;
        float s3 = smk * cm1 + cmk * sm1, c3 = cmk * cm1 - smk * sm1;
        smk = s3;
        cmk = c3;
    }
}

// The basis vector of the indicator of elevations [a, b] (zero if b <= a).
void hfgi_elevation(float a, float b, out float e[HFGI_NE]) {
    if (HFGI_NE == HFGI_N) {
        hfgi_interval(a, b, e);
    } else {
        hfgi_fourier_moments(a, b, e);
    }
}

#endif
