// hfgi — the level-0 height field as CONVENTIONS.md defines it, for shaders that read the raw
// heights (local lights, sphere blockers, the view's spheres): texel heights, the bilinear
// surface, the normal, and the exact horizon slope along a ray over it. The includer defines,
// before including: HFGI_FIELD_H(i) (the absolute height at row-major index i, a float
// expression), HFGI_FIELD_W and HFGI_FIELD_HGT (the field size, uint expressions) and
// HFGI_FIELD_S (the texel size). Twins: HeightField::bilinear, reference::direct::normals,
// reference::sweep::near_slope_on.
#ifndef HFGI_FIELD_GLSL
#define HFGI_FIELD_GLSL
#include "hfgi_near.glsl"

float hfgi_field_height(int x, int y) {
    return HFGI_FIELD_H(uint(y) * HFGI_FIELD_W + uint(x));
}

// The bilinear surface at level-0 position q, clamped to the field.
float hfgi_field_bilinear(vec2 q) {
    vec2 c = clamp(q, vec2(0.0), vec2(HFGI_FIELD_W - 1u, HFGI_FIELD_HGT - 1u));
    ivec2 i = min(ivec2(floor(c)), ivec2(HFGI_FIELD_W - 2u, HFGI_FIELD_HGT - 2u));
    vec2 f = c - vec2(i);
    float a = mix(hfgi_field_height(i.x, i.y), hfgi_field_height(i.x + 1, i.y), f.x);
    float b = mix(hfgi_field_height(i.x, i.y + 1), hfgi_field_height(i.x + 1, i.y + 1), f.x);
    return mix(a, b, f.y);
}

// CONVENTIONS.md normal at texel p: central differences inside, one-sided at the border.
vec3 hfgi_field_normal(ivec2 p) {
    int w = int(HFGI_FIELD_W), h = int(HFGI_FIELD_HGT);
    int x0 = max(p.x - 1, 0), x1 = min(p.x + 1, w - 1), y0 = max(p.y - 1, 0), y1 = min(p.y + 1, h - 1);
    float hx = (hfgi_field_height(x1, p.y) - hfgi_field_height(x0, p.y)) / (float(x1 - x0) * HFGI_FIELD_S);
    float hy = (hfgi_field_height(p.x, y1) - hfgi_field_height(p.x, y0)) / (float(y1 - y0) * HFGI_FIELD_S);
    return normalize(vec3(-hx, -hy, 1.0));
}

// sup (F(t) − base)/t for t ∈ (0, reach] texels along unit d from level-0 position p, F the
// bilinear surface (world units): one quadratic per cell the ray crosses, exact on the bilinear
// surface (as the sweep's near field, hfgi_near_slope). `base` is the height the slopes are
// measured from (the surface at p, or a point above it). False where the ray leaves at once.
bool hfgi_field_slope(vec2 p, vec2 d, float reach, float base, out float best) {
    best = -1e30;
    vec2 n = vec2(HFGI_FIELD_W, HFGI_FIELD_HGT);
    float ex = d.x > 0.0 ? (n.x - 1.0 - p.x) / d.x : (d.x < 0.0 ? p.x / -d.x : 1e30);
    float ey = d.y > 0.0 ? (n.y - 1.0 - p.y) / d.y : (d.y < 0.0 ? p.y / -d.y : 1e30);
    float t_end = min(reach, min(ex, ey));
    if (t_end <= 0.0) return false;
    vec2 stp = vec2(abs(d.x) > 1e-6 ? 1.0 / abs(d.x) : 1e30, abs(d.y) > 1e-6 ? 1.0 / abs(d.y) : 1e30);
    vec2 dist = vec2(d.x > 0.0 ? floor(p.x) + 1.0 - p.x : p.x - ceil(p.x) + 1.0,
                     d.y > 0.0 ? floor(p.y) + 1.0 - p.y : p.y - ceil(p.y) + 1.0);
    vec2 tn = dist * stp;
    // A point above the surface starts a hair along the ray (F/t → −∞ at 0); one below it is
    // blocked in every direction.
    float f0 = hfgi_field_bilinear(p) - base;
    if (f0 > 0.0) {
        best = 1e30;
        return true;
    }
    float ta = f0 < 0.0 ? 1e-3 : 0.0;
    float fa = f0 < 0.0 ? hfgi_field_bilinear(p + ta * d) - base : 0.0;
    for (int guard = 0; guard < 4 * int(t_end) + 8; ++guard) {
        float tb = min(min(tn.x, tn.y), t_end);
        if (tb > ta + 1e-6) {
            float len = tb - ta;
            float fm = hfgi_field_bilinear(p + (ta + 0.5 * len) * d) - base;
            float fb = hfgi_field_bilinear(p + tb * d) - base;
            float a = 2.0 * (fb - 2.0 * fm + fa) / (len * len);
            float b = (fb - fa) / len - a * len;
            best = max(best, hfgi_piece_max(ta, tb, a, b, fa));
            fa = fb;
            ta = tb;
        }
        if (tb >= t_end) break;
        if (tn.x <= tb) tn.x += stp.x;
        if (tn.y <= tb) tn.y += stp.y;
    }
    return true;
}

#endif
