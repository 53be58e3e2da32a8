#version 460
// Visibility of one light set (environment or a key light) at every receiver of the working
// grid (NS09 §5.2 and §6; docs/direct.md §1–4). Per azimuth sample j: scan the pyramid with
// exponentially growing steps (eq. 14–16), take ω_max as the maximum of the cubic B-spline
// through the blocking angles at knots and mid-points (eq. 17), project the visible window to
// NLP (eq. 10–11) and accumulate V += A_j v_j, where A_j folds the wedge matrices and the
// z-rotations of eq. 20–21 (built in f64 on the host).
#include "hfgi_shared.glsl"
layout(local_size_x = 8, local_size_y = 8) in;
layout(constant_id = 0) const int HFGI_N = 4;   // SH order n
layout(constant_id = 1) const int HFGI_NV = 33; // pyramid levels n_v
const int HFGI_N2 = HFGI_N * HFGI_N;

layout(std430, binding = 0) readonly buffer Levels { float hfgi_levels[]; };
layout(std430, binding = 1) readonly buffer Table { hfgi_Level hfgi_table[]; };
layout(std430, binding = 2) readonly buffer Stack { float hfgi_stack[]; };
layout(std430, binding = 3) readonly buffer Samples { vec4 hfgi_samples[]; }; // cos φ, sin φ, lo, hi
layout(std430, binding = 4) readonly buffer Fold { float hfgi_fold[]; };      // A_j: n² × n, row-major
layout(std430, binding = 5) writeonly buffer Vis { float hfgi_vis[]; };
layout(push_constant) uniform Push { hfgi_VisibilityPush pc; };
#include "hfgi_pyramid.glsl"
#include "hfgi_nlp.glsl"

float hfgi_omega[HFGI_NV];
float hfgi_base[HFGI_NV];

void main() {
    uvec2 r = gl_GlobalInvocationID.xy;
    if (r.x >= pc.work_width || r.y >= pc.work_height) return;
    hfgi_Scan scan = hfgi_scan_begin(r, uvec2(pc.work_width, pc.work_height), pc.level_step, pc.level_bias,
                                     pc.texel_size, pc.stack_mode != 0u, pc.wrap != 0u);
    for (int i = 0; i < HFGI_NV; ++i) hfgi_base[i] = hfgi_scan_base(scan, i);

    float V[HFGI_N2];
    for (int k = 0; k < HFGI_N2; ++k) V[k] = 0.0;

    for (uint j = 0u; j < pc.sample_count; ++j) {
        vec4 smp = hfgi_samples[pc.sample_offset + j];
        vec2 d = smp.xy;
        // eq. 14–16 (hfgi_scan_sample): the valid samples form a prefix of length count.
        int count = 0;
        for (int i = 0; i < HFGI_NV; ++i) {
            vec2 q;
            if (!hfgi_scan_sample(scan, i, HFGI_NV, d, hfgi_base[i], q, hfgi_omega[i])) break;
            count = i + 1;
        }
        // eq. 17: max of the B-spline through ω_0..ω_{count−1} at knots and mid-points,
        // ends extended by repetition.
        float wmax = -1.5707963267948966;
        for (int i = 0; i < count; ++i) {
            float a = hfgi_omega[max(i - 1, 0)];
            float b = hfgi_omega[i];
            float c = hfgi_omega[min(i + 1, count - 1)];
            wmax = max(wmax, (a + 4.0 * b + c) / 6.0);
            if (i + 1 < count) {
                float e = hfgi_omega[min(i + 2, count - 1)];
                wmax = max(wmax, (a + 23.0 * b + 23.0 * c + e) / 48.0);
            }
        }
        // eq. 11 within the sample's elevation window (§6).
        float v[HFGI_N];
        hfgi_interval(max(wmax, smp.z), smp.w, v);
        // eq. 20–21 folded: V += A_j v_j.
        uint base = (pc.sample_offset + j) * uint(HFGI_N2 * HFGI_N);
        for (int k = 0; k < HFGI_N2; ++k) {
            float acc = 0.0;
            for (int l = 0; l < HFGI_N; ++l) acc += hfgi_fold[base + uint(k * HFGI_N + l)] * v[l];
            V[k] += acc;
        }
    }
    uint out_base = pc.out_offset + (r.y * pc.work_width + r.x) * uint(HFGI_N2);
    for (int k = 0; k < HFGI_N2; ++k) hfgi_vis[out_base + uint(k)] = V[k];
}
