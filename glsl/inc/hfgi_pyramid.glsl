// hfgi — height lookups in the pyramid, the way every scanning pass does them.
// The includer declares `float hfgi_levels[]`, `hfgi_Level hfgi_table[]` and `float hfgi_stack[]`
// (bind the levels buffer as the stack in pyramid mode), then includes this file.
// Positions are in level-0 texel units.
#ifndef HFGI_PYRAMID_GLSL
#define HFGI_PYRAMID_GLSL
#include "hfgi_filter.glsl"

float hfgi_stack_fetch(uint level, ivec2 p, uvec2 work, bool wrap) {
    int x = hfgi_address(p.x, int(work.x), wrap);
    int y = hfgi_address(p.y, int(work.y), wrap);
    return hfgi_stack[level * work.x * work.y + uint(y) * work.x + uint(x)];
}

// Stack mode: bilinear on the synthesized plane (working resolution `work`).
// Pyramid mode: the cubic B-spline of the decimated level, on the fly.
float hfgi_height_at(uint level, vec2 p0, uvec2 work, bool stack_mode, bool wrap) {
    hfgi_Level base = hfgi_table[0];
    vec2 n0 = vec2(float(base.width), float(base.height));
    if (stack_mode) {
        vec2 pw = (p0 + 0.5) * vec2(work) / n0 - 0.5;
        vec2 fl = floor(pw);
        vec2 f = pw - fl;
        ivec2 i = ivec2(fl);
        float a = hfgi_stack_fetch(level, i, work, wrap);
        float b = hfgi_stack_fetch(level, i + ivec2(1, 0), work, wrap);
        float c = hfgi_stack_fetch(level, i + ivec2(0, 1), work, wrap);
        float d = hfgi_stack_fetch(level, i + ivec2(1, 1), work, wrap);
        return mix(mix(a, b, f.x), mix(c, d, f.x), f.y);
    }
    hfgi_Level l = hfgi_table[level];
    return hfgi_bspline_at(l, hfgi_rescale(p0, n0, l), wrap);
}

// Pyramid level read by scan sample i (NS09 §5.2 level offset; docs/direct.md §2): the level
// whose texel matches the step t_i, biased k·o levels finer ("sharper long-range shadows").
uint hfgi_scan_level(int i, uint bias) {
    return uint(max(i - int(bias), 0));
}

#endif
