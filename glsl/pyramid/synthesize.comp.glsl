#version 460
// Height pyramid, synthesis step (NS09 §9, "stack" mode): every level the stack keeps is
// resampled back to the working resolution with a cubic B-spline (Sigg & Hadwiger).
// Dispatch z = stack plane c·K + i (channel c, level i < K); pc.level = K | n_v << 16, where K is
// the stack's levels per channel (the finest K of n_v; frame::pyramid::scan_stack_levels).
// The stack is an array of 32-bit words (hfgi_store.glsl): one float each, or with HFGI_HALF
// (the radiance stack with gi.storage = "f16") two halves each, written by the invocation of
// the even value of the pair, which also computes the odd one (planes may have odd sizes), and
// stores both times the pre-exposure pc.scale (frame::storage::pre_exposure).
#include "hfgi_shared.glsl"
layout(local_size_x = HFGI_WORKGROUP, local_size_y = HFGI_WORKGROUP) in;
layout(constant_id = 0) const uint HFGI_HALF = 0u;
layout(std430, binding = 0) readonly buffer Levels { float hfgi_levels[]; };
layout(std430, binding = 1) readonly buffer Table { hfgi_Level hfgi_table[]; };
layout(std430, binding = 2) writeonly buffer Stack { uint hfgi_stack[]; };
layout(push_constant) uniform Push { hfgi_PyramidPush pc; };
#include "hfgi_filter.glsl"
#include "hfgi_store.glsl"

// The value of stack plane `plane_index` at texel p of the out_width × out_height plane.
float hfgi_synthesized(uint plane_index, uvec2 p) {
    uint kept = pc.level & 0xffffu, n_v = pc.level >> 16;
    hfgi_Level l = hfgi_table[(plane_index / kept) * n_v + plane_index % kept];
    vec2 s = hfgi_rescale(vec2(p), vec2(float(pc.out_width), float(pc.out_height)), l);
    return hfgi_bspline_at(l, s, pc.wrap != 0u);
}

void main() {
    uint z = gl_GlobalInvocationID.z;
    uvec2 p = gl_GlobalInvocationID.xy;
    if (p.x >= pc.out_width || p.y >= pc.out_height) return;
    uint i = (z * pc.out_height + p.y) * pc.out_width + p.x;
    if (HFGI_HALF == 0u) {
        hfgi_stack[i] = floatBitsToUint(hfgi_synthesized(z, p));
    } else if ((i & 1u) == 0u) {
        // Value i + 1: the next texel of the row, else the first of the next row or plane.
        uvec2 q = p.x + 1u < pc.out_width ? uvec2(p.x + 1u, p.y) : uvec2(0u, p.y + 1u);
        uint zq = q.y < pc.out_height ? z : z + 1u;
        q.y = q.y < pc.out_height ? q.y : 0u;
        float odd = zq < gl_NumWorkGroups.z ? hfgi_synthesized(zq, q) : 0.0; // local_size_z = 1
        hfgi_stack[i >> 1u] = hfgi_pack_pair(vec2(hfgi_synthesized(z, p), odd) * pc.scale, 0u, false);
    }
}
