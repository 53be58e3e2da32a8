#version 460
#extension GL_EXT_control_flow_attributes : require
// Direct shading (NS09 §7; docs/direct.md §6) at full resolution: incident radiance
// T = Σ_sets L_set ⊛ V_set (SH triple product, truncated to order n), diffuse
// ρ/π · ⟨T, rotated clamped-cosine ZH about N⟩ and glossy k_s · ⟨T, rotated Phong ZH about R⟩.
// Visibility comes from the (possibly sub-sampled) receiver grid, interpolated bilinearly;
// normals are always full resolution (fig. 7).
// With HFGI_INDIRECT = 1 the same shader shades one indirect bounce (docs/indirect.md §4): the
// incident radiance is the IR vector U of eq. 21 (RGB, from binding 1) instead of L ⊛ V, and
// the bounce's exit radiance goes straight into level 0 of the radiance pyramid (binding 7),
// the next bounce's input.
//
// Output planes (RGB f32 triples, W×H each): 0 total, 1 direct, 2 indirect (Σ bounces), and
// for a glossy surface (HFGI_GLOSSY) 3 glossy, 4 glossy of the direct light, 5 glossy of the
// indirect light. Each dispatch rewrites its own planes and recomposes 0 and 3 from 1, 2, 4, 5,
// so direct and indirect may be updated on different frames (amortised shading, §7).
#include "hfgi_shared.glsl"
layout(local_size_x = HFGI_WORKGROUP, local_size_y = HFGI_WORKGROUP) in;
layout(constant_id = 0) const int HFGI_N = 4;
layout(constant_id = 1) const int HFGI_INDIRECT = 0;
layout(constant_id = 2) const int HFGI_STORE_T = 0; // 1: write T (glossy vector pyramid): binding 8, or 7 in indirect mode
// Sphere blockers (docs/blockers.md §4; frame::blockers::shading_mode): 0 none; 1 product: T is
// multiplied by their visibility V_s (binding 9); 2 log: as 1, but the environment set (set 0)
// takes the combined exp*(f_hf + Σ f_i) (binding 9's second vector) instead of L ⊛ V_env ⊛ V_s;
// 3 log_brdf: as 2, and the environment's diffuse irradiance is π⟨L_env, T_ρ⟩ with the transfer
// T_ρ = exp*(f_hf + Σ f_i + f_ρ(N)) (binding 9's third vector) instead of ⟨L_env ⊛ V', cc_N⟩,
// and its glossy light ⟨L_env, T_φ⟩ with T_φ = exp*(f_hf + Σ f_i + f_φ(R)) (the fourth vector).
layout(constant_id = 3) const uint HFGI_BLOCKERS = 0u;
layout(constant_id = 4) const uint HFGI_HALF = 0u; // gi.storage of binding 1: 1 = f16 (hfgi_store.glsl)
layout(constant_id = 5) const int HFGI_GLOSSY = 0; // 1: the buffer has the glossy planes 3-5 (shade::planes)
layout(constant_id = 6) const uint HFGI_NEXT_STRIDE = 0u; // indirect mode: floats per channel of binding 7
// Indirect mode: coefficients of U stored (rules::scene::u_bands²); the others are read as 0.
// Below n² only for a diffuse surface, whose clamped-cosine lobe zeroes them exactly.
layout(constant_id = 7) const int HFGI_NU = 16;
// The working grid is the field (no sub-sampling; frame::shade::spec): a texel is receiver r00
// with weight 1, so its V, U and blocker vectors are read, not interpolated from four receivers
// (the same value; docs/performance.md §34).
layout(constant_id = 8) const uint HFGI_SAME_GRID = 0u;
layout(constant_id = 9) const uint HFGI_PACKED = 0u; // 1: RGBE shading planes (gi.shading_storage; hfgi_plane.glsl)
const int HFGI_N2 = HFGI_N * HFGI_N;
const int HFGI_UNROLLED = HFGI_MAX_SH_ORDER * HFGI_MAX_SH_ORDER; // the product matrix's unrolled sum

// Bindings 0–3 are texel views (docs/performance.md §17: lavapipe gathers texel fetches on its
// SIMD lanes and reads storage buffers lane by lane; the blockers' triple loop reads two per
// entry, the product with the lighting's matrix one per term).
layout(binding = 0) uniform usamplerBuffer hfgi_levels_texels; // level 0 = heights (f32 bits)
layout(binding = 1) uniform usamplerBuffer hfgi_vis_texels;    // sets × receivers × n²; U: receivers × n² × rgb (hfgi_store.glsl)
layout(binding = 2) uniform usamplerBuffer hfgi_light_texels;  // sets × n² (rgb), then per set its cap (key light: dir, α)
layout(binding = 3) uniform usamplerBuffer hfgi_triple_texels; // (i | j<<8 | k<<16, γ bits)
#define hfgi_light(i) uintBitsToFloat(texelFetch(hfgi_light_texels, int(i)))
#define hfgi_triple(i) texelFetch(hfgi_triple_texels, int(i)).xy
layout(std430, binding = 4) readonly buffer Albedo { vec4 hfgi_albedo[]; };      // per texel (albedo_map)
layout(std430, binding = 5) readonly buffer Consts {
    float hfgi_klm[HFGI_MAX_SH_ORDER * HFGI_MAX_SH_ORDER];
    float hfgi_zh_diffuse[HFGI_MAX_SH_ORDER]; // √(4π/(2l+1)) · clamped-cosine ZH
    float hfgi_zh_glossy[HFGI_MAX_SH_ORDER];  // √(4π/(2l+1)) · Phong ZH
    uint hfgi_triple_count;
};
layout(std430, binding = 6) buffer Out { uint hfgi_out[]; };                  // 6 (3 without HFGI_GLOSSY) planes × W×H texels (hfgi_plane.glsl)
layout(std430, binding = 7) writeonly buffer Next { float hfgi_next[]; };    // indirect: the radiance levels (level 0 = the next bounce's input)
layout(std430, binding = 8) writeonly buffer Incident { vec4 hfgi_incident[]; }; // direct: texel × n²: T (HFGI_STORE_T)
layout(std430, binding = 9) readonly buffer Blockers { float hfgi_bv[]; };     // receivers × n² (× 2 in log mode)
layout(std430, binding = 10) readonly buffer BSpheres { vec4 hfgi_spheres[]; }; // per slot: (c_hi, r), (c_lo, 0)
layout(push_constant) uniform Push { hfgi_ShadePush pc; };
#include "hfgi_sh.glsl"
#include "hfgi_address.glsl"
#include "hfgi_store.glsl"
#define HFGI_PACKED_PLANES (HFGI_PACKED != 0u)
#include "hfgi_plane.glsl"

#define vis_at(i) HFGI_LOAD_TEXEL(hfgi_vis_texels, i)
// A receiver-grid value at this texel: `at(r)` of receiver r, bilinear over r00 … r11 with the
// weights w00 … w11, or with HFGI_SAME_GRID receiver r00's own.
#define HFGI_RECEIVERS_AT(at) \
    (HFGI_SAME_GRID != 0u ? at(r00) : w00 * at(r00) + w10 * at(r10) + w01 * at(r01) + w11 * at(r11))

// Texel `at` (plane · W·H + texel) of the shading planes.
vec3 hfgi_out_get(uint at) {
    return HFGI_PLANE_LOAD(hfgi_out, at);
}

void hfgi_out_set(uint at, vec3 v) {
    HFGI_PLANE_STORE(hfgi_out, at, v)
}

float height(int x, int y) {
    return uintBitsToFloat(texelFetch(hfgi_levels_texels, int(uint(y) * pc.width + uint(x))).x);
}

int wrap_or_clamp(int p, int n) {
    return hfgi_address(p, n, pc.wrap != 0u);
}

// CONVENTIONS.md normals: central differences inside, one-sided at the border (periodic with wrap).
vec3 normal_at(ivec2 p) {
    int w = int(pc.width), h = int(pc.height);
    int x0, x1, y0, y1;
    float dx, dy;
    if (pc.wrap != 0u) {
        x0 = p.x - 1; x1 = p.x + 1; y0 = p.y - 1; y1 = p.y + 1; dx = 2.0; dy = 2.0;
    } else {
        x0 = max(p.x - 1, 0); x1 = min(p.x + 1, w - 1); y0 = max(p.y - 1, 0); y1 = min(p.y + 1, h - 1);
        dx = float(x1 - x0); dy = float(y1 - y0);
    }
    float hx = (height(wrap_or_clamp(x1, w), p.y) - height(wrap_or_clamp(x0, w), p.y)) / (dx * pc.texel_size);
    float hy = (height(p.x, wrap_or_clamp(y1, h)) - height(p.x, wrap_or_clamp(y0, h))) / (dy * pc.texel_size);
    return normalize(vec3(-hx, -hy, 1.0));
}

// Solid angle of the intersection of caps of angular radii a, b whose centres are g apart:
// two sectors minus the kite, haversine and L'Huilier forms (small suns keep their digits).
// Twin: math::overlap::cap_overlap.
float hfgi_hav(float x) {
    float s = sin(0.5 * x);
    return s * s;
}

float hfgi_cap_overlap(float a, float b, float g) {
    const float PI = 3.14159265358979;
    if (g >= a + b) return 0.0;
    if (g <= abs(a - b)) return 4.0 * PI * hfgi_hav(min(a, b));
    if (a + b + g >= 2.0 * PI) return 4.0 * PI * (hfgi_hav(a) + hfgi_hav(b)) - 4.0 * PI;
    float ha = clamp((hfgi_hav(b) - hfgi_hav(a - g)) / (sin(a) * sin(g)), 0.0, 1.0);
    float hb = clamp((hfgi_hav(a) - hfgi_hav(b - g)) / (sin(b) * sin(g)), 0.0, 1.0);
    float pa = 2.0 * asin(sqrt(ha)), pb = 2.0 * asin(sqrt(hb));
    float s = 0.5 * (a + b + g);
    float t = max(tan(0.5 * s), 0.0) * max(tan(0.5 * (s - a)), 0.0) * max(tan(0.5 * (s - b)), 0.0) * max(tan(0.5 * (s - g)), 0.0);
    float e = 4.0 * atan(sqrt(t));
    return max(4.0 * pa * hfgi_hav(a) + 4.0 * pb * hfgi_hav(b) - 2.0 * e, 0.0);
}

// The fraction of the key light's cap (unit dir, angular radius alpha) that the spheres leave
// open from P: Π_i (1 − Ω(light ∩ sphere_i)/Ω_light), 0 inside a sphere.
// Twin: math::overlap::unoccluded_fraction.
float hfgi_key_open(vec3 P, vec3 dir, float alpha) {
    float light = 12.566370614359172 * hfgi_hav(alpha);
    float t = 1.0;
    for (uint i = 0u; i < pc.sphere_count; ++i) {
        vec4 c_hi = hfgi_spheres[2u * i], c_lo = hfgi_spheres[2u * i + 1u];
        float rad = c_hi.w;
        if (rad <= 0.0) continue;
        precise vec3 C = (c_hi.xyz - P) + c_lo.xyz;
        float d = length(C);
        if (d <= rad) return 0.0;
        float g = atan(length(cross(C, dir)), dot(C, dir));
        t *= 1.0 - min(hfgi_cap_overlap(alpha, asin(rad / d), g) / light, 1.0);
    }
    return t;
}

vec3 hfgi_T[HFGI_N2];
vec3 hfgi_T2[HFGI_N2]; // log mode: the environment's L ⊛ exp*(f_hf + Σ f_i)
float hfgi_V[HFGI_N2];
float hfgi_VS[HFGI_N2]; // the blockers' visibility at the texel

// V = the blockers' vectors at float offset `base` (n² per receiver), at this texel
// (HFGI_RECEIVERS_AT: bilinear, or the receiver's own on the same grid).
void hfgi_interp(uint base, uint r00, uint r10, uint r01, uint r11, vec4 w) {
    uint n2 = uint(HFGI_N2);
    float w00 = w.x, w10 = w.y, w01 = w.z, w11 = w.w;
    for (int k = 0; k < HFGI_N2; ++k) {
        uint o = base + uint(k);
#define HFGI_BV_OF(r) hfgi_bv[o + (r) * n2]
        hfgi_V[k] = HFGI_RECEIVERS_AT(HFGI_BV_OF);
#undef HFGI_BV_OF
    }
}

void main() {
    ivec2 p = ivec2(gl_GlobalInvocationID.xy);
    if (p.x >= int(pc.width) || p.y >= int(pc.height)) return;
    vec3 N = normal_at(p);

    // Receiver-grid position of this texel and its bilinear weights (docs/direct.md §6).
    vec2 pw = (vec2(p) + 0.5) * vec2(pc.work_width, pc.work_height) / vec2(pc.width, pc.height) - 0.5;
    vec2 fl = floor(pw);
    vec2 f = pw - fl;
    ivec2 b = ivec2(fl);
    int ww = int(pc.work_width), wh = int(pc.work_height);
    uint r00 = uint(wrap_or_clamp(b.y, wh) * ww + wrap_or_clamp(b.x, ww));
    uint r10 = uint(wrap_or_clamp(b.y, wh) * ww + wrap_or_clamp(b.x + 1, ww));
    uint r01 = uint(wrap_or_clamp(b.y + 1, wh) * ww + wrap_or_clamp(b.x, ww));
    uint r11 = uint(wrap_or_clamp(b.y + 1, wh) * ww + wrap_or_clamp(b.x + 1, ww));
    float w00 = (1.0 - f.x) * (1.0 - f.y), w10 = f.x * (1.0 - f.y), w01 = (1.0 - f.x) * f.y, w11 = f.x * f.y;
    uint receivers = pc.work_width * pc.work_height;

    vec3 K[HFGI_N2]; // key lights shadowed by the cap overlap (not multiplied by V_s)
    for (int k = 0; k < HFGI_N2; ++k) {
        hfgi_T[k] = vec3(0.0);
        hfgi_T2[k] = vec3(0.0);
        K[k] = vec3(0.0);
    }
    vec3 P = vec3(float(p.x) * pc.texel_size, float(p.y) * pc.texel_size, height(p.x, p.y));
    if (HFGI_INDIRECT != 0) {
        // Incident indirect radiance: U of eq. 21, bilinear from the receiver grid.
        uint us = hfgi_stride(3 * HFGI_NU);
        for (int k = 0; k < HFGI_NU; ++k) {
            for (int c = 0; c < 3; ++c) {
                uint oc = uint(3 * k + c);
#define HFGI_U_OF(r) vis_at((r) * us + oc)
                hfgi_T[k][c] = HFGI_RECEIVERS_AT(HFGI_U_OF);
#undef HFGI_U_OF
            }
        }
        // With f16, U is stored times the pre-exposure (frame::storage::pre_exposure).
        if (HFGI_HALF != 0u) {
            float unexpose = 1.0 / pc.u_scale;
            for (int k = 0; k < HFGI_NU; ++k) hfgi_T[k] *= unexpose;
        }
    }
    bool diffuse_only = HFGI_BLOCKERS == 0u && HFGI_STORE_T == 0 && pc.glossy == 0u;
    for (uint s = 0u; s < (HFGI_INDIRECT != 0 ? 0u : pc.set_count); ++s) {
        uint vs = hfgi_stride(HFGI_N2);
        uint base = s * receivers * vs;
        for (int k = 0; k < HFGI_N2; ++k) {
#define HFGI_V_OF(r) vis_at(base + (r) * vs + uint(k))
            hfgi_V[k] = HFGI_RECEIVERS_AT(HFGI_V_OF);
#undef HFGI_V_OF
        }
        bool combined = HFGI_BLOCKERS >= 2u && s == 0u; // log modes: the environment's own vector
        if (combined) hfgi_interp(receivers * uint(HFGI_N2), r00, r10, r01, r11, vec4(w00, w10, w01, w11));
        // A key light with gi.blocker_key_lights = "overlap": scaled by the fraction of its cap
        // the spheres leave open, and kept out of the product with V_s.
        vec4 cap = hfgi_light(pc.set_count * uint(HFGI_N2) + s);
        bool key = HFGI_BLOCKERS != 0u && pc.key_overlap != 0u && cap.w > 0.0;
        float open = key ? hfgi_key_open(P, cap.xyz, cap.w) : 1.0;
        // T_k += Σ_ij Γ_ijk L_i V_j = Σ_j V_j M_s[j][k]: the set's product matrix, formed on the
        // host from its lighting (shade::product_matrix; n² × n² RGB after the caps).
        uint mbase = pc.set_count * uint(HFGI_N2 + 1) + s * uint(HFGI_N2 * HFGI_N2);
        // The sum over j unrolled: V indexed by constants stays in registers (docs/performance.md
        // §19). The bound is a literal (order ≤ HFGI_MAX_SH_ORDER): the copies past n² are dead.
        [[dont_unroll]] for (int k = 0; k < HFGI_N2; ++k) {
            // Rows only the diffuse lobe reads, where its band is zero (the clamped cosine's odd
            // bands ≥ 3, the exact lobe's every band but 1): nothing else reads T_k.
            if (diffuse_only && hfgi_zh_diffuse[int(sqrt(float(k) + 0.5))] == 0.0) continue;
            vec3 add = vec3(0.0);
            [[unroll]] for (int j = 0; j < HFGI_UNROLLED; ++j) {
                if (j < HFGI_N2) add += hfgi_V[j] * hfgi_light(mbase + uint(j * HFGI_N2 + k)).rgb;
            }
            if (combined) hfgi_T2[k] += add; else if (key) K[k] += open * add; else hfgi_T[k] += add;
        }
    }
    if (HFGI_BLOCKERS != 0u) {
        // T ← T ⊛ V_s (+ the log mode's environment term), truncated to order n.
        hfgi_interp(0u, r00, r10, r01, r11, vec4(w00, w10, w01, w11));
        for (int k = 0; k < HFGI_N2; ++k) hfgi_VS[k] = hfgi_V[k];
        vec3 W[HFGI_N2];
        for (int k = 0; k < HFGI_N2; ++k) W[k] = hfgi_T2[k];
        for (uint e = 0u; e < hfgi_triple_count; ++e) {
            uvec2 t = hfgi_triple(e);
            uint i = t.x & 0xFFu, j = (t.x >> 8) & 0xFFu, k = (t.x >> 16) & 0xFFu;
            W[k] += uintBitsToFloat(t.y) * hfgi_VS[j] * hfgi_T[i];
        }
        for (int k = 0; k < HFGI_N2; ++k) hfgi_T[k] = W[k] + K[k];
    }

    // Diffuse: E = Σ_k T_k c_k with c the clamped cosine ZH rotated to N.
    hfgi_sh_eval(N);
    vec3 E = vec3(0.0);
    for (int l = 0; l < HFGI_N; ++l) {
        for (int m = -l; m <= l; ++m) {
            int k = l * (l + 1) + m;
            E += hfgi_T[k] * (hfgi_zh_diffuse[l] * hfgi_y[k]);
        }
    }
    if (HFGI_BLOCKERS == 3u && HFGI_INDIRECT == 0 && pc.set_count > 0u) {
        // log_brdf: the environment's diffuse term from its transfer vector (seed 001 §5).
        hfgi_interp(2u * receivers * uint(HFGI_N2), r00, r10, r01, r11, vec4(w00, w10, w01, w11));
        for (int l = 0; l < HFGI_N; ++l) {
            for (int m = -l; m <= l; ++m) {
                int k = l * (l + 1) + m;
                E += 3.14159265358979 * hfgi_V[k] * hfgi_light(uint(k)).rgb - hfgi_T2[k] * (hfgi_zh_diffuse[l] * hfgi_y[k]);
            }
        }
    }
    vec3 rho = pc.albedo_map != 0u ? hfgi_albedo[uint(p.y) * pc.width + uint(p.x)].rgb : pc.albedo.rgb;
    vec3 direct = rho * E * 0.31830988618379067;

    vec3 glossy = vec3(0.0);
    if (pc.glossy != 0u) {
        // (camera − P) + camera_lo: the high part cancels exactly against P near the surface,
        // the low part restores the camera's f64 position (docs/hard-cases.md).
        precise vec3 rel = (pc.camera.xyz - P) + pc.camera_lo.xyz;
        vec3 wo = normalize(rel);
        vec3 R = 2.0 * dot(N, wo) * N - wo;
        hfgi_sh_eval(normalize(R));
        vec3 G = vec3(0.0);
        for (int l = 0; l < HFGI_N; ++l) {
            for (int m = -l; m <= l; ++m) {
                int k = l * (l + 1) + m;
                G += hfgi_T[k] * (hfgi_zh_glossy[l] * hfgi_y[k]);
            }
        }
        if (HFGI_BLOCKERS == 3u && HFGI_INDIRECT == 0 && pc.set_count > 0u) {
            // log_brdf: the environment's glossy term from its glossy transfer (seed 001
            // eq. 27), ⟨L_env, T_φ⟩, instead of ⟨L_env ⊛ V', phong_R⟩ (hfgi_y holds Y(R)).
            hfgi_interp(3u * receivers * uint(HFGI_N2), r00, r10, r01, r11, vec4(w00, w10, w01, w11));
            for (int l = 0; l < HFGI_N; ++l) {
                for (int m = -l; m <= l; ++m) {
                    int k = l * (l + 1) + m;
                    G += hfgi_V[k] * hfgi_light(uint(k)).rgb - hfgi_T2[k] * (hfgi_zh_glossy[l] * hfgi_y[k]);
                }
            }
        }
        glossy = pc.specular.rgb * G;
    }
    uint plane = pc.width * pc.height;
    uint idx = uint(p.y) * pc.width + uint(p.x);
    if (HFGI_STORE_T != 0 && HFGI_INDIRECT == 0) {
        for (int k = 0; k < HFGI_N2; ++k) hfgi_incident[idx * uint(HFGI_N2) + uint(k)] = vec4(hfgi_T[k], 0.0);
    }
    // Plane indices: HFGI_PLANE_* (src/constants.rs, defined by build.rs).
    uint at_direct = HFGI_PLANE_DIRECT * plane + idx, at_indirect = HFGI_PLANE_INDIRECT * plane + idx;
    uint at_gd = HFGI_PLANE_GLOSSY_DIRECT * plane + idx, at_gi = HFGI_PLANE_GLOSSY_INDIRECT * plane + idx;
    if (HFGI_INDIRECT != 0) {
        // `direct` and `glossy` hold this bounce's diffuse and glossy exit radiance; the next
        // bounce's radiance pyramid (§5.3) starts from their sum (the scalar approximation for
        // mixtures), or from the diffuse part alone beside T (glossy vector pyramid), written
        // here into its level 0 (W×H at offset 0 of each channel) as radiance.gather writes
        // bounce 1's: channels 0-2 the radiance, then (vector) channel 3 + 3k + c = T_k.
        // A working-grid pyramid (scalar only) gets it through the total plane, except after the
        // last bounce: radiance.gather averages it to its level 0 (rules::scene::radiance_base).
        vec3 next = HFGI_STORE_T != 0 ? direct : direct + glossy;
        if (pc.next_mode == HFGI_NEXT_LEVEL0) {
            for (uint c = 0u; c < 3u; ++c) hfgi_next[c * HFGI_NEXT_STRIDE + idx] = next[c];
        } else if (pc.next_mode == HFGI_NEXT_TOTAL) {
            hfgi_out_set(HFGI_PLANE_TOTAL * plane + idx, next);
        }
        if (HFGI_STORE_T != 0) {
            for (uint k = 0u; k < uint(HFGI_N2); ++k) {
                for (uint c = 0u; c < 3u; ++c) hfgi_next[(3u + 3u * k + c) * HFGI_NEXT_STRIDE + idx] = hfgi_T[k][c];
            }
        }
        if (pc.accumulate != 0u) {
            direct += hfgi_out_get(at_indirect);
            if (HFGI_GLOSSY != 0) glossy += hfgi_out_get(at_gi);
        }
        hfgi_out_set(at_indirect, direct);
        if (HFGI_GLOSSY != 0) hfgi_out_set(at_gi, glossy);
    } else {
        hfgi_out_set(at_direct, direct);
        if (HFGI_GLOSSY != 0) hfgi_out_set(at_gd, glossy);
    }
    vec3 g = vec3(0.0);
    if (HFGI_GLOSSY != 0) {
        g = hfgi_out_get(at_gd) + hfgi_out_get(at_gi);
        hfgi_out_set(HFGI_PLANE_GLOSSY * plane + idx, g);
    }
    // With HFGI_NEXT_TOTAL the total plane holds the next bounce's input until the last bounce.
    if (HFGI_INDIRECT == 0 || pc.next_mode != HFGI_NEXT_TOTAL) {
        hfgi_out_set(HFGI_PLANE_TOTAL * plane + idx, hfgi_out_get(at_direct) + hfgi_out_get(at_indirect) + g);
    }
}
