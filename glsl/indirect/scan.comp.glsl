#version 460
#extension GL_EXT_control_flow_attributes : require
#extension GL_KHR_shader_subgroup_vote : require
// Indirect radiance vectors (NS09 §3, §5.2–5.3, §6; docs/indirect.md §2–3) at every receiver of
// the working grid. Per azimuth φ_j: scan the height pyramid with the steps of eq. 14–16, keep
// the casting set (eq. 6: samples whose blocking angle exceeds ω_min and every nearer sample),
// read each member's radiance from the radiance pyramid of the previous bounce, accumulate the
// NLP vector u of eq. 12 (piecewise constant in ω, eq. 8, starting at ω_min), and fold the wedges
// and z-rotations of eq. 19–21 into U += A_j u_j (per RGB channel).
#include "hfgi_shared.glsl"
layout(local_size_x = HFGI_WORKGROUP, local_size_y = HFGI_WORKGROUP) in;
layout(constant_id = 0) const int HFGI_N = 4;   // SH order n
layout(constant_id = 1) const int HFGI_NV = 33; // height-pyramid levels n_v (scan samples)
layout(constant_id = 2) const int HFGI_VECTOR = 0; // 1: glossy vector pyramid (docs/indirect.md §1–2)
layout(constant_id = 3) const int HFGI_NE = 4;     // values per azimuth: n (NLP) or 2n + 1 (legendre moments)
// Static modes (frame::shared::static_modes; the push constants' stack_mode, wrap, flags without
// the dynamic bits, and radiance_stack): branches on them are compiled out (docs/performance.md §5).
layout(constant_id = 4) const uint HFGI_STACK = 1u;
layout(constant_id = 5) const uint HFGI_WRAP = 0u;
layout(constant_id = 6) const uint HFGI_STATIC_FLAGS = 0u;
layout(constant_id = 7) const uint HFGI_RSTACK = 1u;
layout(constant_id = 8) const uint HFGI_HALF = 0u; // gi.storage: 1 = f16 (hfgi_store.glsl)
// (Constant 9, the max-pyramid bound's pipelines, is gone: the bound is now the early stop
// alone, a comparison per sample; docs/performance.md §18.)
// Coefficients of U stored and so accumulated (rules::scene::u_bands²): n², or only the bands a
// diffuse surface's clamped-cosine lobe does not zero (order 4: 9), docs/indirect.md §4.
layout(constant_id = 10) const int HFGI_NU = 16;
// 0: the pipeline of bounces without radial probes: the probes' code (a division and a ceil per
// sample, and their loop state) is compiled out (docs/performance.md §17).
layout(constant_id = 11) const uint HFGI_PROBES = 1u;
// The replay of the later bounces' casting set (docs/indirect.md §2, "Replay";
// rules::scene::replays): 0 off (every bounce walks), 1 the first bounce's walk, which also
// finds the members a walk without probes has and stores them as bits (hfgi_members), 2 a later
// bounce (no probes), which casts those members without walking (its walk is compiled out).
layout(constant_id = 12) const uint HFGI_REPLAY = 0u;
layout(constant_id = 13) const int HFGI_FOLD_SIZE = 1; // vec4 texels of A_j per azimuth (shared::fold_texels)
// The later bounces' azimuths within the first bounce's set (rules::scene::replay_stride): the
// first bounce records the casting sets of every HFGI_REPLAY_STRIDE-th of its azimuths; a later
// bounce's sample j (of the samples from HFGI_REPLAY_BASE on, its own set) casts set j − base.
layout(constant_id = 14) const uint HFGI_REPLAY_STRIDE = 1u;
layout(constant_id = 15) const uint HFGI_REPLAY_BASE = 0u;
// The cast merge (gi.cast_merge = δ; docs/indirect.md §2, "Merged casts"): tan δ, 0 = off. A
// member less than δ above the last member kept is not cast; the next member kept is cast over
// its interval too (or, at the ray's end, the last member held).
layout(constant_id = 16) const float HFGI_MERGE = 0.0;
const int HFGI_N2 = HFGI_N * HFGI_N;
const int HFGI_QUEUE = 2; // members a lane may hold before the subgroup casts (docs/performance.md §18)

layout(binding = 0) uniform usamplerBuffer hfgi_levels_texels; // the height levels (f32 bits), a texel buffer
layout(std430, binding = 1) readonly buffer Table { hfgi_Level hfgi_table[]; };
layout(binding = 2) uniform usamplerBuffer hfgi_stack_texels; // the height stack (f32 bits), a texel buffer
layout(binding = 3) uniform usamplerBuffer hfgi_radiance_levels_texels; // radiance levels (f32 bits)
layout(std430, binding = 4) readonly buffer RTable { hfgi_Level hfgi_radiance_table[]; };
layout(binding = 5) uniform usamplerBuffer hfgi_radiance_stack_texels; // words of gi.storage (hfgi_store.glsl)
layout(binding = 6) uniform usamplerBuffer hfgi_samples_texels; // cos φ, sin φ, 0, 0 (f32 bits)
layout(binding = 7) uniform usamplerBuffer hfgi_fold_texels; // A_j per azimuth (hfgi_fold.glsl, shared::gpu_fold)
layout(binding = 8) uniform usamplerBuffer hfgi_radiance_level_texels; // per scan sample, from `first`
layout(std430, binding = 9) buffer U { uint hfgi_u[]; };                      // receivers × n² × rgb, over azimuth chunks (hfgi_store.glsl)
layout(std430, binding = 10) readonly buffer Consts {                         // the shading constants
    float hfgi_klm[HFGI_MAX_SH_ORDER * HFGI_MAX_SH_ORDER];
    float hfgi_zh_diffuse[HFGI_MAX_SH_ORDER];
    float hfgi_zh_glossy[HFGI_MAX_SH_ORDER]; // √(4π/(2l+1)) · Phong ZH
    uint hfgi_triple_count;
};
layout(binding = 11) uniform usamplerBuffer hfgi_max_texels; // pyramid.max (f32 bits; with the bound)
// The radiance stack's planes (stack mode): width, height, offset per level of channel 0, then
// the channel stride (PyramidLayout::stack_planes: coarse planes are smaller than the working grid).
layout(binding = 12) uniform usamplerBuffer hfgi_rplanes_texels;
// The height stack's planes (hfgi_pyramid.glsl; stack mode).
layout(binding = 13) uniform usamplerBuffer hfgi_hplanes_texels;
// The later bounces' casting sets (HFGI_REPLAY ≠ 0): per azimuth i of the later bounces' set and
// receiver r the two words (i·receivers + r)·2 and + 1, bit k (of the 64) set when ladder sample
// first + k is a member of the walk without probes (rules::scene::REPLAY_STEPS: ladders of at
// most 64 samples).
layout(std430, binding = 14) buffer Members { uvec2 hfgi_members[]; };
layout(push_constant) uniform Push { hfgi_IndirectPush pc; };
// What the scan reads per sample or per member it reads through texel views (HFGI_TEXELS,
// hfgi_filter.glsl; docs/performance.md §17); only what it reads per receiver or writes is a
// storage buffer.
#define HFGI_TEXELS
#define HFGI_LEVEL_READ(l, i) ((l).source == 0u ? HFGI_TEXEL_F(hfgi_levels_texels, i) : HFGI_TEXEL_F(hfgi_radiance_levels_texels, i))
#define hfgi_radiance_levels(i) HFGI_TEXEL_F(hfgi_radiance_levels_texels, i)
#define hfgi_rplanes(i) texelFetch(hfgi_rplanes_texels, int(i))
#define hfgi_max(i) HFGI_TEXEL_F(hfgi_max_texels, i)
#include "hfgi_store.glsl"
#define rstack_at(i) HFGI_LOAD_TEXEL(hfgi_radiance_stack_texels, i)
// With f16 the radiance stack holds radiance × pc.radiance_scale (the pre-exposure,
// frame::storage::pre_exposure): its reads divide by it, and U is stored times it.
float hfgi_unexpose;
// hfgi_pyramid.glsl's stack reads are the height stack's (hfgi_stack, its planes hfgi_hplanes):
// the radiance stack has its own planes (binding 12), and radiance_rgb reads them itself.
#include "hfgi_pyramid.glsl"
// U keeps bands < √HFGI_NU (rules::scene::u_bands), whose fold rows read Fourier orders up
// to √HFGI_NU: the casts compute and accumulate no higher ones.
const int hfgi_u_bands = HFGI_NU >= 64 ? 8 : HFGI_NU >= 49 ? 7 : HFGI_NU >= 36 ? 6 : HFGI_NU >= 25 ? 5
                       : HFGI_NU >= 16 ? 4 : HFGI_NU >= 9 ? 3 : HFGI_NU >= 4 ? 2 : 1;
#define HFGI_KMAX (hfgi_u_bands < HFGI_N ? hfgi_u_bands : HFGI_N)
#include "hfgi_elevation.glsl"
#include "hfgi_sh.glsl"
#include "hfgi_max.glsl"
#include "hfgi_receiver.glsl"
#include "hfgi_fold.glsl"

float hfgi_base[HFGI_NV];
vec3 hfgi_U[HFGI_NU];
// Radiance level 0, read once per receiver (radiance_begin): its size, the scale from level-0
// height positions to its texels, and its channels' offsets and biases. Positions q are the
// field's texels; level 0 is the field or, sub-sampled, the working grid
// (rules::scene::radiance_base): hfgi_r_base is level 0's entry with the field's size, the base
// every radiance level is addressed from.
ivec2 hfgi_r0_size;
vec2 hfgi_field_size;
hfgi_Level hfgi_r_base;
vec2 hfgi_r0_raw_scale;
uvec3 hfgi_r0_offset;
vec3 hfgi_r0_bias;
// The radiance stack's channel stride (its planes table's last entry), read once per receiver.
uint hfgi_rstride;

void radiance_begin() {
    hfgi_Level r0 = hfgi_radiance_table[0];
    hfgi_Level h0 = hfgi_table[0];
    hfgi_r_base = r0;
    hfgi_r_base.width = h0.width;
    hfgi_r_base.height = h0.height;
    vec2 n0 = vec2(float(h0.width), float(h0.height));
    hfgi_field_size = n0;
    hfgi_r0_size = ivec2(int(r0.width), int(r0.height));
    hfgi_r0_raw_scale = vec2(hfgi_r0_size) / n0;
    for (uint c = 0u; c < 3u; ++c) {
        hfgi_Level l = hfgi_radiance_table[c * pc.radiance_levels];
        hfgi_r0_offset[c] = l.offset;
        hfgi_r0_bias[c] = l.bias;
    }
    hfgi_rstride = HFGI_RSTACK != 0u ? hfgi_rplanes(pc.radiance_planes).z : 0u;
}

// The RGB radiance of level lv at level-0 position q: the three channels' planes share their
// texel addresses, so they are computed once and each channel reads its four corners at its own
// plane (the same values and arithmetic as hfgi_pyramid_at per channel). Pyramid mode (no stack,
// not raw) reads each channel with hfgi_pyramid_at.
vec3 radiance_rgb(uint lv, vec2 q, bool stack_mode, bool wrap, bool raw) {
    uint n_u = pc.radiance_levels;
    vec3 rad;
    if (!raw && !stack_mode) {
        for (uint c = 0u; c < 3u; ++c) {
            uint e = c * n_u + lv;
            rad[c] = hfgi_pyramid_at(hfgi_r_base, hfgi_radiance_table[e], e, q, false, wrap, false);
        }
        return rad;
    }
    uvec4 plane = raw ? uvec4(0u) : hfgi_rplanes(lv);
    ivec2 size = raw ? hfgi_r0_size : ivec2(plane.xy);
    vec2 pw = (q + 0.5) * (raw ? hfgi_r0_raw_scale : vec2(plane.xy) / hfgi_field_size) - 0.5;
    vec2 fl = floor(pw);
    vec2 f = pw - fl;
    ivec2 i = ivec2(fl);
    int x0 = hfgi_address(i.x, size.x, wrap), x1 = hfgi_address(i.x + 1, size.x, wrap);
    int y0 = hfgi_address(i.y, size.y, wrap), y1 = hfgi_address(i.y + 1, size.y, wrap);
    uvec4 at = uvec4(y0 * size.x + x0, y0 * size.x + x1, y1 * size.x + x0, y1 * size.x + x1);
    for (uint c = 0u; c < 3u; ++c) {
        if (raw) {
            uvec4 k = at + hfgi_r0_offset[c];
            float b = hfgi_r0_bias[c];
            rad[c] = hfgi_bilerp(hfgi_radiance_levels(k.x) - b, hfgi_radiance_levels(k.y) - b,
                                 hfgi_radiance_levels(k.z) - b, hfgi_radiance_levels(k.w) - b, f);
        } else {
            uvec4 k = at + c * hfgi_rstride + plane.z; // lv < radiance_planes
            rad[c] = hfgi_bilerp(rstack_at(k.x), rstack_at(k.y),
                                 rstack_at(k.z), rstack_at(k.w), f);
            if (HFGI_HALF != 0u) rad[c] *= hfgi_unexpose;
        }
    }
    return rad;
}

// Exit radiance of casting point q toward the receiver (docs/indirect.md §2): the diffuse RGB
// pyramid, plus in vector mode k_s · ⟨T(q), Phong ZH rotated to R⟩ with R the reflection of the
// direction back to the receiver about q's normal.
// With HFGI_FLAG_RAW_LEVEL0 (raw0) radiance level 0 is read as the unfiltered bilinear image:
// from level 0 itself, or with HFGI_FLAG_RAW_RPLANE0 from the stack's plane 0, which then holds
// it (hfgi_radiance_raw0 is false: one read path).
const bool hfgi_radiance_raw0 =
    (HFGI_STATIC_FLAGS & (HFGI_FLAG_RAW_LEVEL0 | HFGI_FLAG_RAW_RPLANE0)) == HFGI_FLAG_RAW_LEVEL0;
vec3 member_radiance(uint lv, vec2 q, float omega, vec2 d, bool stack_mode, bool wrap, bool raw0) {
    bool raw = raw0 && lv == 0u;
    uint n_u = pc.radiance_levels;
    vec3 rad = radiance_rgb(lv, q, stack_mode, wrap, raw);
    if (HFGI_VECTOR != 0) {
        vec3 nc = hfgi_normal_at(q, wrap, pc.texel_size);
        vec3 s = -vec3(cos(omega) * d, sin(omega));
        hfgi_sh_eval(normalize(2.0 * dot(nc, s) * nc - s));
        vec3 gl = vec3(0.0);
        for (int l = 0; l < HFGI_N; ++l) {
            for (int m = -l; m <= l; ++m) {
                int k = l * (l + 1) + m;
                vec3 t;
                for (uint c = 0u; c < 3u; ++c) {
                    uint e = (3u + 3u * uint(k) + c) * n_u + lv;
                    t[c] = hfgi_pyramid_at(hfgi_r_base, hfgi_radiance_table[e], e, q, false, wrap, raw);
                }
                gl += t * (hfgi_zh_glossy[l] * hfgi_y[k]);
            }
        }
        rad += pc.specular.rgb * gl;
    }
    return rad;
}

// Casting-set member (eq. 6) at q with slope tan ω, seen over [running, ω): eq. 12 telescoped.
// `i`: the ladder sample (or the one a probe precedes), whose radiance level it reads.
void cast_member(inout vec3 u[HFGI_NE], inout float running, inout float running_slope, float slope, int i, vec2 q,
                 vec2 d, hfgi_Scan scan, bool wrap) {
    float omega = atan(slope);
    uint rl = texelFetch(hfgi_radiance_level_texels, i - scan.first).x;
    float seg[HFGI_NE];
    hfgi_elevation(running, omega, seg);
    vec3 rad = member_radiance(rl, q, omega, d, HFGI_RSTACK != 0u, wrap, hfgi_radiance_raw0);
    HFGI_ADD_MOMENTS(u, rad, seg)
    running = omega;
    running_slope = slope;
}

#include "hfgi_queue.glsl"

// Casts the oldest queued member, if any (cast_member: over [running, its ω)).
void queue_cast(inout hfgi_Queue m, inout vec3 u[HFGI_NE], inout float running, inout float running_slope,
                hfgi_Scan scan, vec2 d, bool wrap) {
    if (m.count == 0) return;
    cast_member(u, running, running_slope, m.slope[0], m.i[0], scan.p + m.t[0] * d, d, scan, wrap);
    [[unroll]] for (int k = 0; k + 1 < HFGI_QUEUE; ++k) {
        m.slope[k] = m.slope[k + 1];
        m.t[k] = m.t[k + 1];
        m.i[k] = m.i[k + 1];
    }
    --m.count;
}

// The casting set along direction d from the running horizon `running` (eq. 6, 12), without
// radial probes (the later bounces' pipeline; presets without probes). The inner loop only
// walks and queues members; the outer loop casts them (elevation moments, radiance,
// accumulation): lavapipe executes every branch of a loop body on all its SIMD lanes
// (docs/performance.md §5). It compares Δh with the horizon's slope · t · texel (no division
// per sample), and leaves when this lane has ended or holds a full queue, or when any lane of
// the subgroup holds a full queue (§18).
void scan_ray_plain(hfgi_Scan scan, vec2 d, bool wrap, bool bounded, float gmax, float bmin, float running,
                    inout vec3 u[HFGI_NE]) {
    float running_slope = tan(running); // of the members cast
    float walk_slope = running_slope;   // of the members found, cast or queued
    int i = scan.first;
    float t = hfgi_scan_t(scan, i, HFGI_NV), ratio = hfgi_scan_ratio(scan); // t of sample i, then i + 1 …
    bool more = true;
    hfgi_Queue m = queue_empty(running_slope);
    while (more || m.count > 0 || queue_holds(m, walk_slope)) {
        while (more && m.count < HFGI_QUEUE) {
            vec2 q = scan.p + t * d;
            if (i >= scan.end || !hfgi_scan_inside(scan, q) ||
                hfgi_nothing_beyond(bounded, gmax, bmin, walk_slope, t, scan.texel_size)) {
                more = false;
                break;
            }
            uint lv = hfgi_scan_level(i, scan.level_bias, HFGI_NV);
            float before = walk_slope;
            queue_sample(m, walk_slope, hfgi_height_at(scan, lv, q) - hfgi_base[lv], t, i, scan.texel_size);
            // Every member is one (queued, or held by the cast merge): the horizon rose.
            if (HFGI_REPLAY == 1u && walk_slope != before) plain_record(i, scan.first);
            ++i;
            t *= ratio;
            if (subgroupAny(m.count == HFGI_QUEUE)) break;
        }
        if (!more) queue_end(m, walk_slope);
        queue_cast(m, u, running, running_slope, scan, d, wrap);
    }
}

// The same with radial probes (docs/indirect.md §2): before each ladder sample more than a
// texel past the previous one, level-0 samples in the gap, at most one per texel of it (thin
// spikes the ladder steps over; docs/accuracy.md §4). One walk over probes and samples, not two
// nested loops: lavapipe pays for an inner loop even when it runs no iteration.
// With HFGI_REPLAY = 1 it also finds the members of the walk without probes (the later bounces'
// casting set): the samples above that walk's own horizon plain_slope, found by `rises` as
// scan_ray_plain finds them; and it walks on until that horizon, never above its
// own, ends the ray too (the same early stop, so at the same sample).
void scan_ray(hfgi_Scan scan, vec2 d, bool wrap, bool bounded, float gmax, float bmin, float running,
              inout vec3 u[HFGI_NE]) {
    float running_slope = tan(running), walk_slope = running_slope;
    float plain_slope = running_slope;
    float t_prev = 0.0, t = 0.0;
    uint lv = 0u;
    int i = scan.first, s2 = 0, np = -1; // np < 0: sample i not set up yet
    bool more = true;
    float t_next = hfgi_scan_t(scan, i, HFGI_NV), ratio = hfgi_scan_ratio(scan); // t of sample i, then i + 1 …
    hfgi_Queue m = queue_empty(running_slope);
    while (more || m.count > 0 || queue_holds(m, walk_slope)) {
        while (more && m.count < HFGI_QUEUE) {
            if (i >= scan.end) {
                more = false;
                break;
            }
            if (np < 0) {
                t = t_next;
                t_next *= ratio;
                if (!hfgi_scan_inside(scan, scan.p + t * d)) {
                    more = false;
                    break;
                }
                lv = hfgi_scan_level(i, scan.level_bias, HFGI_NV);
                np = clamp(int(ceil(t - t_prev)) - 1, 0, int(pc.probes));
                s2 = 1;
            }
            bool probe = s2 <= np;
            float tp = probe ? t_prev + (t - t_prev) * float(s2) / float(np + 1) : t;
            float stop_slope = HFGI_REPLAY == 1u ? plain_slope : walk_slope;
            if (hfgi_nothing_beyond(bounded, gmax, bmin, stop_slope, tp, scan.texel_size)) {
                more = false;
                break;
            }
            uint lq = probe ? 0u : lv;
            float dh = hfgi_height_at(scan, lq, scan.p + tp * d) - hfgi_base[lq];
            if (HFGI_REPLAY == 1u && !probe && rises(plain_slope, dh, tp, scan.texel_size)) plain_record(i, scan.first);
            queue_sample(m, walk_slope, dh, tp, i, scan.texel_size); // a probe reads sample i's radiance level
            if (probe) {
                ++s2;
            } else {
                t_prev = t;
                ++i;
                np = -1;
            }
            if (subgroupAny(m.count == HFGI_QUEUE)) break;
        }
        if (!more) queue_end(m, walk_slope);
        queue_cast(m, u, running, running_slope, scan, d, wrap);
    }
}

// The casting set of the walk without probes along d (HFGI_REPLAY = 2; docs/indirect.md §2),
// from the bits the first bounce's walk stored: each member's step t as the walk computes it
// (t_first times the ratio once per sample), its height read once, and its cast — the same
// members, slopes and casts as scan_ray_plain, without the walk. Lanes cast one member each per
// iteration.
void replay_ray(hfgi_Scan scan, vec2 d, bool wrap, float running, inout vec3 u[HFGI_NE], uvec2 bits) {
    float running_slope = tan(running);
    float ratio = hfgi_scan_ratio(scan);
    int k = 0;
    float t = hfgi_scan_t(scan, scan.first, HFGI_NV);
    while (bits != uvec2(0u)) {
        int next = bits.x != 0u ? findLSB(bits.x) : 32 + findLSB(bits.y);
        if (bits.x != 0u) bits.x &= bits.x - 1u; else bits.y &= bits.y - 1u;
        while (k < next) {
            t *= ratio;
            ++k;
        }
        int i = scan.first + k;
        uint lv = hfgi_scan_level(i, scan.level_bias, HFGI_NV);
        vec2 q = scan.p + t * d;
        cast_member(u, running, running_slope, (hfgi_height_at(scan, lv, q) - hfgi_base[lv]) / (t * scan.texel_size),
                    i, q, d, scan, wrap);
    }
}

void main() {
    uvec2 r = hfgi_receiver();
    if (r.x >= pc.work_width || r.y >= pc.work_height) return;
    bool wrap = HFGI_WRAP != 0u;
    hfgi_Scan scan = hfgi_scan_begin(r, uvec2(pc.work_width, pc.work_height), pc.level_step, pc.level_bias,
                                     pc.texel_size, HFGI_STACK != 0u, wrap, HFGI_STATIC_FLAGS, pc.scan_extent, HFGI_NV);
    vec3 N = hfgi_normal_at(scan.p, wrap, pc.texel_size);
    bool tangent = (HFGI_STATIC_FLAGS & HFGI_FLAG_TANGENT) != 0u;
    float bmin = 3.402823466e38;
    // Not unrolled: n_v inlined height reads made most of the compile time (docs/performance.md §3).
    // Only the levels the scan reads (the stack holds no others; hfgi_scan_levels): bmin is the
    // lowest base a sample is compared with, which is all the max-pyramid bound needs.
    int levels = hfgi_scan_levels(scan, HFGI_NV);
    [[dont_unroll]] for (int l = 0; l < levels; ++l) {
        hfgi_base[l] = hfgi_scan_base(scan, uint(l));
        bmin = min(bmin, hfgi_base[l]);
    }
    bool bounded = (pc.flags & HFGI_FLAG_MAX_BOUND) != 0u;
    float gmax = bounded ? max(hfgi_max_top(uvec2(scan.n0)), bmin) : 0.0; // bmin ≤ gmax but for rounding
    radiance_begin();
    hfgi_unexpose = 1.0 / pc.radiance_scale;
    for (int k = 0; k < HFGI_NU; ++k) hfgi_U[k] = vec3(0.0);
    // The receiver's own radiance, which the near-field limit casts (radiance level 0 at p): with
    // the scalar pyramid the same at every azimuth, so read once (the glossy term depends on d).
    vec3 rad_p = HFGI_VECTOR == 0 && scan.first < 0
        ? member_radiance(0u, scan.p, 0.0, vec2(1.0, 0.0), HFGI_RSTACK != 0u, wrap, hfgi_radiance_raw0) : vec3(0.0);
    for (uint j = pc.sample_offset; j < pc.sample_offset + pc.sample_count; ++j) {
        vec2 d = uintBitsToFloat(texelFetch(hfgi_samples_texels, int(j)).xy);
        // ω_min: the tangent plane of the receiver along φ (§3): the paper's −asin(N·d), or the
        // exact tangent elevation atan2(−N·d, N_z) (CONVENTIONS.md; docs/accuracy.md §4).
        float running = tangent ? hfgi_tangent_elevation(N, d) : -asin(clamp(dot(N.xy, d), -1.0, 1.0));
        vec3 u[HFGI_NE];
        for (int l = 0; l < HFGI_NE; ++l) u[l] = vec3(0.0);
        // The near-field limit t → 0 (with near steps): the receiver's own surface, seen with the
        // receiver's radiance (radiance level 0 at p), over [ω_min, ω_0). Skipped when narrower than
        // 1e-5 rad: at the tangent plane its cosine-weighted share is O(width²), and
        // on a plane the two angles differ only by rounding (f32 here, f64 in the twin).
        float limit;
        if (scan.first < 0 && hfgi_scan_limit(scan, d, limit) && limit > running + 1e-5) {
            float seg[HFGI_NE];
            hfgi_elevation(running, limit, seg);
            vec3 rad = HFGI_VECTOR == 0 ? rad_p : member_radiance(0u, scan.p, limit, d, HFGI_RSTACK != 0u, wrap, hfgi_radiance_raw0);
            HFGI_ADD_MOMENTS(u, rad, seg)
            running = limit;
        }
        uint receiver = r.y * pc.work_width + r.x, receivers = pc.work_width * pc.work_height;
        uint slot = (HFGI_REPLAY == 2u ? j - HFGI_REPLAY_BASE : j / HFGI_REPLAY_STRIDE) * receivers + receiver;
        if (HFGI_REPLAY == 2u) {
            replay_ray(scan, d, wrap, running, u, hfgi_members[slot]);
        } else {
            hfgi_plain = uvec2(0u);
            if (HFGI_PROBES == 0u) {
                scan_ray_plain(scan, d, wrap, bounded, gmax, bmin, running, u);
            } else {
                scan_ray(scan, d, wrap, bounded, gmax, bmin, running, u);
            }
            if (HFGI_REPLAY == 1u && j % HFGI_REPLAY_STRIDE == 0u) hfgi_members[slot] = hfgi_plain;
        }
        // eq. 19–21 folded: U += A_j u_j (the stored coefficients; hfgi_fold.glsl: in the legendre
        // basis only A_j's non-zero entries, shared::gpu_fold).
        HFGI_FOLD(vec3, hfgi_fold_texels, j * uint(HFGI_FOLD_SIZE), u, hfgi_U, HFGI_NU)
    }
    // Value 3k + c of the receiver's vector is channel c of coefficient k; the receiver stride is
    // 3·HFGI_NU, rounded up to even with f16 (Storage::stride).
    const int count = 3 * HFGI_NU;
    uint out_base = (r.y * pc.work_width + r.x) * hfgi_stride(count);
    bool acc = (pc.flags & HFGI_FLAG_ACCUMULATE) != 0u;
#define HFGI_U_AT(i) (HFGI_HALF != 0u ? hfgi_U[(i) / 3][(i) % 3] * pc.radiance_scale : hfgi_U[(i) / 3][(i) % 3])
    HFGI_STORE(hfgi_u, out_base, count, HFGI_U_AT, acc)
}
