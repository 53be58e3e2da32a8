// hfgi — the largest slope F(t)/t of one quadratic piece of a ray's height profile: the exact
// horizon along a ray over the bilinear level-0 surface is the largest of these over the cells
// the ray crosses (docs/direct.md §7, the sweep's near field; docs/local-lights.md, the local
// lights' horizons).
#ifndef HFGI_NEAR_GLSL
#define HFGI_NEAR_GLSL

// Largest F(t)/t of the piece F(t0 + τ) = aτ² + bτ + c, τ ∈ [0, t1 − t0] (at t0 = 0, c = 0 and
// the limit is b). Twin: reference::sweep::piece_max.
float hfgi_piece_max(float t0, float t1, float a, float b, float c) {
    float len = t1 - t0;
    float best = max(t0 > 0.0 ? c / t0 : b, ((a * len + b) * len + c) / t1);
    float cp = (a * t0 - b) * t0 + c; // F/t = a·t + b' + c'/t: a maximum at √(c'/a) when a, c' < 0
    if (a < 0.0 && cp < 0.0) {
        float ts = sqrt(cp / a);
        if (ts > t0 && ts < t1) {
            float tau = ts - t0;
            best = max(best, ((a * tau + b) * tau + c) / ts);
        }
    }
    return best;
}

#endif
