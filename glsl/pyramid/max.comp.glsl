#version 460
// Stage `pyramid.max` (docs/accuracy.md §4): level `pc.level` of the max pyramid of the level-0
// heights, m_L and ov_L (hfgi_max.glsl), from the heights (L = 0) or from m_{L−1}. One dispatch
// per level, a compute→compute barrier between them.
#include "hfgi_shared.glsl"
layout(local_size_x = HFGI_WORKGROUP, local_size_y = HFGI_WORKGROUP) in;
layout(std430, binding = 0) readonly buffer Levels { float hfgi_levels[]; };
layout(std430, binding = 1) readonly buffer Table { hfgi_Level hfgi_table[]; };
layout(std430, binding = 2) buffer Max { float hfgi_max[]; };
layout(push_constant) uniform Push { hfgi_PyramidPush pc; }; // level; out_width × out_height = W × H
#include "hfgi_filter.glsl"
#include "hfgi_max.glsl"

// The largest of `n` × `n` values from index `base` of a level of size `s` (indices clamped): the
// heights (L = 0) or m_{L−1}.
float block_max(uvec2 base, uint n, uvec2 s, uint level, uint src) {
    float m = -3.402823466e38;
    for (uint y = 0u; y < n; ++y) {
        for (uint x = 0u; x < n; ++x) {
            uvec2 i = min(base + uvec2(x, y), s - 1u);
            float v = level == 0u ? hfgi_fetch(hfgi_table[0], ivec2(i), false) : hfgi_max[src + i.y * s.x + i.x];
            m = max(m, v);
        }
    }
    return m;
}

void main() {
    uvec2 n0 = uvec2(pc.out_width, pc.out_height);
    uint level = pc.level;
    uvec2 size = hfgi_max_size(n0, level);
    uvec2 c = gl_GlobalInvocationID.xy;
    if (c.x >= size.x || c.y >= size.y) return;
    uint at = c.y * size.x + c.x;
    if (level == 0u) {
        // m_0[c] = max h[c .. c+1]; ov_0[c] = max h[c .. c+2].
        hfgi_max[hfgi_max_offset(n0, 0u, false) + at] = block_max(c, 2u, n0, 0u, 0u);
        hfgi_max[hfgi_max_offset(n0, 0u, true) + at] = block_max(c, 3u, n0, 0u, 0u);
        return;
    }
    // m_L[c] = max m_{L−1}[2c .. 2c+1]; ov_L[c] = max m_{L−1}[2c .. 2c+3].
    uvec2 s = hfgi_max_size(n0, level - 1u);
    uint src = hfgi_max_offset(n0, level - 1u, false);
    hfgi_max[hfgi_max_offset(n0, level, false) + at] = block_max(2u * c, 2u, s, level, src);
    hfgi_max[hfgi_max_offset(n0, level, true) + at] = block_max(2u * c, 4u, s, level, src);
}
