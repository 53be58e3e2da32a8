// hfgi — software bilinear and cubic B-spline sampling of pyramid levels stored in a float
// buffer. The includer declares, before including this file:
//     layout(std430, binding = N) readonly buffer ... { float hfgi_levels[]; };
// or, with HFGI_TEXELS defined, `layout(binding = N) uniform usamplerBuffer hfgi_levels_texels;`.
// A shader that reads two pyramids (heights and radiance) defines instead
//     #define HFGI_LEVEL_READ(l, i) ((l).source == 0u ? hfgi_levels[i] : hfgi_radiance_levels[i])
// Coordinates are in the level's texel units with texel centres at integers.
#ifndef HFGI_FILTER_GLSL
#define HFGI_FILTER_GLSL
#include "hfgi_shared.glsl"
#include "hfgi_address.glsl"

// Value i of a buffer read through a texel view of 32-bit words (`usamplerBuffer`, a float's
// bits). lavapipe gathers texel fetches on its SIMD lanes but reads a storage buffer lane by
// lane, with a branch per lane: the scanning shaders read what they read per sample this way
// (docs/performance.md §17). An includer that defines HFGI_TEXELS declares
// `uniform usamplerBuffer hfgi_levels_texels` instead of the `hfgi_levels` storage buffer.
#define HFGI_TEXEL_F(t, i) uintBitsToFloat(texelFetch(t, int(i)).x)
#ifndef HFGI_LEVEL_READ
#ifdef HFGI_TEXELS
#define HFGI_LEVEL_READ(l, i) HFGI_TEXEL_F(hfgi_levels_texels, i)
#else
#define HFGI_LEVEL_READ(l, i) hfgi_levels[i]
#endif
#endif

float hfgi_fetch(hfgi_Level l, ivec2 p, bool wrap) {
    int x = hfgi_address(p.x, int(l.width), wrap);
    int y = hfgi_address(p.y, int(l.height), wrap);
    // Relative to the level's bias (the height origin z0 on level 0): exact for heights near z0.
    return HFGI_LEVEL_READ(l, l.offset + uint(y) * l.width + uint(x)) - l.bias;
}

// Linear interpolation in base-relative form, a + t·(b − a): equal inputs give exactly that
// input, and the rounding error is relative to |b − a| instead of to |a| (docs/hard-cases.md:
// with a weighted sum a·(1−t) + b·t, a plateau at 1e7 or a 4e6 wall came out ±1 from texel to
// texel in f32, which is a false horizon of 45° one texel away).
float hfgi_lerp(float a, float b, float t) {
    return a + t * (b - a);
}

// Bilinear interpolation of a (x0,y0), b (x1,y0), c (x0,y1), d (x1,y1) with fractions f,
// separably (x, then y) in base-relative form: rows that are equal give exactly the row's value,
// so a field that does not vary along y is filtered exactly the same on every row.
float hfgi_bilerp(float a, float b, float c, float d, vec2 f) {
    return hfgi_lerp(hfgi_lerp(a, b, f.x), hfgi_lerp(c, d, f.x), f.y);
}

// Bilinear interpolation between texels base and base+1 with fractions f in [0, 1].
// Computed in software (exact f32 weights) rather than by the sampler, whose sub-texel
// precision (often 8 bits) would cost ~1e-3 of the local height difference.
float hfgi_bilinear(hfgi_Level l, ivec2 base, vec2 f, bool wrap) {
    float a = hfgi_fetch(l, base, wrap);
    float b = hfgi_fetch(l, base + ivec2(1, 0), wrap);
    float c = hfgi_fetch(l, base + ivec2(0, 1), wrap);
    float d = hfgi_fetch(l, base + ivec2(1, 1), wrap);
    return hfgi_bilerp(a, b, c, d, f);
}

float hfgi_bilinear_at(hfgi_Level l, vec2 pos, bool wrap) {
    vec2 fl = floor(pos);
    return hfgi_bilinear(l, ivec2(fl), pos - fl, wrap);
}

// Uniform cubic B-spline (SN08 eq. 4.9–4.12) at pos, as four bilinear taps
// (Sigg & Hadwiger 2005, "Fast third-order texture filtering"): per axis the weights
// w0..w3 of texels i-1..i+2 collapse into g0 = w0+w1 at i-1 + w1/g0 and g1 = w2+w3 at
// i+1 + w3/g1. Integer bases and fractions are kept apart for precision. The taps are
// combined as a bilinear blend with weight g1 (g0 = 1 − g1), in base-relative form like
// hfgi_bilerp, so a constant region is reproduced exactly.
// hfgi_bspline_window combines the 16 texels of the window (v_rc: row r, column c, from
// floor(pos) − (1, 1)); a caller may fetch them itself (glsl/pyramid/synthesize.comp.glsl
// fetches two neighbours' windows at once) and get hfgi_bspline_at's result.
float hfgi_bspline_window(float v00, float v01, float v02, float v03, float v10, float v11, float v12, float v13,
                          float v20, float v21, float v22, float v23, float v30, float v31, float v32, float v33,
                          vec2 pos) {
    vec2 t = pos - floor(pos);
    vec2 s = 1.0 - t;
    vec2 t2 = t * t;
    vec2 t3 = t2 * t;
    vec2 w0 = s * s * s / 6.0;
    vec2 w1 = (3.0 * t3 - 6.0 * t2 + 4.0) / 6.0;
    vec2 w3 = t3 / 6.0;
    vec2 w2 = 1.0 - w0 - w1 - w3;
    vec2 g0 = w0 + w1;
    vec2 g1 = w2 + w3;
    vec2 f0 = w1 / g0;
    vec2 f1 = w3 / g1;
    float t00 = hfgi_bilerp(v00, v01, v10, v11, vec2(f0.x, f0.y));
    float t10 = hfgi_bilerp(v02, v03, v12, v13, vec2(f1.x, f0.y));
    float t01 = hfgi_bilerp(v20, v21, v30, v31, vec2(f0.x, f1.y));
    float t11 = hfgi_bilerp(v22, v23, v32, v33, vec2(f1.x, f1.y));
    return hfgi_bilerp(t00, t10, t01, t11, g1);
}

// The cubic B-spline of level l at pos: its window's 16 texels, combined.
float hfgi_bspline_at(hfgi_Level l, vec2 pos, bool wrap) {
    ivec2 i = ivec2(floor(pos));
#define HFGI_W(c, r) hfgi_fetch(l, i + ivec2((c) - 1, (r) - 1), wrap)
    return hfgi_bspline_window(HFGI_W(0, 0), HFGI_W(1, 0), HFGI_W(2, 0), HFGI_W(3, 0), HFGI_W(0, 1), HFGI_W(1, 1),
                               HFGI_W(2, 1), HFGI_W(3, 1), HFGI_W(0, 2), HFGI_W(1, 2), HFGI_W(2, 2), HFGI_W(3, 2),
                               HFGI_W(0, 3), HFGI_W(1, 3), HFGI_W(2, 3), HFGI_W(3, 3), pos);
#undef HFGI_W
}

// Position in level l's texel units of a point given in texel units of a grid `from`
// cells wide (texel-centre aligned: the domain edges coincide).
vec2 hfgi_rescale(vec2 p, vec2 from, hfgi_Level l) {
    return (p + 0.5) * vec2(float(l.width), float(l.height)) / from - 0.5;
}

#endif
