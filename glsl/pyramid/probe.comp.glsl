#version 460
// Diagnostic: samples the height pyramid at arbitrary (level, x, y) queries, x and y in
// working-resolution texel units, the way later passes do. pc.level selects the mode:
// 0 = stack (bilinear on the synthesized level), 1 = true pyramid (B-spline on the fly).
#include "hfgi_shared.glsl"
layout(local_size_x = 64) in;
layout(std430, binding = 0) readonly buffer Levels { float hfgi_levels[]; };
layout(std430, binding = 1) readonly buffer Table { hfgi_Level hfgi_table[]; };
layout(std430, binding = 2) readonly buffer Stack { float hfgi_stack[]; };
layout(std430, binding = 3) readonly buffer Queries { vec4 hfgi_queries[]; };
layout(std430, binding = 4) writeonly buffer Result { float hfgi_result[]; };
layout(push_constant) uniform Push { hfgi_PyramidPush pc; };
#include "hfgi_filter.glsl"

float stack_fetch(uint level, ivec2 p, uvec2 size, bool wrap) {
    int x = hfgi_address(p.x, int(size.x), wrap);
    int y = hfgi_address(p.y, int(size.y), wrap);
    return hfgi_stack[level * size.x * size.y + uint(y) * size.x + uint(x)];
}

void main() {
    uint q = gl_GlobalInvocationID.x;
    if (q >= uint(hfgi_queries.length())) return;
    vec4 query = hfgi_queries[q];
    uint level = uint(query.x);
    vec2 pos = query.yz;
    bool wrap = pc.wrap != 0u;
    uvec2 work = uvec2(pc.out_width, pc.out_height);
    float h;
    if (pc.level == 0u) {
        vec2 fl = floor(pos);
        vec2 f = pos - fl;
        ivec2 i = ivec2(fl);
        float a = stack_fetch(level, i, work, wrap);
        float b = stack_fetch(level, i + ivec2(1, 0), work, wrap);
        float c = stack_fetch(level, i + ivec2(0, 1), work, wrap);
        float d = stack_fetch(level, i + ivec2(1, 1), work, wrap);
        h = mix(mix(a, b, f.x), mix(c, d, f.x), f.y);
    } else {
        hfgi_Level l = hfgi_table[level];
        h = hfgi_bspline_at(l, hfgi_rescale(pos, vec2(work), l), wrap);
    }
    hfgi_result[q] = h;
}
