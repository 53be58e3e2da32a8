// hfgi — one texel of the shading planes (docs/integration.md, "Shading buffer";
// frame::shade::ShadingFormat, gi.shading_storage): an RGB f32 triple (three words) or one
// shared-exponent word (Ward's RGBE: mantissas in bits 0-7, 8-15, 16-23, exponent in 24-31, a
// channel m · 2^(e − 135)), packed with the exponent rule of the Vulkan specification's
// shared-exponent conversion and rounding to nearest, ties to even, exactly as src/math/rgbe.rs
// packs it. The plane buffers are arrays of 32-bit words (`uint`). Needs HFGI_PACKED_PLANES (a
// bool expression: the words are RGBE) defined before the include.
#ifndef HFGI_PLANE_GLSL
#define HFGI_PLANE_GLSL

// The word of a texel with a non-finite channel; it unpacks to NaN (rgbe::NON_FINITE).
const uint HFGI_RGBE_NON_FINITE = 0xffffffffu;
// The largest channel: 255 · 2^120 (rgbe::MAX).
const float HFGI_RGBE_MAX = 3.3895313892515355e38; // 255 · 2^120 (bits 0x7f7f0000)

// v · 2^k for k in −270 … 270 in two exact steps (2^k alone may leave f32's range).
vec3 hfgi_rgbe_scale(vec3 v, int k) {
    return ldexp(ldexp(v, ivec3(k / 2)), ivec3(k - k / 2));
}

// Packs v: channels clamped to [0, HFGI_RGBE_MAX]; shared exponent
// e = max(−128, ⌊log2 max⌋) + 128, +1 where the largest mantissa rounds up to 2^8; mantissas
// c · 2^(135 − e) rounded to nearest, ties to even (a sum of planes often falls on a tie:
// rgbe::mantissa). The scales are powers of two, so every product is exact in f32.
uint hfgi_rgbe_pack(vec3 v) {
    if (any(isnan(v)) || any(isinf(v))) return HFGI_RGBE_NON_FINITE;
    vec3 c = clamp(v, vec3(0.0), vec3(HFGI_RGBE_MAX));
    float m = max(c.r, max(c.g, c.b));
    if (m == 0.0) return 0u;
    int f;
    frexp(m, f); // m = μ · 2^f, μ ∈ [½, 1): ⌊log2 m⌋ = f − 1
    int e = max(-128, f - 1) + 128;
    if (roundEven(hfgi_rgbe_scale(vec3(m), 135 - e).x) >= 256.0) e += 1;
    uvec3 q = uvec3(roundEven(hfgi_rgbe_scale(c, 135 - e)));
    uint w = q.r | (q.g << 8u) | (q.b << 16u) | (uint(e) << 24u);
    return w == HFGI_RGBE_NON_FINITE ? w - 1u : w;
}

// Unpacks a word: mantissa · 2^(e − 135) per channel; HFGI_RGBE_NON_FINITE gives NaN.
vec3 hfgi_rgbe_unpack(uint w) {
    if (w == HFGI_RGBE_NON_FINITE) return vec3(uintBitsToFloat(0x7fc00000u));
    return hfgi_rgbe_scale(vec3(uvec3(w, w >> 8u, w >> 16u) & 255u), int(w >> 24u) - 135);
}

// Texel `at` (plane · W·H + texel) of the plane words `buf`.
#define HFGI_PLANE_LOAD(buf, at)                                                                  \
    (HFGI_PACKED_PLANES ? hfgi_rgbe_unpack(buf[(at)])                                            \
                        : vec3(uintBitsToFloat(buf[3u * (at)]), uintBitsToFloat(buf[3u * (at) + 1u]), \
                               uintBitsToFloat(buf[3u * (at) + 2u])))

// Stores the vec3 `v` (a variable: it is read more than once) at texel `at` of `buf`.
#define HFGI_PLANE_STORE(buf, at, v)                                                              \
    if (HFGI_PACKED_PLANES) {                                                                     \
        buf[(at)] = hfgi_rgbe_pack(v);                                                            \
    } else {                                                                                      \
        for (uint hfgi_c = 0u; hfgi_c < 3u; ++hfgi_c) buf[3u * (at) + hfgi_c] = floatBitsToUint((v)[hfgi_c]); \
    }
#endif
