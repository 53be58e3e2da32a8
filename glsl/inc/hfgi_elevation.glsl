// hfgi — the per-azimuth elevation basis (src/math/elevation.rs; docs/accuracy.md §4).
// Requires the specialization constants HFGI_N (SH order n) and HFGI_NE (values per azimuth,
// math::elevation::gpu_size: n for the paper's NLP basis, the 2n + 1 Fourier moments for the
// `legendre` basis, whose wedge matrices the host has multiplied by the Fourier table).
#ifndef HFGI_ELEVATION_GLSL
#define HFGI_ELEVATION_GLSL
#include "hfgi_nlp.glsl"

// The highest Fourier order the includer needs (HFGI_KMAX ≤ n; row (l, m) of a fold reads
// orders ≤ l + 1, so a vector kept to bands < b needs b): the moments above it stay 0 and
// HFGI_ADD_MOMENTS leaves them out. Default: every order.
#ifndef HFGI_KMAX
#define HFGI_KMAX HFGI_N
#endif

// sin x and cos x for |x| ≤ π/2 (elevations, their half-differences and midpoints), by their
// Taylor series to x¹¹ and x¹² in Horner form: the first omitted terms are below 6e-8 and 7e-9
// at π/2, under f32's spacing at 1 (1.2e-7), and sin keeps its relative precision as x → 0.
// A few multiply-adds instead of the general sin and cos and their range reduction
// (docs/performance.md §20).
float hfgi_sin_elevation(float x) {
    float x2 = x * x;
    float p = -2.5052108385441720e-8;              // −1/11!
    p = p * x2 + 2.7557319223985893e-6;           // 1/9!
    p = p * x2 - 1.9841269841269841e-4;           // −1/7!
    p = p * x2 + 8.3333333333333333e-3;           // 1/5!
    p = p * x2 - 1.6666666666666667e-1;           // −1/3!
    return x + x * (x2 * p);
}

float hfgi_cos_elevation(float x) {
    float x2 = x * x;
    float p = 2.0876756987868099e-9;               // 1/12!
    p = p * x2 - 2.7557319223985891e-7;           // −1/10!
    p = p * x2 + 2.4801587301587302e-5;           // 1/8!
    p = p * x2 - 1.3888888888888889e-3;           // −1/6!
    p = p * x2 + 4.1666666666666667e-2;           // 1/4!
    p = p * x2 - 0.5;                             // −1/2!
    return 1.0 + x2 * p;
}

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
    float sh1 = hfgi_sin_elevation(h), ch1 = hfgi_cos_elevation(h);
    float sm1 = hfgi_sin_elevation(mu), cm1 = hfgi_cos_elevation(mu);
    float shk = sh1, chk = ch1, smk = sm1, cmk = cm1; // k = 1
    e[0] = d;
    for (int k = 1; k <= HFGI_KMAX; ++k) {
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

// acc += w · e for the values a fold up to order HFGI_KMAX reads: every value in the NLP basis;
// in the legendre basis the width and the cosines and sines of orders 1..HFGI_KMAX.
#define HFGI_ADD_MOMENTS(acc, w, e)                                                           \
    if (HFGI_NE == HFGI_N) {                                                                  \
        for (int hfgi_i = 0; hfgi_i < HFGI_NE; ++hfgi_i) acc[hfgi_i] += (w) * e[hfgi_i];      \
    } else {                                                                                  \
        for (int hfgi_i = 0; hfgi_i <= HFGI_KMAX; ++hfgi_i) acc[hfgi_i] += (w) * e[hfgi_i];   \
        for (int hfgi_i = 1; hfgi_i <= HFGI_KMAX; ++hfgi_i) acc[HFGI_N + hfgi_i] += (w) * e[HFGI_N + hfgi_i]; \
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
