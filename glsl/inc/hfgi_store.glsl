// hfgi — f32 or f16 storage of the visibility vectors V, the IR vectors U and the radiance
// stack (gi.storage, docs/performance.md §9; scene::model::Storage). The buffers are arrays of
// 32-bit words: one float's bits each (f32), or two IEEE halves each (f16, packHalf2x16: value i
// in word i/2, the even value in the low half). One receiver's vector starts at an even value
// with f16 (Storage::stride), so a word never holds values of two receivers; the stack's planes
// are not padded (its synthesis writes both values of a word). The shaders compute in f32.
// Needs the specialization constant HFGI_HALF (0: f32, 1: f16) declared before the include.
#ifndef HFGI_STORE_GLSL
#define HFGI_STORE_GLSL

// The largest finite half: f16 stores clamp to it (U scales with the scene's radiance).
const float HFGI_HALF_MAX = 65504.0;

// Values one receiver's vector of `values` numbers occupies (Storage::stride): even with f16.
uint hfgi_stride(int values) {
    return HFGI_HALF != 0u ? uint(values + 1) & ~1u : uint(values);
}

// Value i of the word array `buf`.
#define HFGI_LOAD(buf, i) (HFGI_HALF != 0u ? unpackHalf2x16(buf[(i) >> 1u])[(i) & 1u] : uintBitsToFloat(buf[(i)]))
// Value i of the same words read through a texel view `t` of them (`usamplerBuffer`, R32_UINT;
// docs/performance.md §17).
#define HFGI_LOAD_TEXEL(t, i)                                                                    \
    (HFGI_HALF != 0u ? unpackHalf2x16(texelFetch(t, int((i) >> 1u)).x)[(i) & 1u]                   \
                     : uintBitsToFloat(texelFetch(t, int(i)).x))

// The word holding the pair v (f16), plus the pair already in `old` when `acc`.
uint hfgi_pack_pair(vec2 v, uint old, bool acc) {
    vec2 s = v + (acc ? unpackHalf2x16(old) : vec2(0.0));
    return packHalf2x16(clamp(s, vec2(-HFGI_HALF_MAX), vec2(HFGI_HALF_MAX)));
}

// The word holding the float v (f32), plus the float already in `old` when `acc`.
uint hfgi_pack_float(float v, uint old, bool acc) {
    return floatBitsToUint(v + (acc ? uintBitsToFloat(old) : 0.0));
}

// Stores the values value_at(0) … value_at(count − 1) (`value_at`: a macro of the index) at
// value `base` of the word array `buf` on, or adds them to what is there when `acc`: one word
// each with f32; two to a word with f16 (`base` even; an odd count's last word holds 0 in its
// high half). The one writer of V (visibility pass) and U (indirect scan).
#define HFGI_STORE(buf, base, count, value_at, acc)                                                 \
    if (HFGI_HALF != 0u) {                                                                        \
        for (int hfgi_i = 0; hfgi_i < (count); hfgi_i += 2) {                                      \
            uint hfgi_o = ((base) + uint(hfgi_i)) >> 1u;                                           \
            float hfgi_odd = hfgi_i + 1 < (count) ? value_at(min(hfgi_i + 1, (count) - 1)) : 0.0;  \
            buf[hfgi_o] = hfgi_pack_pair(vec2(value_at(hfgi_i), hfgi_odd), buf[hfgi_o], acc);       \
        }                                                                                         \
    } else {                                                                                      \
        for (int hfgi_i = 0; hfgi_i < (count); ++hfgi_i) {                                         \
            uint hfgi_o = (base) + uint(hfgi_i);                                                   \
            buf[hfgi_o] = hfgi_pack_float(value_at(hfgi_i), buf[hfgi_o], acc);                      \
        }                                                                                         \
    }
#endif
