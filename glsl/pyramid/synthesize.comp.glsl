#version 460
#extension GL_EXT_control_flow_attributes : require
// Height pyramid, synthesis step (NS09 §9, "stack" mode): every level the stack keeps is
// resampled with a cubic B-spline (Sigg & Hadwiger) onto its stack plane: the working grid, or
// for a decimated stack (the radiance stack) a grid of at least twice the level's resolution
// (PyramidLayout::stack_plane_size). Binding 3 holds each plane's width, height and offset
// (values from its channel's start) and, after the last plane, the channel stride.
// Dispatch z = stack plane c·K + i (channel c, level i < K) over the working grid (the largest
// plane); pc.level = K | n_v << 16, where K is the stack's levels per channel (the finest K of
// n_v; frame::pyramid::scan_stack_levels).
// The stack is an array of 32-bit words (hfgi_store.glsl): one float each, or with HFGI_HALF
// (the radiance stack with gi.storage = "f16") two halves each: then an invocation computes
// one word, values 2g and 2g + 1 of its plane for flat invocation index g = y·width + x (the
// dispatch covers half the working grid's rows; a decimated stack pads its planes to even
// counts, so a word never straddles two planes), and stores both times the pre-exposure
// pc.scale (frame::storage::pre_exposure). One word per invocation, not one invocation per
// value with the odd ones idle: lavapipe runs idle lanes as busy (docs/performance.md §21).
#include "hfgi_shared.glsl"
layout(local_size_x = HFGI_WORKGROUP, local_size_y = HFGI_WORKGROUP) in;
layout(constant_id = 0) const uint HFGI_HALF = 0u;
// With HFGI_HALF: every plane's width is even (a word's two values lie on one row) and no plane
// is coarser than its level (frame::pyramid::synthesizes_pairs): each word's two B-splines
// share their fetches (hfgi_synthesized_pair; docs/performance.md §34).
layout(constant_id = 1) const uint HFGI_PAIRS = 0u;
// The levels (16 reads per B-spline value) and the planes through texel views (HFGI_TEXELS,
// hfgi_filter.glsl; docs/performance.md §17).
#define HFGI_TEXELS
layout(binding = 0) uniform usamplerBuffer hfgi_levels_texels;
layout(std430, binding = 1) readonly buffer Table { hfgi_Level hfgi_table[]; };
layout(std430, binding = 2) writeonly buffer Stack { uint hfgi_stack[]; };
layout(binding = 3) uniform usamplerBuffer hfgi_planes_texels; // width, height, offset, 0
#define hfgi_planes(i) texelFetch(hfgi_planes_texels, int(i))
layout(push_constant) uniform Push { hfgi_PyramidPush pc; };
#include "hfgi_filter.glsl"
#include "hfgi_store.glsl"

// The level stack plane `plane_index` resamples: channel plane_index / K, level plane_index % K.
hfgi_Level hfgi_plane_level(uint plane_index) {
    uint kept = pc.level & 0xffffu, n_v = pc.level >> 16;
    return hfgi_table[(plane_index / kept) * n_v + plane_index % kept];
}

// With pc.flags & 1 (raw plane 0, HeightPyramid::set_raw_plane0) plane 0 of each channel has
// level 0's size and holds its own values, relative to its bias as hfgi_fetch reads them; the
// others the B-spline.
bool hfgi_raw_plane(uint plane_index) {
    return (pc.flags & 1u) != 0u && plane_index % (pc.level & 0xffffu) == 0u;
}

// The value of stack plane `plane_index` (of size `size`) at texel p.
float hfgi_synthesized(uint plane_index, uvec2 p, uvec2 size) {
    hfgi_Level l = hfgi_plane_level(plane_index);
    if (hfgi_raw_plane(plane_index)) return hfgi_fetch(l, ivec2(p), pc.wrap != 0u);
    vec2 s = hfgi_rescale(vec2(p), vec2(size), l);
    return hfgi_bspline_at(l, s, pc.wrap != 0u);
}

// Values t and t + 1 of a plane (texels e and e + (1, 0), one row: HFGI_PAIRS). Their B-splines'
// windows share their rows and all but one column (the second starts o ≤ 1 level texels
// further: the plane is no coarser than its level), so the 4 × 5 texels are fetched once, and
// each value combines its 16 as hfgi_bspline_at does (the same values, weights and order: the
// same result). A raw plane 0 (pc.flags & 1) holds the level's own two texels.
vec2 hfgi_synthesized_pair(uint plane_index, uvec2 e, uvec2 size) {
    hfgi_Level l = hfgi_plane_level(plane_index);
    bool wrap = pc.wrap != 0u;
    vec2 s0 = hfgi_rescale(vec2(e), vec2(size), l), s1 = hfgi_rescale(vec2(e.x + 1u, e.y), vec2(size), l);
    bool one = floor(s1.x) != floor(s0.x); // the second window starts a column further
    ivec2 i = ivec2(floor(s0));
    float w[4][5];
    [[unroll]] for (int r = 0; r < 4; ++r) {
        [[unroll]] for (int c = 0; c < 5; ++c) w[r][c] = hfgi_fetch(l, i + ivec2(c - 1, r - 1), wrap);
    }
    float a[4][4];
    [[unroll]] for (int r = 0; r < 4; ++r) {
        [[unroll]] for (int c = 0; c < 4; ++c) a[r][c] = one ? w[r][c + 1] : w[r][c];
    }
    vec2 v = vec2(hfgi_bspline_window(w[0][0], w[0][1], w[0][2], w[0][3], w[1][0], w[1][1], w[1][2], w[1][3],
                                      w[2][0], w[2][1], w[2][2], w[2][3], w[3][0], w[3][1], w[3][2], w[3][3], s0),
                  hfgi_bspline_window(a[0][0], a[0][1], a[0][2], a[0][3], a[1][0], a[1][1], a[1][2], a[1][3],
                                      a[2][0], a[2][1], a[2][2], a[2][3], a[3][0], a[3][1], a[3][2], a[3][3], s1));
    return hfgi_raw_plane(plane_index) ? vec2(hfgi_fetch(l, ivec2(e), wrap), hfgi_fetch(l, ivec2(e) + ivec2(1, 0), wrap)) : v;
}

void main() {
    uint z = gl_GlobalInvocationID.z;
    uvec2 p = gl_GlobalInvocationID.xy;
    uint kept = pc.level & 0xffffu;
    uvec4 plane = hfgi_planes(z % kept);
    uvec2 size = plane.xy;
    uint base = (z / kept) * hfgi_planes(kept).z + plane.z; // even with f16 (padded planes)
    if (HFGI_HALF == 0u) {
        if (p.x >= size.x || p.y >= size.y) return;
        uint t = p.y * size.x + p.x;
        hfgi_stack[base + t] = floatBitsToUint(hfgi_synthesized(z, p, size));
        // A decimated plane of odd count is padded by one value: 0, so the buffer's contents
        // are defined (read-backs see every value; the scan never reads the pad).
        uint count = size.x * size.y;
        if (t + 1u == count && plane.z + count < hfgi_planes(z % kept + 1u).z) hfgi_stack[base + t + 1u] = 0u;
    } else {
        // Word g = p.y·size.x + p.x of the plane holds values t = 2g and t + 1: t's texel is
        // (2p.x, 2p.y), or (2p.x − size.x, 2p.y + 1) past the row's end (2p.x < 2·size.x).
        if (p.x >= size.x) return;
        uvec2 e = 2u * p.x < size.x ? uvec2(2u * p.x, 2u * p.y) : uvec2(2u * p.x - size.x, 2u * p.y + 1u);
        if (e.y >= size.y) return;
        vec2 pair;
        if (HFGI_PAIRS != 0u) {
            pair = hfgi_synthesized_pair(z, e, size);
        } else {
            // Value t + 1: the next texel of the row, else the first of the next row, else padding.
            uvec2 q = e.x + 1u < size.x ? uvec2(e.x + 1u, e.y) : uvec2(0u, e.y + 1u);
            pair = vec2(hfgi_synthesized(z, e, size), q.y < size.y ? hfgi_synthesized(z, q, size) : 0.0);
        }
        uint t = e.y * size.x + e.x;
        hfgi_stack[(base + t) >> 1u] = hfgi_pack_pair(pair * pc.scale, 0u, false);
    }
}
