#version 460
// Diagnostic: samples the height pyramid at arbitrary (level, x, y) queries, x and y in
// level-0 texel units, exactly as the scanning passes do (hfgi_pyramid_at; query.w ≠ 0 reads the level
// raw, as gi.level0 = "bilinear" reads level 0).
// pc.level: 0 = stack mode, 1 = pyramid mode.
#include "hfgi_shared.glsl"
layout(local_size_x = HFGI_WORKGROUP_1D) in;
layout(std430, binding = 0) readonly buffer Levels { float hfgi_levels[]; };
layout(std430, binding = 1) readonly buffer Table { hfgi_Level hfgi_table[]; };
layout(std430, binding = 2) readonly buffer Stack { float hfgi_stack[]; };
layout(std430, binding = 3) readonly buffer Queries { vec4 hfgi_queries[]; };
layout(std430, binding = 4) writeonly buffer Result { float hfgi_result[]; };
layout(std430, binding = 5) readonly buffer HPlanes { uvec4 hfgi_hplanes[]; }; // the stack's planes (stack mode)
layout(push_constant) uniform Push { hfgi_PyramidPush pc; };
#include "hfgi_pyramid.glsl"

void main() {
    uint q = gl_GlobalInvocationID.x;
    if (q >= uint(hfgi_queries.length())) return;
    vec4 query = hfgi_queries[q];
    uint level = uint(query.x);
    hfgi_result[q] = hfgi_pyramid_at(hfgi_table[0], hfgi_table[level], level, query.yz, pc.level == 0u, pc.wrap != 0u,
                                     query.w != 0.0);
}
