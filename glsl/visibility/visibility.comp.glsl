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
layout(constant_id = 2) const int HFGI_NE = 4;  // values per azimuth: n (NLP) or 2n + 1 (legendre moments)
const int HFGI_N2 = HFGI_N * HFGI_N;

layout(std430, binding = 0) readonly buffer Levels { float hfgi_levels[]; };
layout(std430, binding = 1) readonly buffer Table { hfgi_Level hfgi_table[]; };
layout(std430, binding = 2) readonly buffer Stack { float hfgi_stack[]; };
layout(std430, binding = 3) readonly buffer Samples { vec4 hfgi_samples[]; }; // cos φ, sin φ, lo, hi
layout(std430, binding = 4) readonly buffer Fold { float hfgi_fold[]; };      // A_j: n² × NE, row-major
layout(std430, binding = 5) buffer Vis { float hfgi_vis[]; };                  // accumulated over azimuth chunks
layout(push_constant) uniform Push { hfgi_VisibilityPush pc; };
#include "hfgi_pyramid.glsl"
#include "hfgi_elevation.glsl"

float hfgi_omega[HFGI_NV];
float hfgi_base[HFGI_NV];

// ω_max along d (eq. 14–17). The valid samples form a prefix of the ladder [first, end). With
// HFGI_FLAG_HORIZON_SAMPLES it is their largest blocking angle (docs/accuracy.md §4: eq. 17's
// spline maximum never exceeds the largest sample and lowers near horizons); otherwise the
// paper's maximum of the cubic B-spline through ω_i at knots and mid-points, ends extended by
// repetition through the ladder's n_v samples, and the largest of the extra samples (near and
// far steps, gi.near_steps and gi.scan_reach) beside it.
float hfgi_horizon(hfgi_Scan scan, vec2 d, bool samples_max) {
    float wmax = -1.5707963267948966;
    int count = 0;
    float limit;
    if (scan.first < 0 && hfgi_scan_limit(scan, d, limit)) wmax = limit;
    for (int i = scan.first; i < scan.end; ++i) {
        vec2 q;
        float omega;
        if (!hfgi_scan_sample(scan, i, HFGI_NV, d, hfgi_base[hfgi_scan_level(i, scan.level_bias, HFGI_NV)], q, omega))
            break;
        if (samples_max || i < 0 || i >= HFGI_NV) {
            wmax = max(wmax, omega);
        } else {
            hfgi_omega[i] = omega;
            count = i + 1;
        }
    }
    if (samples_max) return wmax;
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
    return wmax;
}

void main() {
    uvec2 r = gl_GlobalInvocationID.xy;
    if (r.x >= pc.work_width || r.y >= pc.work_height) return;
    hfgi_Scan scan = hfgi_scan_begin(r, uvec2(pc.work_width, pc.work_height), pc.level_step, pc.level_bias,
                                     pc.texel_size, pc.stack_mode != 0u, pc.wrap != 0u, pc.flags, pc.scan_extent,
                                     HFGI_NV);
    for (int l = 0; l < HFGI_NV; ++l) hfgi_base[l] = hfgi_scan_base(scan, uint(l));
    bool samples_max = (pc.flags & HFGI_FLAG_HORIZON_SAMPLES) != 0u;

    float V[HFGI_N2];
    for (int k = 0; k < HFGI_N2; ++k) V[k] = 0.0;

    for (uint j = 0u; j < pc.sample_count; ++j) {
        vec4 smp = hfgi_samples[pc.sample_offset + j];
        float wmax = hfgi_horizon(scan, smp.xy, samples_max);
        // eq. 11 within the sample's elevation window (§6), in the NLP or legendre basis.
        float v[HFGI_NE];
        hfgi_elevation(max(wmax, smp.z), smp.w, v);
        // eq. 20–21 folded: V += A_j v_j.
        uint base = (pc.sample_offset + j) * uint(HFGI_N2 * HFGI_NE);
        for (int k = 0; k < HFGI_N2; ++k) {
            float acc = 0.0;
            for (int l = 0; l < HFGI_NE; ++l) acc += hfgi_fold[base + uint(k * HFGI_NE + l)] * v[l];
            V[k] += acc;
        }
    }
    uint out_base = pc.out_offset + (r.y * pc.work_width + r.x) * uint(HFGI_N2);
    bool acc = (pc.flags & HFGI_FLAG_ACCUMULATE) != 0u;
    for (int k = 0; k < HFGI_N2; ++k) hfgi_vis[out_base + uint(k)] = V[k] + (acc ? hfgi_vis[out_base + uint(k)] : 0.0);
}
