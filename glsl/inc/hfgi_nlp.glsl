// hfgi — normalised Legendre polynomial (NLP) projections of elevation functions (NS09 §4).
// Requires the specialization constant HFGI_N (SH order n) declared by the includer.
#ifndef HFGI_NLP_GLSL
#define HFGI_NLP_GLSL

// Occlusion vector v̄(σ) of eq. 10: v̄_l = ∫_{-1}^{sin σ} P̂_l(z) dz, in closed form
// v̄_0 = (x+1)/√2, v̄_l = √((2l+1)/2) (P_{l+1}(x) − P_{l−1}(x)) / (2l+1), x = sin σ.
void hfgi_occlusion(float sigma, out float v[HFGI_N]) {
    float x = sin(sigma);
    float pm1 = 1.0; // P_{l-1}
    float p0 = x;    // P_l
    v[0] = (x + 1.0) * 0.70710678118654752;
    for (int l = 1; l < HFGI_N; ++l) {
        float p1 = (float(2 * l + 1) * x * p0 - float(l) * pm1) / float(l + 1); // P_{l+1}
        v[l] = sqrt(float(2 * l + 1) * 0.5) * (p1 - pm1) / float(2 * l + 1);
        pm1 = p0;
        p0 = p1;
    }
}

// NLP vector of the indicator of elevations in [a, b] (zero if b <= a): v̄(b) − v̄(a).
// With a = max(ω_max, lo) and b = hi this is eq. 11 restricted to a light's window (§6).
void hfgi_interval(float a, float b, out float v[HFGI_N]) {
    if (b <= a) {
        for (int l = 0; l < HFGI_N; ++l) v[l] = 0.0;
        return;
    }
    float va[HFGI_N];
    hfgi_occlusion(a, va);
    hfgi_occlusion(b, v);
    for (int l = 0; l < HFGI_N; ++l) v[l] -= va[l];
}

#endif
