// hfgi — normalised Legendre polynomial (NLP) projections of elevation functions (NS09 §4).
// Requires the specialization constants HFGI_N (SH order n) and HFGI_NE ≥ HFGI_N (the length of
// the caller's vectors; the NLP coefficients fill the first n) declared by the includer.
#ifndef HFGI_NLP_GLSL
#define HFGI_NLP_GLSL

// Occlusion vector v̄(σ) of eq. 10: v̄_l = ∫_{-1}^{sin σ} P̂_l(z) dz, in closed form
// v̄_0 = (x+1)/√2, v̄_l = √((2l+1)/2) (P_{l+1}(x) − P_{l−1}(x)) / (2l+1), x = sin σ.
void hfgi_occlusion(float sigma, out float v[HFGI_NE]) {
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
// Computed from differences, not as hfgi_occlusion(b) − hfgi_occlusion(a): with
// Δx = sin b − sin a = 2 cos((a+b)/2) sin((b−a)/2) and ΔP_l = P_l(sin b) − P_l(sin a) from the
// difference of the Legendre recurrences,
//     ΔP_0 = 0, ΔP_1 = Δx, ΔP_{l+1} = ((2l+1)(x_b ΔP_l + Δx P_l(x_a)) − l ΔP_{l−1}) / (l+1),
// Δv̄_0 = Δx/√2 and Δv̄_l = √((2l+1)/2) (ΔP_{l+1} − ΔP_{l−1}) / (2l+1). Every term is
// proportional to Δx, so a thin interval (the casting-set segments of nearly flat terrain,
// ~1e-6 rad wide) keeps f32 precision relative to its own width instead of to 1
// (docs/hard-cases.md: the two-sided form lost the whole indirect light of 1e-6-high terrain).
void hfgi_interval(float a, float b, out float v[HFGI_NE]) {
    for (int l = 0; l < HFGI_NE; ++l) v[l] = 0.0;
    if (b <= a) {
        return;
    }
    float xa = sin(a);
    float xb = sin(b);
    float dx = 2.0 * cos(0.5 * (a + b)) * sin(0.5 * (b - a));
    float dp_prev = 0.0; // ΔP_{l-1}
    float dp = dx;       // ΔP_l
    float pa_prev = 1.0; // P_{l-1}(x_a)
    float pa = xa;       // P_l(x_a)
    v[0] = dx * 0.70710678118654752;
    for (int l = 1; l < HFGI_N; ++l) {
        float k = float(2 * l + 1);
        float dp_next = (k * (xb * dp + dx * pa) - float(l) * dp_prev) / float(l + 1);
        float pa_next = (k * xa * pa - float(l) * pa_prev) / float(l + 1);
        v[l] = sqrt(k * 0.5) * (dp_next - dp_prev) / k;
        dp_prev = dp;
        dp = dp_next;
        pa_prev = pa;
        pa = pa_next;
    }
}

#endif
