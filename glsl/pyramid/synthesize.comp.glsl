#version 460
// Height pyramid, synthesis step (NS09 §9, "stack" mode): every level is resampled back to the
// working resolution with a cubic B-spline (Sigg & Hadwiger). Dispatch z = level.
#include "hfgi_shared.glsl"
layout(local_size_x = HFGI_WORKGROUP, local_size_y = HFGI_WORKGROUP) in;
layout(std430, binding = 0) readonly buffer Levels { float hfgi_levels[]; };
layout(std430, binding = 1) readonly buffer Table { hfgi_Level hfgi_table[]; };
layout(std430, binding = 2) writeonly buffer Stack { float hfgi_stack[]; };
layout(push_constant) uniform Push { hfgi_PyramidPush pc; };
#include "hfgi_filter.glsl"

void main() {
    uint level = gl_GlobalInvocationID.z;
    uvec2 p = gl_GlobalInvocationID.xy;
    if (p.x >= pc.out_width || p.y >= pc.out_height) return;
    hfgi_Level l = hfgi_table[level];
    vec2 s = hfgi_rescale(vec2(p), vec2(float(pc.out_width), float(pc.out_height)), l);
    uint plane = pc.out_width * pc.out_height;
    hfgi_stack[level * plane + p.y * pc.out_width + p.x] = hfgi_bspline_at(l, s, pc.wrap != 0u);
}
