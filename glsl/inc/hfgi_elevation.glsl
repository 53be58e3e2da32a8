// hfgi — the per-azimuth elevation basis (src/math/elevation.rs; docs/accuracy.md §4).
// Requires the specialization constants HFGI_N (SH order n) and HFGI_NE (values per azimuth: n
// for the paper's NLP basis, n(n+1)/2 for the `legendre` basis) and, for the latter, the buffer
//     layout(std430, binding = N) readonly buffer Elev { float hfgi_elev[]; };
// holding `math::elevation::fourier_table(n)`: per (l, m) in index order l(l+1)/2 + m, 2n + 1
// values [c_0, α_1..α_n, β_1..β_n] of g_lm(ω) = P_l^m(sin ω) cos ω as a trigonometric polynomial.
#ifndef HFGI_ELEVATION_GLSL
#define HFGI_ELEVATION_GLSL
#include "hfgi_nlp.glsl"

// e_lm(a, b) = ∫_a^b P_l^m(sin ω) cos ω dω = c_0 Δ + Σ_k (2/k) sin(kΔ/2) (α_k cos kμ + β_k sin kμ),
// Δ = b − a, μ = (a + b)/2: every term is proportional to sin(kΔ/2), so a thin interval keeps its
// precision relative to its own width. sin(kΔ/2), cos kμ, sin kμ by rotation (angle addition).
void hfgi_legendre_interval(float a, float b, out float e[HFGI_NE]) {
    for (int i = 0; i < HFGI_NE; ++i) e[i] = 0.0;
    if (b <= a) return;
    float d = b - a;
    float h = 0.5 * d;
    float mu = 0.5 * (a + b);
    float sh1 = sin(h), ch1 = cos(h), sm1 = sin(mu), cm1 = cos(mu);
    float shk = sh1, chk = ch1, smk = sm1, cmk = cm1; // k = 1
    int row = 2 * HFGI_N + 1;
    for (int i = 0; i < HFGI_NE; ++i) e[i] = hfgi_elev[i * row] * d;
    for (int k = 1; k <= HFGI_N; ++k) {
        float w = 2.0 / float(k) * shk;
        for (int i = 0; i < HFGI_NE; ++i) {
            e[i] += w * (hfgi_elev[i * row + k] * cmk + hfgi_elev[i * row + HFGI_N + k] * smk);
        }
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
        hfgi_legendre_interval(a, b, e);
    }
}

#endif
