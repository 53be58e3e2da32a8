#version 460
// Indirect radiance vectors (NS09 §3, §5.2–5.3, §6; docs/indirect.md §2–3) at every receiver of
// the working grid. Per azimuth φ_j: scan the height pyramid with the steps of eq. 14–16, keep
// the casting set (eq. 6: samples whose blocking angle exceeds ω_min and every nearer sample),
// read each member's radiance from the radiance pyramid of the previous bounce, accumulate the
// NLP vector u of eq. 12 (piecewise constant in ω, eq. 8, starting at ω_min), and fold the wedges
// and z-rotations of eq. 19–21 into U += A_j u_j (per RGB channel).
#include "hfgi_shared.glsl"
layout(local_size_x = 8, local_size_y = 8) in;
layout(constant_id = 0) const int HFGI_N = 4;   // SH order n
layout(constant_id = 1) const int HFGI_NV = 33; // height-pyramid levels n_v (scan samples)
layout(constant_id = 2) const int HFGI_VECTOR = 0; // 1: glossy vector pyramid (docs/indirect.md §1–2)
const int HFGI_N2 = HFGI_N * HFGI_N;

layout(std430, binding = 0) readonly buffer Levels { float hfgi_levels[]; };
layout(std430, binding = 1) readonly buffer Table { hfgi_Level hfgi_table[]; };
layout(std430, binding = 2) readonly buffer Stack { float hfgi_stack[]; };
layout(std430, binding = 3) readonly buffer RLevels { float hfgi_radiance_levels[]; };
layout(std430, binding = 4) readonly buffer RTable { hfgi_Level hfgi_radiance_table[]; };
layout(std430, binding = 5) readonly buffer RStack { float hfgi_radiance_stack[]; };
layout(std430, binding = 6) readonly buffer Samples { vec4 hfgi_samples[]; }; // cos φ, sin φ
layout(std430, binding = 7) readonly buffer Fold { float hfgi_fold[]; };      // A_j: n² × n
layout(std430, binding = 8) readonly buffer RLevel { uint hfgi_radiance_level[]; }; // per scan sample
layout(std430, binding = 9) writeonly buffer U { vec4 hfgi_u[]; };            // receivers × n²
layout(std430, binding = 10) readonly buffer Consts {                         // the shading constants
    float hfgi_klm[64];
    float hfgi_zh_diffuse[8];
    float hfgi_zh_glossy[8]; // √(4π/(2l+1)) · Phong ZH
    uint hfgi_triple_count;
};
layout(push_constant) uniform Push { hfgi_IndirectPush pc; };
#define HFGI_LEVEL_READ(l, i) ((l).source == 0u ? hfgi_levels[i] : hfgi_radiance_levels[i])
#define HFGI_STACK_READ(source, i) ((source) == 0u ? hfgi_stack[i] : hfgi_radiance_stack[i])
#include "hfgi_pyramid.glsl"
#include "hfgi_nlp.glsl"
#include "hfgi_sh.glsl"

float hfgi_base[HFGI_NV];
vec3 hfgi_U[HFGI_N2];

// CONVENTIONS.md height gradient at texel (i, j) of level 0 (one-sided at the border, periodic
// with wrap).
vec2 gradient(ivec2 t, bool wrap) {
    hfgi_Level l0 = hfgi_table[0];
    int w = int(l0.width), h = int(l0.height);
    t = ivec2(hfgi_address(t.x, w, wrap), hfgi_address(t.y, h, wrap));
    ivec2 a = wrap ? t - 1 : max(t - 1, ivec2(0));
    ivec2 b = wrap ? t + 1 : min(t + 1, ivec2(w - 1, h - 1));
    float hx = hfgi_fetch(l0, ivec2(b.x, t.y), wrap) - hfgi_fetch(l0, ivec2(a.x, t.y), wrap);
    float hy = hfgi_fetch(l0, ivec2(t.x, b.y), wrap) - hfgi_fetch(l0, ivec2(t.x, a.y), wrap);
    return vec2(hx / (float(b.x - a.x) * pc.texel_size), hy / (float(b.y - a.y) * pc.texel_size));
}

// Normal at level-0 position q: the gradients of the four surrounding texels, bilinear, then
// normalised (docs/indirect.md §2; the receiver's and, in vector mode, a casting point's).
vec3 normal_at(vec2 q, bool wrap) {
    vec2 fl = floor(q);
    vec2 f = q - fl;
    ivec2 b = ivec2(fl);
    vec2 g = (1.0 - f.x) * (1.0 - f.y) * gradient(b, wrap) + f.x * (1.0 - f.y) * gradient(b + ivec2(1, 0), wrap)
           + (1.0 - f.x) * f.y * gradient(b + ivec2(0, 1), wrap) + f.x * f.y * gradient(b + ivec2(1, 1), wrap);
    return normalize(vec3(-g, 1.0));
}

// Exit radiance of casting point q toward the receiver (docs/indirect.md §2): the diffuse RGB
// pyramid, plus in vector mode k_s · ⟨T(q), Phong ZH rotated to R⟩ with R the reflection of the
// direction back to the receiver about q's normal.
vec3 member_radiance(uint lv, vec2 q, float omega, vec2 d, uvec2 work, bool stack_mode, bool wrap) {
    hfgi_Level r0 = hfgi_radiance_table[0];
    uint n_u = pc.radiance_levels;
    vec3 rad;
    for (uint c = 0u; c < 3u; ++c) {
        uint e = c * n_u + lv;
        rad[c] = hfgi_pyramid_at(r0, hfgi_radiance_table[e], e, q, work, stack_mode, wrap);
    }
    if (HFGI_VECTOR != 0) {
        vec3 nc = normal_at(q, wrap);
        vec3 s = -vec3(cos(omega) * d, sin(omega));
        hfgi_sh_eval(normalize(2.0 * dot(nc, s) * nc - s));
        vec3 gl = vec3(0.0);
        for (int l = 0; l < HFGI_N; ++l) {
            for (int m = -l; m <= l; ++m) {
                int k = l * (l + 1) + m;
                vec3 t;
                for (uint c = 0u; c < 3u; ++c) {
                    uint e = (3u + 3u * uint(k) + c) * n_u + lv;
                    t[c] = hfgi_pyramid_at(r0, hfgi_radiance_table[e], e, q, work, false, wrap);
                }
                gl += t * (hfgi_zh_glossy[l] * hfgi_y[k]);
            }
        }
        rad += pc.specular.rgb * gl;
    }
    return rad;
}

void main() {
    uvec2 r = gl_GlobalInvocationID.xy;
    if (r.x >= pc.work_width || r.y >= pc.work_height) return;
    bool wrap = pc.wrap != 0u;
    hfgi_Scan scan = hfgi_scan_begin(r, uvec2(pc.work_width, pc.work_height), pc.level_step, pc.level_bias,
                                     pc.texel_size, pc.stack_mode != 0u, wrap);
    vec3 N = normal_at(scan.p, wrap);
    for (int i = 0; i < HFGI_NV; ++i) hfgi_base[i] = hfgi_scan_base(scan, i);
    for (int k = 0; k < HFGI_N2; ++k) hfgi_U[k] = vec3(0.0);
    for (uint j = 0u; j < pc.sample_count; ++j) {
        vec2 d = hfgi_samples[j].xy;
        // ω_min: the tangent plane of the receiver along φ (§3).
        float running = -asin(clamp(dot(N.xy, d), -1.0, 1.0));
        vec3 u[HFGI_N];
        for (int l = 0; l < HFGI_N; ++l) u[l] = vec3(0.0);
        for (int i = 0; i < HFGI_NV; ++i) {
            vec2 q;
            float omega;
            if (!hfgi_scan_sample(scan, i, HFGI_NV, d, hfgi_base[i], q, omega)) break;
            if (omega > running) {
                // Casting-set member (eq. 6), seen over [running, ω): eq. 12 telescoped.
                float seg[HFGI_N];
                hfgi_interval(running, omega, seg);
                vec3 rad = member_radiance(hfgi_radiance_level[i], q, omega, d, scan.work, pc.radiance_stack != 0u, wrap);
                for (int l = 0; l < HFGI_N; ++l) u[l] += rad * seg[l];
                running = omega;
            }
        }
        // eq. 19–21 folded: U += A_j u_j.
        uint base = j * uint(HFGI_N2 * HFGI_N);
        for (int k = 0; k < HFGI_N2; ++k) {
            vec3 acc = vec3(0.0);
            for (int l = 0; l < HFGI_N; ++l) acc += hfgi_fold[base + uint(k * HFGI_N + l)] * u[l];
            hfgi_U[k] += acc;
        }
    }
    uint out_base = (r.y * pc.work_width + r.x) * uint(HFGI_N2);
    for (int k = 0; k < HFGI_N2; ++k) hfgi_u[out_base + uint(k)] = vec4(hfgi_U[k], 0.0);
}
