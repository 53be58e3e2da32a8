#version 460
// Height pyramid, synthesis step (NS09 §9, "stack" mode): every level the stack keeps is
// resampled back to the working resolution with a cubic B-spline (Sigg & Hadwiger).
// Dispatch z = stack plane c·K + i (channel c, level i < K); pc.level = K | n_v << 16, where K is
// the stack's levels per channel (the finest K of n_v; frame::pyramid::scan_stack_levels).
#include "hfgi_shared.glsl"
layout(local_size_x = HFGI_WORKGROUP, local_size_y = HFGI_WORKGROUP) in;
layout(std430, binding = 0) readonly buffer Levels { float hfgi_levels[]; };
layout(std430, binding = 1) readonly buffer Table { hfgi_Level hfgi_table[]; };
layout(std430, binding = 2) writeonly buffer Stack { float hfgi_stack[]; };
layout(push_constant) uniform Push { hfgi_PyramidPush pc; };
#include "hfgi_filter.glsl"

void main() {
    uint plane_index = gl_GlobalInvocationID.z;
    uvec2 p = gl_GlobalInvocationID.xy;
    if (p.x >= pc.out_width || p.y >= pc.out_height) return;
    uint kept = pc.level & 0xffffu, n_v = pc.level >> 16;
    hfgi_Level l = hfgi_table[(plane_index / kept) * n_v + plane_index % kept];
    vec2 s = hfgi_rescale(vec2(p), vec2(float(pc.out_width), float(pc.out_height)), l);
    uint plane = pc.out_width * pc.out_height;
    hfgi_stack[plane_index * plane + p.y * pc.out_width + p.x] = hfgi_bspline_at(l, s, pc.wrap != 0u);
}
