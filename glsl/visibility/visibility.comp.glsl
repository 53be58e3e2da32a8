#version 460
#extension GL_EXT_control_flow_attributes : require
// Visibility of one light set (environment or a key light) at every receiver of the working
// grid (NS09 §5.2 and §6; docs/direct.md §1–4). Per azimuth sample j: scan the pyramid with
// exponentially growing steps (eq. 14–16), take ω_max as the maximum of the cubic B-spline
// through the blocking angles at knots and mid-points (eq. 17), project the visible window to
// NLP (eq. 10–11) and accumulate V += A_j v_j, where A_j folds the wedge matrices and the
// z-rotations of eq. 20–21 (built in f64 on the host). With HFGI_FLAG_SWEEP, ω_max comes from
// the line sweep's horizons (binding 6, docs/direct.md §7) instead of the scan.
#include "hfgi_shared.glsl"
layout(local_size_x = HFGI_WORKGROUP, local_size_y = HFGI_WORKGROUP) in;
layout(constant_id = 0) const int HFGI_N = 4;   // SH order n
layout(constant_id = 1) const int HFGI_NV = 33; // pyramid levels n_v
layout(constant_id = 2) const int HFGI_NE = 4;  // values per azimuth: n (NLP) or 2n + 1 (legendre moments)
// Static modes (frame::shared::static_modes; the push constants' stack_mode, wrap and flags
// without the dynamic bits): branches on them are compiled out (docs/performance.md §5).
layout(constant_id = 3) const uint HFGI_STACK = 1u;
layout(constant_id = 4) const uint HFGI_WRAP = 0u;
layout(constant_id = 5) const uint HFGI_STATIC_FLAGS = 0u;
layout(constant_id = 6) const uint HFGI_HALF = 0u; // gi.storage: 1 = f16 (hfgi_store.glsl)
layout(constant_id = 7) const int HFGI_FOLD_SIZE = 1; // vec4 texels of A_j per azimuth (shared::fold_texels)
const int HFGI_N2 = HFGI_N * HFGI_N;

// What is read per sample or per azimuth is read through texel views of 32-bit words
// (HFGI_TEXELS, hfgi_filter.glsl; docs/performance.md §17).
#define HFGI_TEXELS
layout(binding = 0) uniform usamplerBuffer hfgi_levels_texels;
layout(std430, binding = 1) readonly buffer Table { hfgi_Level hfgi_table[]; };
layout(binding = 2) uniform usamplerBuffer hfgi_stack_texels;
layout(binding = 3) uniform usamplerBuffer hfgi_samples_texels; // cos φ, sin φ, lo, hi (f32 bits)
layout(binding = 4) uniform usamplerBuffer hfgi_fold_texels;    // A_j per azimuth (hfgi_fold.glsl, shared::gpu_fold)
layout(std430, binding = 5) buffer Vis { uint hfgi_vis[]; };    // accumulated over azimuth chunks (hfgi_store.glsl)
layout(binding = 6) uniform usamplerBuffer hfgi_horizons_texels; // sweep: [sample][receiver][2]
layout(binding = 7) uniform usamplerBuffer hfgi_hplanes_texels;  // the height stack's planes (hfgi_pyramid.glsl)
layout(binding = 8) uniform usamplerBuffer hfgi_max_texels;      // pyramid.max (f32 bits; with HFGI_FLAG_MAX_BOUND)
#define hfgi_max(i) HFGI_TEXEL_F(hfgi_max_texels, i)
layout(push_constant) uniform Push { hfgi_VisibilityPush pc; };
#include "hfgi_pyramid.glsl"
#include "hfgi_elevation.glsl"
#include "hfgi_near.glsl"
#include "hfgi_store.glsl"
#include "hfgi_fold.glsl"
#include "hfgi_max.glsl"

float hfgi_omega[HFGI_NV];
float hfgi_base[HFGI_NV];

// ω_max along d (eq. 14–17). The valid samples form a prefix of the ladder [first, end). With
// HFGI_FLAG_HORIZON_SAMPLES it is their largest blocking angle (docs/accuracy.md §4: eq. 17's
// spline maximum never exceeds the largest sample and lowers near horizons); otherwise the
// paper's maximum of the cubic B-spline through ω_i at knots and mid-points, ends extended by
// repetition through the ladder's n_v samples, and the largest of the extra samples (near and
// far steps, gi.near_steps and gi.scan_reach) beside it. With `bounded` (samples_max only) the
// ray ends where no farther sample can exceed the largest slope so far (hfgi_nothing_beyond,
// `gmax` the field's largest height, `bmin` the lowest base): the same ω_max.
float hfgi_horizon(hfgi_Scan scan, vec2 d, bool samples_max, bool bounded, float gmax, float bmin) {
    // The largest slope (of every sample with samples_max, else of the extra ones): atan is
    // monotonic, so one atan of it instead of one per sample (docs/performance.md §18).
    float smax = -3.402823466e38; // atan: −π/2 (no sample)
    int count = 0;
    float limit;
    if (scan.first < 0 && hfgi_scan_limit_slope(scan, d, limit)) smax = limit;
    float t = hfgi_scan_t(scan, scan.first, HFGI_NV), ratio = hfgi_scan_ratio(scan);
    for (int i = scan.first; i < scan.end; ++i, t *= ratio) {
        if (hfgi_nothing_beyond(bounded, gmax, bmin, smax, t, scan.texel_size)) break;
        vec2 q;
        float slope;
        if (!hfgi_scan_slope(scan, i, t, HFGI_NV, d, hfgi_base[hfgi_scan_level(i, scan.level_bias, HFGI_NV)], q, slope))
            break;
        if (samples_max || i < 0 || i >= HFGI_NV) {
            smax = max(smax, slope);
        } else {
            hfgi_omega[i] = atan(slope);
            count = i + 1;
        }
    }
    float wmax = atan(smax);
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

// The sweep's near field (docs/direct.md §7): sup F(t)/t for t ∈ (0, reach] along the receiver's
// own ray, one quadratic per level-0 cell through the surface at the piece's start, middle and
// end (exact on the bilinear surface). False where the ray leaves the field at once.
// Twin: reference::sweep::near_slope.
bool hfgi_near_slope(hfgi_Scan scan, vec2 d, float reach, out float best) {
    best = -1e30;
    vec2 p = scan.p, n = scan.n0;
    float ex = d.x > 0.0 ? (n.x - 1.0 - p.x) / d.x : (d.x < 0.0 ? p.x / -d.x : 1e30);
    float ey = d.y > 0.0 ? (n.y - 1.0 - p.y) / d.y : (d.y < 0.0 ? p.y / -d.y : 1e30);
    float t_end = min(reach, min(ex, ey));
    if (t_end <= 0.0) return false;
    vec2 stp = vec2(abs(d.x) > 1e-6 ? 1.0 / abs(d.x) : 1e30, abs(d.y) > 1e-6 ? 1.0 / abs(d.y) : 1e30);
    vec2 dist = vec2(d.x > 0.0 ? floor(p.x) + 1.0 - p.x : p.x - ceil(p.x) + 1.0,
                     d.y > 0.0 ? floor(p.y) + 1.0 - p.y : p.y - ceil(p.y) + 1.0);
    vec2 tn = dist * stp;
    float base = hfgi_height_at(scan, 0u, p);
    float ta = 0.0, fa = 0.0;
    for (int guard = 0; guard < 4 * int(reach) + 8; ++guard) {
        float tb = min(min(tn.x, tn.y), t_end);
        if (tb > ta + 1e-6) {
            float len = tb - ta;
            float fm = hfgi_height_at(scan, 0u, p + (ta + 0.5 * len) * d) - base;
            float fb = hfgi_height_at(scan, 0u, p + tb * d) - base;
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

void main() {
    uvec2 r = gl_GlobalInvocationID.xy;
    if (r.x >= pc.work_width || r.y >= pc.work_height) return;
    hfgi_Scan scan = hfgi_scan_begin(r, uvec2(pc.work_width, pc.work_height), pc.level_step, pc.level_bias,
                                     pc.texel_size, HFGI_STACK != 0u, HFGI_WRAP != 0u, HFGI_STATIC_FLAGS, pc.scan_extent,
                                     HFGI_NV);
    bool sweep = (HFGI_STATIC_FLAGS & HFGI_FLAG_SWEEP) != 0u;
    float bmin = 3.402823466e38; // the lowest base a sample is compared with (the early stop)
    if (!sweep) {
        // Not unrolled: n_v inlined height reads made most of the compile time (docs/performance.md §3).
        // Only the levels the scan reads (the stack holds no others; hfgi_scan_levels).
        int levels = hfgi_scan_levels(scan, HFGI_NV);
        [[dont_unroll]] for (int l = 0; l < levels; ++l) {
            hfgi_base[l] = hfgi_scan_base(scan, uint(l));
            bmin = min(bmin, hfgi_base[l]);
        }
    }
    bool samples_max = (HFGI_STATIC_FLAGS & HFGI_FLAG_HORIZON_SAMPLES) != 0u;
    // The early stop (docs/performance.md §34): with the max pyramid, for the samples' maximum.
    bool bounded = samples_max && !sweep && (pc.flags & HFGI_FLAG_MAX_BOUND) != 0u;
    float gmax = bounded ? max(hfgi_max_top(uvec2(scan.n0)), bmin) : 0.0; // bmin ≤ gmax but for rounding
    uint receivers = pc.work_width * pc.work_height;

    float V[HFGI_N2];
    for (int k = 0; k < HFGI_N2; ++k) V[k] = 0.0;
    // gi.diffuse_lobe = "exact": V zero below the receiver's tangent plane, as the exact lobe
    // needs (docs/accuracy.md §6); the normal is the indirect scan's (hfgi_normal_at).
    bool clip = (HFGI_STATIC_FLAGS & HFGI_FLAG_TANGENT_CLIP) != 0u;
    vec3 N = clip ? hfgi_normal_at(scan.p, HFGI_WRAP != 0u, pc.texel_size) : vec3(0.0, 0.0, 1.0);

    for (uint j = 0u; j < pc.sample_count; ++j) {
        vec4 smp = uintBitsToFloat(texelFetch(hfgi_samples_texels, int(pc.sample_offset + j)));
        float wmax;
        if (sweep) {
            // The two lines' weighted horizons (glsl/visibility/sweep.comp.glsl).
            uint h = ((pc.sample_offset + j - pc.horizon_first) * receivers + r.y * pc.work_width + r.x) * 2u;
            wmax = HFGI_TEXEL_F(hfgi_horizons_texels, h) + HFGI_TEXEL_F(hfgi_horizons_texels, h + 1u);
            float near;
            if (pc.sweep_near > 0.0 && hfgi_near_slope(scan, smp.xy, pc.sweep_near, near))
                wmax = max(wmax, atan(near / pc.texel_size));
        } else {
            wmax = hfgi_horizon(scan, smp.xy, samples_max, bounded, gmax, bmin);
        }
        // eq. 11 within the sample's elevation window (§6), in the NLP or legendre basis.
        if (clip) wmax = max(wmax, hfgi_tangent_elevation(N, smp.xy));
        float v[HFGI_NE];
        hfgi_elevation(max(wmax, smp.z), smp.w, v);
        // eq. 20–21 folded: V += A_j v_j (hfgi_fold.glsl: in the legendre basis only A_j's
        // non-zero entries, shared::gpu_fold; docs/performance.md §19, §22).
        HFGI_FOLD(float, hfgi_fold_texels, (pc.sample_offset + j) * uint(HFGI_FOLD_SIZE), v, V, HFGI_N2)
    }
    // Receiver stride n², rounded up to even with f16 (Storage::stride); out_offset likewise.
    uint stride = hfgi_stride(HFGI_N2);
    uint out_base = pc.out_offset + (r.y * pc.work_width + r.x) * stride;
    bool acc = (pc.flags & HFGI_FLAG_ACCUMULATE) != 0u;
#define HFGI_V_AT(k) V[k]
    HFGI_STORE(hfgi_vis, out_base, HFGI_N2, HFGI_V_AT, acc)
}
