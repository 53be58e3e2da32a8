#version 460
// Brute-force ground truth (CONVENTIONS.md "Accuracy"; docs/accuracy.md §1), one invocation per
// texel of rows [row_offset, row_offset + rows). Per azimuth φ_a = 2π(a + ½)/A the bilinear
// surface is marched at `step`-texel steps (rays leaving the domain escape; with wrap the march
// ends after max(W, H) texels). Elevation integrals: Gauss–Legendre on [max(ω_hor, ω_t), π/2]
// (open directions: lighting) and on [ω_t, ω_hor] (blocked directions: the previous bounce's
// radiance at the first hit), ω_t the exact tangent elevation. Outputs per texel:
//   exact mode:  E = ∫ L_in max(N·ω, 0) dω (rgb) in element 0;
//   SH mode:     V_k = ∫_open y_k dω (direct, .x) or U_k = ∫_blocked L_hit y_k dω (indirect, rgb).
// The host finishes the shading in f64 (ρ/π, L ⊛ V, clamped-cosine ZH).
#include "hfgi_shared.glsl"
layout(local_size_x = 8, local_size_y = 8) in;
layout(constant_id = 0) const int HFGI_N = 4;
layout(constant_id = 1) const int HFGI_NODES = 16;
const int HFGI_N2 = HFGI_N * HFGI_N;

layout(std430, binding = 0) readonly buffer Heights { float hfgi_h[]; };       // W×H
layout(std430, binding = 1) readonly buffer Light { vec4 hfgi_light[]; };      // n² rgb
layout(std430, binding = 2) readonly buffer Source { vec4 hfgi_source[]; };    // W×H rgb: L_{b-1}
layout(std430, binding = 3) readonly buffer Gauss { vec2 hfgi_gauss[]; };      // nodes, weights on [-1, 1]
layout(std430, binding = 4) readonly buffer Consts { float hfgi_klm[64]; };
layout(std430, binding = 5) buffer Out { vec4 hfgi_out[]; };                   // texel × n² (accumulated over azimuth chunks)
layout(push_constant) uniform Push { hfgi_TruthPush pc; };
#include "hfgi_sh.glsl"

// Index of texel t, clamped to the edge or periodic with wrap.
uint texel_index(ivec2 t) {
    int w = int(pc.width), h = int(pc.height);
    if (pc.wrap != 0u) { t = ivec2(((t.x % w) + w) % w, ((t.y % h) + h) % h); }
    else { t = clamp(t, ivec2(0), ivec2(w - 1, h - 1)); }
    return uint(t.y) * pc.width + uint(t.x);
}

float height_at(ivec2 t) {
    return hfgi_h[texel_index(t)];
}

float bilinear_h(vec2 q) {
    vec2 fl = floor(q);
    vec2 f = q - fl;
    ivec2 b = ivec2(fl);
    return mix(mix(height_at(b), height_at(b + ivec2(1, 0)), f.x), mix(height_at(b + ivec2(0, 1)), height_at(b + ivec2(1, 1)), f.x), f.y);
}

vec3 source_at(ivec2 t) {
    return hfgi_source[texel_index(t)].rgb;
}

vec3 bilinear_source(vec2 q) {
    vec2 fl = floor(q);
    vec2 f = q - fl;
    ivec2 b = ivec2(fl);
    return mix(mix(source_at(b), source_at(b + ivec2(1, 0)), f.x), mix(source_at(b + ivec2(0, 1)), source_at(b + ivec2(1, 1)), f.x), f.y);
}

// CONVENTIONS.md normal (one-sided at the border, periodic with wrap).
vec3 normal_at(ivec2 p) {
    int w = int(pc.width), h = int(pc.height);
    ivec2 a = pc.wrap != 0u ? p - 1 : max(p - 1, ivec2(0));
    ivec2 b = pc.wrap != 0u ? p + 1 : min(p + 1, ivec2(w - 1, h - 1));
    float hx = (height_at(ivec2(b.x, p.y)) - height_at(ivec2(a.x, p.y))) / (float(b.x - a.x) * pc.texel_size);
    float hy = (height_at(ivec2(p.x, b.y)) - height_at(ivec2(p.x, a.y))) / (float(b.y - a.y) * pc.texel_size);
    return normalize(vec3(-hx, -hy, 1.0));
}

bool inside(vec2 q, float t) {
    if (pc.wrap != 0u) return t <= float(max(pc.width, pc.height));
    return q.x >= 0.0 && q.y >= 0.0 && q.x <= float(pc.width - 1u) && q.y <= float(pc.height - 1u);
}

// A bound on the march length (steps) from p along d: the domain is left by then (or, with
// wrap, max(W, H) texels are covered). Loops get an explicit trip count: lavapipe cuts
// unbounded loops short after a few thousand iterations.
uint march_bound(vec2 p, vec2 d) {
    float t = float(max(pc.width, pc.height));
    if (pc.wrap == 0u) {
        vec2 hi = vec2(float(pc.width - 1u), float(pc.height - 1u));
        float tx = d.x > 1e-6 ? (hi.x - p.x) / d.x : (d.x < -1e-6 ? -p.x / d.x : 1e9);
        float ty = d.y > 1e-6 ? (hi.y - p.y) / d.y : (d.y < -1e-6 ? -p.y / d.y : 1e9);
        t = min(tx, ty);
    }
    return uint(max(t, 0.0) / pc.step) + 2u;
}

vec3 hfgi_acc[HFGI_N2];

void main() {
    ivec2 p = ivec2(gl_GlobalInvocationID.x, gl_GlobalInvocationID.y + pc.row_offset);
    if (p.x >= int(pc.width) || p.y >= int(pc.height) || gl_GlobalInvocationID.y >= pc.rows) return;
    float h0 = height_at(p);
    vec3 N = normal_at(p);
    bool sh_mode = pc.sh_visibility != 0u;
    bool indirect = pc.indirect != 0u;
    for (int k = 0; k < HFGI_N2; ++k) hfgi_acc[k] = vec3(0.0);
    float dphi = 6.283185307179586 / float(pc.azimuths);
    // Azimuths [azimuth_first, azimuth_first + azimuth_count) of A: lavapipe truncates an
    // invocation's loops after some ten thousand iterations, so the host splits A into chunks.
    for (uint a = pc.azimuth_first; a < pc.azimuth_first + pc.azimuth_count; ++a) {
        float phi = (float(a) + 0.5) * dphi;
        vec2 d = vec2(cos(phi), sin(phi));
        // Horizon: the largest blocking angle along the march.
        float hor = -1.5707963267948966;
        uint bound = march_bound(vec2(p), d);
        for (uint k = 1u; k <= bound; ++k) {
            float t = float(k) * pc.step;
            vec2 q = vec2(p) + t * d;
            if (!inside(q, t)) break;
            hor = max(hor, atan((bilinear_h(q) - h0) / (t * pc.texel_size)));
        }
        float tangent = atan(-(N.x * d.x + N.y * d.y), N.z);
        if (!indirect) {
            float lo = sh_mode ? hor : max(hor, tangent);
            float half_w = 0.5 * (1.5707963267948966 - lo), mid = 0.5 * (1.5707963267948966 + lo);
            for (int e = 0; e < HFGI_NODES; ++e) {
                float om = mid + half_w * hfgi_gauss[e].x;
                float wt = half_w * hfgi_gauss[e].y * cos(om) * dphi;
                vec3 dir = vec3(cos(om) * d, sin(om));
                hfgi_sh_eval(dir);
                if (sh_mode) {
                    for (int k = 0; k < HFGI_N2; ++k) hfgi_acc[k].x += wt * hfgi_y[k];
                } else {
                    vec3 L = vec3(0.0);
                    for (int k = 0; k < HFGI_N2; ++k) L += hfgi_light[k].rgb * hfgi_y[k];
                    hfgi_acc[0] += wt * max(dot(N, dir), 0.0) * L;
                }
            }
        } else if (hor > tangent) {
            // Blocked directions: nodes ascend and the running maximum of the blocking angle
            // sweeps them; a node's first hit is the sample that lifts the maximum past it.
            float half_w = 0.5 * (hor - tangent), mid = 0.5 * (hor + tangent);
            float running = -1.5707963267948966;
            uint k = 1u;
            vec2 hit = vec2(p);
            for (int e = 0; e < HFGI_NODES; ++e) {
                float om = mid + half_w * hfgi_gauss[e].x;
                bool found = running >= om;
                while (!found && k <= bound) {
                    float t = float(k) * pc.step;
                    vec2 q = vec2(p) + t * d;
                    if (!inside(q, t)) break;
                    k += 1u;
                    float w_k = atan((bilinear_h(q) - h0) / (t * pc.texel_size));
                    if (w_k > running) { running = w_k; hit = q; }
                    found = running >= om;
                }
                if (!found) break;
                vec3 r = bilinear_source(hit);
                float wt = half_w * hfgi_gauss[e].y * cos(om) * dphi;
                vec3 dir = vec3(cos(om) * d, sin(om));
                if (sh_mode) {
                    hfgi_sh_eval(dir);
                    for (int c = 0; c < HFGI_N2; ++c) hfgi_acc[c] += wt * hfgi_y[c] * r;
                } else {
                    hfgi_acc[0] += wt * max(dot(N, dir), 0.0) * r;
                }
            }
        }
    }
    uint base = (uint(p.y) * pc.width + uint(p.x)) * uint(HFGI_N2);
    bool first = pc.azimuth_first == 0u;
    for (int k = 0; k < (sh_mode ? HFGI_N2 : 1); ++k) {
        vec3 prev = first ? vec3(0.0) : hfgi_out[base + uint(k)].rgb;
        hfgi_out[base + uint(k)] = vec4(prev + hfgi_acc[k], 0.0);
    }
}
