#version 460
// Stage `pyramid.max` (docs/accuracy.md §4): level `pc.level` of the max reduction of the
// level-0 heights (hfgi_max.glsl), from the heights (L = 0) or from m_{L−1}. One dispatch per
// level, a compute→compute barrier between them.
#include "hfgi_shared.glsl"
layout(local_size_x = HFGI_WORKGROUP, local_size_y = HFGI_WORKGROUP) in;
layout(std430, binding = 0) readonly buffer Levels { float hfgi_levels[]; };
layout(std430, binding = 1) readonly buffer Table { hfgi_Level hfgi_table[]; };
layout(std430, binding = 2) buffer Max { float hfgi_max[]; };
layout(push_constant) uniform Push { hfgi_PyramidPush pc; }; // level; out_width × out_height = W × H
#include "hfgi_filter.glsl"
#include "hfgi_max.glsl"

void main() {
    uvec2 n0 = uvec2(pc.out_width, pc.out_height);
    uint level = pc.level;
    uvec2 size = hfgi_max_size(n0, level);
    uvec2 c = gl_GlobalInvocationID.xy;
    if (c.x >= size.x || c.y >= size.y) return;
    // The largest of the source's 8 × 8 block at 8c (indices clamped): the heights (L = 0) or
    // m_{L−1}, in separate loops so that no lane indexes the one with the other's size.
    float m = -3.402823466e38;
    if (level == 0u) {
        for (uint y = 0u; y < HFGI_MAX_BLOCK; ++y) {
            for (uint x = 0u; x < HFGI_MAX_BLOCK; ++x) {
                uvec2 i = min(HFGI_MAX_BLOCK * c + uvec2(x, y), n0 - 1u);
                m = max(m, hfgi_fetch(hfgi_table[0], ivec2(i), false));
            }
        }
    } else {
        uvec2 s = hfgi_max_size(n0, level - 1u);
        uint src = hfgi_max_offset(n0, level - 1u);
        for (uint y = 0u; y < HFGI_MAX_BLOCK; ++y) {
            for (uint x = 0u; x < HFGI_MAX_BLOCK; ++x) {
                uvec2 i = min(HFGI_MAX_BLOCK * c + uvec2(x, y), s - 1u);
                m = max(m, hfgi_max[src + i.y * s.x + i.x]);
            }
        }
    }
    hfgi_max[hfgi_max_offset(n0, level) + c.y * size.x + c.x] = m;
}
