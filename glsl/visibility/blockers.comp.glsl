#version 460
// Sphere blockers' visibility (stage `visibility.blockers`; docs/blockers.md, after seed 001
// §3–4 and Ren et al. 2006): per receiver of the working grid, the sum in log-SH space of each
// sphere's log-ZH — the cap of half-angle asin(r/d) toward the sphere times log ε, rotated
// toward it (eq. 24–26), times r/d with ratio attenuation (or, HFGI_MATCHED, the moment-matched
// log-ZH of the cap, math::logcap), culled when the whole sphere is
// below the receiver's tangent plane — then one SH exponentiation: by quadrature
// (HFGI_EXP = 0: exp(f) at a product rule of the sphere, projected back) or Ren et al.'s optimal
// linear approximation with DC isolation (HFGI_EXP = 1). With HFGI_LOG = 1 the environment's
// height-field visibility joins the sum as f_hf = log ε·(1 − V_env) (the wedge construction of
// eq. 15–23 in log space, by linearity) and a second vector is written: exp*(f_hf + Σ f_i).
// Output per receiver: V_s = exp*(Σ f_i) (n² floats), then with HFGI_LOG the environment's,
// then with HFGI_LOG = 2 its transfer exp*(f_hf + Σ f_i + f_ρ(N)) (log-SH diffuse BRDF, §5)
// and its glossy transfer exp*(f_hf + Σ f_i + f_φ(R)) (log-SH Phong lobe, eq. 27).
// Twin: reference::blockers.
#include "hfgi_shared.glsl"
layout(local_size_x = HFGI_WORKGROUP, local_size_y = HFGI_WORKGROUP) in;
layout(constant_id = 0) const int HFGI_N = 4;
layout(constant_id = 1) const uint HFGI_EXP = 0u; // 0: quadrature, 1: optimal linear
layout(constant_id = 2) const uint HFGI_LOG = 0u; // 1: also exp*(f_hf + Σ f_i) for the environment; 2: and exp*(f_hf + Σ f_i + f_ρ(N))
layout(constant_id = 3) const uint HFGI_PRIMAL = 0u; // 1: V_s = ⊛_i (1 − cap_i), no log space
layout(constant_id = 4) const uint HFGI_MATCHED = 0u; // 1: the moment-matched log-ZH (math::logcap), no ε
layout(constant_id = 5) const uint HFGI_HALF = 0u; // gi.storage of binding 4: 1 = f16 (hfgi_store.glsl)
const int HFGI_N2 = HFGI_N * HFGI_N;

layout(std430, binding = 0) readonly buffer Levels { float hfgi_levels[]; };   // level 0 = absolute heights
layout(std430, binding = 1) readonly buffer Spheres { vec4 hfgi_spheres[]; }; // per slot: (c_hi, r), (c_lo, 0)
layout(std430, binding = 2) readonly buffer Quad { float hfgi_quad[]; };      // per node: w, y_0 .. y_{n²−1}
layout(std430, binding = 3) readonly buffer Consts {
    float hfgi_klm[HFGI_MAX_SH_ORDER * HFGI_MAX_SH_ORDER];
    float hfgi_ol_a[HFGI_OL_POINTS]; // a(i·step) of the OL method at this order
    float hfgi_ol_b[HFGI_OL_POINTS];
    float hfgi_log_brdf[HFGI_MAX_SH_ORDER]; // √(4π/(2l+1)) · ZH of ln max(cos θ/π, ε_ρ)
    float hfgi_matched[]; // HFGI_MATCHED: (K + 1) × n values √(4π/(2l+1)) · z_l(u_i)/u_i, u_i = i/K
};
layout(std430, binding = 4) readonly buffer Vis { uint hfgi_vis[]; };         // the visibility sets (HFGI_LOG; hfgi_store.glsl)
layout(std430, binding = 5) writeonly buffer Out { float hfgi_bv[]; };        // receivers × n² (× 2 with HFGI_LOG = 1, × 4 with 2)
layout(std430, binding = 6) readonly buffer Triple { uvec2 hfgi_triple[]; };  // (i | j<<8 | k<<16, γ bits)
layout(push_constant) uniform Push { hfgi_BlockerPush pc; };
#include "hfgi_sh.glsl"
#define HFGI_FIELD_H(i) hfgi_levels[i]
#define HFGI_FIELD_W pc.width
#define HFGI_FIELD_HGT pc.height
#define HFGI_FIELD_S pc.texel_size
#include "hfgi_field.glsl"
#include "hfgi_store.glsl"

const float HFGI_SQRT_4PI = 3.5449077018110318;
const float HFGI_TWO_PI = 6.283185307179586;

// CONVENTIONS.md normal of the texel nearest to level-0 position q (the culling plane).
vec3 normal_near(vec2 q) {
    return hfgi_field_normal(clamp(ivec2(floor(q + 0.5)), ivec2(0), ivec2(pc.width - 1u, pc.height - 1u)));
}

float hfgi_f[HFGI_N2];
float hfgi_v[HFGI_N2];

// f += scale · 2π · I_l(Θ) · y_lm(l): a cap ZH of sin Θ = s, cos Θ = x rotated to unit l
// (c_lm = √(4π/(2l+1))·z_l·y_lm, z_l = √(π(2l+1))·I_l). I_0 = 1 − x = s²/(1 + x);
// I_l = (P_{l−1}(x) − P_{l+1}(x))/(2l+1) = s²·P'_l(x)/(l(l+1)) for l ≥ 1 (no cancellation).
void add_cap(vec3 l, float s, float x, float scale) {
    hfgi_sh_eval(l);
    float p_prev = 1.0, p = x;        // P_{l−1}, P_l
    float dp_prev = 0.0, dp = 1.0;    // P'_{l−1}, P'_l
    for (int band = 0; band < HFGI_N; ++band) {
        float il;
        if (band == 0) {
            il = s * s / (1.0 + x);
        } else {
            il = s * s * dp / float(band * (band + 1));
            float pn = (float(2 * band + 1) * x * p - float(band) * p_prev) / float(band + 1);
            float dpn = dp_prev + float(2 * band + 1) * p;
            p_prev = p; p = pn;
            dp_prev = dp; dp = dpn;
        }
        for (int m = -band; m <= band; ++m) {
            int k = band * (band + 1) + m;
            hfgi_f[k] += scale * HFGI_TWO_PI * il * hfgi_y[k];
        }
    }
}

// f += the moment-matched log-ZH of the cap with u = 1 − cos Θ, rotated to unit l: u times
// the Catmull–Rom interpolation of the table (ends extended linearly). Twin:
// math::logcap::MatchedCaps::zh and matched_log_vis.
float matched_row(int j, int band) {
    const int K = HFGI_MATCHED_INTERVALS;
    if (j < 0) return 2.0 * hfgi_matched[band] - hfgi_matched[HFGI_N + band];
    if (j > K) return 2.0 * hfgi_matched[K * HFGI_N + band] - hfgi_matched[(K - 1) * HFGI_N + band];
    return hfgi_matched[j * HFGI_N + band];
}

void add_matched(vec3 l, float u) {
    hfgi_sh_eval(l);
    float s = min(clamp(u, 0.0, 1.0) * float(HFGI_MATCHED_INTERVALS), float(HFGI_MATCHED_INTERVALS));
    int i = min(int(floor(s)), HFGI_MATCHED_INTERVALS - 1);
    float f = s - float(i);
    for (int band = 0; band < HFGI_N; ++band) {
        float p0 = matched_row(i - 1, band), p1 = matched_row(i, band);
        float p2 = matched_row(i + 1, band), p3 = matched_row(i + 2, band);
        float c = u * (p1 + 0.5 * f * ((p2 - p0) + f * ((2.0 * p0 - 5.0 * p1 + 4.0 * p2 - p3) + f * (3.0 * (p1 - p2) + p3 - p0))));
        for (int m = -band; m <= band; ++m) hfgi_f[band * (band + 1) + m] += c * hfgi_y[band * (band + 1) + m];
    }
}

// ln t interpolated at s = x/step: the Lagrange cubic through entries 0..3 on the first
// interval, Catmull–Rom elsewhere (the point past the end extrapolated quadratically), ln t
// extrapolated linearly past the end. Twin: math::shexp::ol_coefficients.
float hfgi_ol(bool a, int i) {
    return log(a ? hfgi_ol_a[i] : hfgi_ol_b[i]);
}

float interp_log(bool a, float x) {
    float s = max(x, 0.0) / pc.ol_step;
    int last = HFGI_OL_POINTS - 1;
    if (s >= float(last)) {
        float slope = hfgi_ol(a, last) - hfgi_ol(a, last - 1);
        return exp(hfgi_ol(a, last) + slope * (s - float(last)));
    }
    int i = int(floor(s));
    float u = s - float(i);
    if (i == 0) {
        float p0 = hfgi_ol(a, 0), p1 = hfgi_ol(a, 1), p2 = hfgi_ol(a, 2), p3 = hfgi_ol(a, 3);
        return exp(-p0 * (u - 1.0) * (u - 2.0) * (u - 3.0) / 6.0 + p1 * u * (u - 2.0) * (u - 3.0) / 2.0
                   - p2 * u * (u - 1.0) * (u - 3.0) / 2.0 + p3 * u * (u - 1.0) * (u - 2.0) / 6.0);
    }
    float p0 = hfgi_ol(a, i - 1), p1 = hfgi_ol(a, i), p2 = hfgi_ol(a, i + 1);
    float p3 = i + 2 > last ? 3.0 * hfgi_ol(a, last) - 3.0 * hfgi_ol(a, last - 1) + hfgi_ol(a, last - 2) : hfgi_ol(a, i + 2);
    return exp(p1 + 0.5 * u * ((p2 - p0) + u * ((2.0 * p0 - 5.0 * p1 + 4.0 * p2 - p3) + u * (3.0 * (p1 - p2) + p3 - p0))));
}

// hfgi_v = exp*(hfgi_f).
void exponentiate() {
    if (HFGI_EXP == 0u) {
        for (int k = 0; k < HFGI_N2; ++k) hfgi_v[k] = 0.0;
        uint stride = uint(HFGI_N2) + 1u;
        for (uint q = 0u; q < pc.quad_count; ++q) {
            uint o = q * stride;
            float f = 0.0;
            for (int k = 0; k < HFGI_N2; ++k) f += hfgi_f[k] * hfgi_quad[o + 1u + uint(k)];
            float e = hfgi_quad[o] * exp(f);
            for (int k = 0; k < HFGI_N2; ++k) hfgi_v[k] += e * hfgi_quad[o + 1u + uint(k)];
        }
    } else {
        // DC isolation: exp(f) = e^{f_0/√4π}·exp(f̂); exp*(f̂) ≈ a(‖f̂‖)·1 + b(‖f̂‖)·f̂.
        float e0 = exp(hfgi_f[0] / HFGI_SQRT_4PI);
        float x = 0.0;
        for (int k = 1; k < HFGI_N2; ++k) x += hfgi_f[k] * hfgi_f[k];
        x = sqrt(x);
        float a = HFGI_N > 1 ? interp_log(true, x) : 1.0, b = HFGI_N > 1 ? interp_log(false, x) : 1.0;
        hfgi_v[0] = e0 * a * HFGI_SQRT_4PI;
        for (int k = 1; k < HFGI_N2; ++k) hfgi_v[k] = e0 * b * hfgi_f[k];
    }
}

// Primal space: hfgi_v = ⊛_i (1 − cap_i) over the spheres not culled (0 inside one), each
// product truncated to order n (SH triple products). Twin: reference::blockers::primal.
void primal(vec3 P, vec3 N) {
    for (int k = 0; k < HFGI_N2; ++k) hfgi_v[k] = 0.0;
    hfgi_v[0] = HFGI_SQRT_4PI;
    for (uint i = 0u; i < pc.sphere_count; ++i) {
        vec4 c_hi = hfgi_spheres[2u * i], c_lo = hfgi_spheres[2u * i + 1u];
        float rad = c_hi.w;
        if (rad <= 0.0) continue;
        precise vec3 C = (c_hi.xyz - P) + c_lo.xyz;
        float d = length(C);
        if (d <= rad) {
            for (int k = 0; k < HFGI_N2; ++k) hfgi_v[k] = 0.0;
            return;
        }
        if (dot(N, C) < -rad) continue;
        for (int k = 0; k < HFGI_N2; ++k) hfgi_f[k] = 0.0;
        float s = rad / d;
        add_cap(C / d, s, sqrt((d - rad) * (d + rad)) / d, -1.0);
        hfgi_f[0] += HFGI_SQRT_4PI;
        float w[HFGI_N2];
        for (int k = 0; k < HFGI_N2; ++k) w[k] = 0.0;
        for (uint e = 0u; e < pc.triple_count; ++e) {
            uvec2 t = hfgi_triple[e];
            uint a = t.x & 0xFFu, b = (t.x >> 8) & 0xFFu, k = (t.x >> 16) & 0xFFu;
            w[k] += uintBitsToFloat(t.y) * hfgi_v[a] * hfgi_f[b];
        }
        for (int k = 0; k < HFGI_N2; ++k) hfgi_v[k] = w[k];
    }
}

void main() {
    uvec2 r = gl_GlobalInvocationID.xy;
    if (r.x >= pc.work_width || r.y >= pc.work_height) return;
    // The receiver's level-0 position (docs/direct.md §1) and world position.
    vec2 q = (vec2(r) + 0.5) * vec2(pc.width, pc.height) / vec2(pc.work_width, pc.work_height) - 0.5;
    vec3 P = vec3(q * pc.texel_size, hfgi_field_bilinear(q));
    vec3 N = normal_near(q);
    uint receivers = pc.work_width * pc.work_height;
    uint idx = r.y * pc.work_width + r.x;
    if (HFGI_PRIMAL != 0u) {
        primal(P, N);
        for (int k = 0; k < HFGI_N2; ++k) hfgi_bv[idx * uint(HFGI_N2) + uint(k)] = hfgi_v[k];
        return;
    }
    for (int k = 0; k < HFGI_N2; ++k) hfgi_f[k] = 0.0;
    for (uint i = 0u; i < pc.sphere_count; ++i) {
        vec4 c_hi = hfgi_spheres[2u * i], c_lo = hfgi_spheres[2u * i + 1u];
        float rad = c_hi.w;
        if (rad <= 0.0) continue; // an empty slot
        precise vec3 C = (c_hi.xyz - P) + c_lo.xyz;
        float d = length(C);
        if (d <= rad) { // inside the sphere: fully blocked
            hfgi_f[0] += (HFGI_MATCHED != 0u ? -float(HFGI_MATCHED_BLOCKED) : pc.log_eps) * HFGI_SQRT_4PI;
            continue;
        }
        if (dot(N, C) < -rad) continue; // below the tangent plane: hides nothing
        float s = rad / d;
        float x = sqrt((d - rad) * (d + rad)) / d;
        if (HFGI_MATCHED != 0u) add_matched(C / d, s * s / (1.0 + x));
        else add_cap(C / d, s, x, pc.ratio != 0u ? pc.log_eps * s : pc.log_eps);
    }
    exponentiate();
    for (int k = 0; k < HFGI_N2; ++k) hfgi_bv[idx * uint(HFGI_N2) + uint(k)] = hfgi_v[k];
    if (HFGI_LOG != 0u) {
        // f_hf = log ε·(√4π·e_0 − V_env): log ε where the height field blocks, 0 where open.
        uint base = pc.env_offset + idx * hfgi_stride(HFGI_N2);
        for (int k = 0; k < HFGI_N2; ++k) hfgi_f[k] -= pc.log_eps * HFGI_LOAD(hfgi_vis, base + uint(k));
        hfgi_f[0] += pc.log_eps * HFGI_SQRT_4PI;
        exponentiate();
        uint o = (receivers + idx) * uint(HFGI_N2);
        for (int k = 0; k < HFGI_N2; ++k) hfgi_bv[o + uint(k)] = hfgi_v[k];
        if (HFGI_LOG == 2u) {
            // The transfer: the log-SH diffuse BRDF rotated to N joins the sum (seed 001 §5).
            hfgi_sh_eval(N);
            for (int l = 0; l < HFGI_N; ++l)
                for (int m = -l; m <= l; ++m) hfgi_f[l * (l + 1) + m] += hfgi_log_brdf[l] * hfgi_y[l * (l + 1) + m];
            exponentiate();
            o = (2u * receivers + idx) * uint(HFGI_N2);
            for (int k = 0; k < HFGI_N2; ++k) hfgi_bv[o + uint(k)] = hfgi_v[k];
            // The glossy transfer: the log-SH Phong lobe (eq. 27) about the reflected view
            // vector instead of the diffuse lobe: exp*(f_hf + Σ f_i + f_φ(R)).
            for (int l = 0; l < HFGI_N; ++l)
                for (int m = -l; m <= l; ++m) hfgi_f[l * (l + 1) + m] -= hfgi_log_brdf[l] * hfgi_y[l * (l + 1) + m];
            precise vec3 rel = (pc.camera.xyz - P) + pc.camera_lo.xyz; // as shade.direct's view vector
            vec3 wo = normalize(rel);
            hfgi_sh_eval(normalize(2.0 * dot(N, wo) * N - wo));
            for (int l = 0; l < HFGI_N; ++l)
                for (int m = -l; m <= l; ++m) hfgi_f[l * (l + 1) + m] += pc.log_phong[l] * hfgi_y[l * (l + 1) + m];
            exponentiate();
            o = (3u * receivers + idx) * uint(HFGI_N2);
            for (int k = 0; k < HFGI_N2; ++k) hfgi_bv[o + uint(k)] = hfgi_v[k];
        }
    }
}
