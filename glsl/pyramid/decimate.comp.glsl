#version 460
// Height pyramid, reduction step (NS09 §5.2, §9): level i is level i-1 bilinearly decimated
// by 2^(1/k_v) per axis.
#include "hfgi_shared.glsl"
layout(local_size_x = HFGI_WORKGROUP, local_size_y = HFGI_WORKGROUP) in;
layout(std430, binding = 0) buffer Levels { float hfgi_levels[]; };
layout(std430, binding = 1) readonly buffer Table { hfgi_Level hfgi_table[]; };
layout(push_constant) uniform Push { hfgi_PyramidPush pc; };
#include "hfgi_filter.glsl"

// Dispatch z = channel: channel c of level i is table entry c·n_levels + i (pc.out_width holds
// n_levels in this pass).
void main() {
    uint e = gl_GlobalInvocationID.z * pc.out_width + pc.level;
    hfgi_Level dst = hfgi_table[e];
    hfgi_Level src = hfgi_table[e - 1u];
    uvec2 p = gl_GlobalInvocationID.xy;
    if (p.x >= dst.width || p.y >= dst.height) return;
    vec2 s = hfgi_rescale(vec2(p), vec2(float(dst.width), float(dst.height)), src);
    hfgi_levels[dst.offset + p.y * dst.width + p.x] = hfgi_bilinear_at(src, s, pc.wrap != 0u);
}
