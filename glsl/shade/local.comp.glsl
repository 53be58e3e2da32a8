#version 460
// Local spherical lights (stage `shade.local_lights`; docs/local-lights.md, after SN08 thesis
// §4.3, seed 002): per full-resolution texel and light, the cap of half-angle asin(r/d) toward
// the light's centre is cut into azimuth slices (Gauss–Legendre in φ = φ_c + β sin u, or
// uniform azimuths when the cap holds the zenith); on each slice the cap's elevation window is
// intersected with the open interval above the horizon — the exact horizon of the bilinear
// surface along the slice, marched only up to where the slice's central ray enters the sphere
// (eq. 4.24: nothing behind the light shadows it; the horizon may be below zero, eq. 4.23) —
// and above the tangent elevation, and the clamped cosine is integrated over it in closed
// form. The diffuse exit radiance ρ/π · Σ_lights L · E_l is added to the direct and total
// planes that shade.direct has just written (the indirect bounces then carry it); on a glossy
// surface k_s · Σ_lights L · G_l — the normalised Phong lobe about the reflected view vector
// integrated over the same visible windows (Gauss–Legendre in elevation) — to the glossy ones.
// Twin: reference::local::local_exitance.
#include "hfgi_shared.glsl"
layout(local_size_x = HFGI_WORKGROUP, local_size_y = HFGI_WORKGROUP) in;

layout(constant_id = 0) const int HFGI_GLOSSY = 0; // 1: the shading buffer has the glossy planes (shade::planes)
layout(constant_id = 1) const uint HFGI_PACKED = 0u; // 1: RGBE shading planes (gi.shading_storage; hfgi_plane.glsl)
#define HFGI_PACKED_PLANES (HFGI_PACKED != 0u)
#include "hfgi_plane.glsl"
layout(std430, binding = 0) readonly buffer Levels { float hfgi_levels[]; };  // level 0 = absolute heights, W×H
layout(std430, binding = 1) readonly buffer Lights { vec4 hfgi_lights[]; };  // per slot: (c_hi, r), (c_lo, 0), (L, 0)
layout(std430, binding = 2) readonly buffer Nodes { vec2 hfgi_nodes[]; };    // Gauss–Legendre (x, w) on [−1, 1]
layout(std430, binding = 3) readonly buffer Albedo { vec4 hfgi_albedo[]; };  // per texel (albedo_map)
layout(std430, binding = 4) buffer Out { uint hfgi_out[]; };                 // the shading planes (hfgi_plane.glsl)
layout(push_constant) uniform Push { hfgi_LocalPush pc; };
#define HFGI_FIELD_H(i) hfgi_levels[i]
#define HFGI_FIELD_W pc.width
#define HFGI_FIELD_HGT pc.height
#define HFGI_FIELD_S pc.texel_size
#include "hfgi_field.glsl"

const float HFGI_PI = 3.14159265358979;
const float HFGI_HALF_PI = 1.5707963267948966;

// The cap's elevation window [ω_c − δ, ω_c + δ] on the half-plane of azimuth direction d;
// false where it misses the cap. Twin: reference::cap::cap_window.
bool cap_window(vec2 d, vec3 l, float sin_a, float cos_a, out float lo, out float hi) {
    float dl = dot(d, l.xy);
    float cr = d.x * l.y - d.y * l.x;
    float x = sin_a * sin_a - cr * cr;
    if (x < 0.0) return false;
    float r = length(vec2(dl, l.z));
    float delta = 2.0 * asin(min(sqrt(x / ((r + cos_a) * 2.0 * r)), 1.0));
    float wc = atan(l.z, dl);
    lo = wc - delta;
    hi = wc + delta;
    return true;
}

// ∫_a^b (N·ω) cos ω dω on the half-plane of azimuth d (h = N·(d, 0)), N·ω ≥ 0 on [a, b].
float slice(float h, float nz, float a, float b) {
    float sa = sin(a), ca = cos(a), sb = sin(b), cb = cos(b);
    return 0.5 * h * ((b - a) + sb * cb - sa * ca) + 0.5 * nz * (sb * sb - sa * sa);
}

// ∫_a^b lobe(u(ω)·R) cos ω dω on the half-plane of azimuth d, the normalised Phong lobe
// (S+1)/(2π) max(cos, 0)^S, by LOCAL_GLOSSY_NODES Gauss–Legendre nodes (after the azimuths').
float glossy_slice(vec2 d, vec3 R, float a, float b) {
    float hw = 0.5 * (b - a), mid = 0.5 * (a + b), g = 0.0;
    for (uint j = 0u; j < HFGI_LOCAL_GLOSSY_NODES; ++j) {
        vec2 node = hfgi_nodes[pc.azimuths + j];
        float om = mid + hw * node.x;
        vec3 u = vec3(cos(om) * d, sin(om));
        g += node.y * pow(max(dot(u, R), 0.0), pc.exponent) * cos(om);
    }
    return hw * g * (pc.exponent + 1.0) / (2.0 * HFGI_PI);
}

// (E, G) / L of one light (centre C relative to the texel, radius r) at texel p, normal N,
// surface height `base` at p (what the horizon slopes are measured from): the irradiance and,
// with pc.glossy, the Phong lobe about R integrated over the same visible part of the cap.
vec2 light_irradiance(vec2 p, float base, vec3 N, vec3 R, vec3 C, float r) {
    float d = length(C);
    bool inside = d <= r;
    float sin_a = inside ? 1.0 : r / d;
    float cos_a = inside ? 0.0 : sqrt((d - r) * (d + r)) / d;
    vec3 l = C / d;
    float cos_e = length(l.xy);
    bool pole = cos_e <= sin_a;
    float phi_c = atan(l.y, l.x);
    float beta = pole ? 0.0 : asin(min(sin_a / cos_e, 1.0));
    float E = 0.0, G = 0.0;
    for (uint k = 0u; k < pc.azimuths; ++k) {
        float phi, w;
        if (pole) {
            w = 2.0 * HFGI_PI / float(pc.azimuths);
            phi = (float(k) + 0.5) * w;
        } else {
            vec2 node = hfgi_nodes[k];
            float u = HFGI_HALF_PI * node.x;
            phi = phi_c + beta * sin(u);
            w = HFGI_HALF_PI * node.y * beta * cos(u);
        }
        vec2 dir = vec2(cos(phi), sin(phi));
        float lo, hi;
        if (!cap_window(dir, l, sin_a, cos_a, lo, hi)) continue;
        float h = dot(N.xy, dir);
        float a = max(max(lo, atan(-h, N.z)), -HFGI_HALF_PI), b = min(hi, HFGI_HALF_PI);
        if (b <= a) continue;
        // Reach: where the slice's central ray (the middle of its window below the zenith)
        // enters the sphere, in planar texels; 0 inside the sphere.
        float wc = 0.5 * (lo + b);
        vec3 u3 = vec3(cos(wc) * dir, sin(wc));
        float bc = dot(u3, C);
        float t = inside ? 0.0 : bc - sqrt(max(bc * bc - (d - r) * (d + r), 0.0));
        float reach = max(t, 0.0) * cos(wc) / pc.texel_size;
        float best;
        if (reach > 0.0 && hfgi_field_slope(p, dir, reach, base, best))
            a = max(a, atan(best / pc.texel_size));
        if (b > a) {
            E += w * slice(h, N.z, a, b);
            if (pc.glossy != 0u) G += w * glossy_slice(dir, R, a, b);
        }
    }
    return vec2(E, G);
}

// Adds `v` to texel `at` (plane · W·H + texel) of the shading planes.
void hfgi_out_add(uint at, vec3 v) {
    vec3 sum = HFGI_PLANE_LOAD(hfgi_out, at) + v;
    HFGI_PLANE_STORE(hfgi_out, at, sum)
}

void main() {
    ivec2 p = ivec2(gl_GlobalInvocationID.xy);
    if (p.x >= int(pc.width) || p.y >= int(pc.height)) return;
    vec3 N = hfgi_field_normal(p);
    vec3 P = vec3(float(p.x) * pc.texel_size, float(p.y) * pc.texel_size, hfgi_field_height(p.x, p.y));
    vec3 E = vec3(0.0), G = vec3(0.0);
    float base = hfgi_field_bilinear(vec2(p)); // once per texel, not per light and slice
    // The reflected view vector (as shade.direct's: (camera − P) + camera_lo).
    precise vec3 rel = (pc.camera.xyz - P) + pc.camera_lo.xyz;
    vec3 wo = normalize(rel);
    vec3 R = normalize(2.0 * dot(N, wo) * N - wo);
    for (uint i = 0u; i < pc.light_count; ++i) {
        vec4 c_hi = hfgi_lights[3u * i], c_lo = hfgi_lights[3u * i + 1u], L = hfgi_lights[3u * i + 2u];
        if (all(equal(L.rgb, vec3(0.0)))) continue;
        // (c_hi − P) + c_lo: the f64 centre relative to the texel, exact near the surface.
        precise vec3 C = (c_hi.xyz - P) + c_lo.xyz;
        vec2 eg = light_irradiance(vec2(p), base, N, R, C, c_hi.w);
        E += L.rgb * eg.x;
        G += L.rgb * eg.y;
    }
    vec3 rho = pc.albedo_map != 0u ? hfgi_albedo[uint(p.y) * pc.width + uint(p.x)].rgb : pc.albedo.rgb;
    vec3 add = rho * E * 0.31830988618379067;
    uint plane = pc.width * pc.height, idx = uint(p.y) * pc.width + uint(p.x);
    uint at_direct = HFGI_PLANE_DIRECT * plane + idx, at_total = HFGI_PLANE_TOTAL * plane + idx;
    hfgi_out_add(at_direct, add);
    vec3 gl = pc.glossy != 0u ? pc.specular.rgb * G : vec3(0.0);
    if (HFGI_GLOSSY != 0 && pc.glossy != 0u) {
        // The glossy light joins the direct glossy plane and the glossy layer (shade.direct
        // recomposes them from planes 4 and 5, so later bounces keep it). Only a surface
        // created glossy has these planes (HFGI_GLOSSY, shade::planes).
        hfgi_out_add(HFGI_PLANE_GLOSSY_DIRECT * plane + idx, gl);
        hfgi_out_add(HFGI_PLANE_GLOSSY * plane + idx, gl);
    }
    hfgi_out_add(at_total, add);
    hfgi_out_add(at_total, gl);
}
