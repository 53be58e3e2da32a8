#version 460
// View spheres (docs/view.md §6): diffuse albedo/π · E(N). E = the environment's irradiance
// from its first 9 SH coefficients (pre-multiplied on the host by the clamped-cosine factors
// Â_0 = π, Â_1 = 2π/3, Â_2 = π/4, so E(N) = Σ_k env[k] y_k(N), CONVENTIONS.md real SH in
// Cartesian form) times an occlusion factor F, plus every key light's
// L·2π(1 − cos α)·max(N·d, 0) (pre-multiplied too) times its visible fraction V.
// The height field's cast shadow (seed 001 §4.1, "Height Field Cast Shadows"): the surface
// point X is projected onto the field (q = X.xy / s, ground g = bilinear height at q, height
// above it h = X.z − g) and the field's exact horizon along an azimuth is marched from q,
// offset by h: ω = atan(sup_t (H(q + t·u) − X.z) / (t·s)). Key light: V = clamp((e + α − ω_b)
// / 2α, 0, 1) along the light's azimuth (e = asin(d_z)); environment: F = mean over 8 uniform
// azimuths of 1 − sin²(max(ω_k, 0)) (an approximation, not the SH product). Outside the
// field, or for a light straight overhead, no field shadow.
// Not clamped (CONVENTIONS.md: the SH lighting is used as it is). Alpha 1.
#include "hfgi_shared.glsl"
#include "hfgi_near.glsl"

const float HFGI_PI = 3.14159265358979;
const uint HFGI_AO_AZIMUTHS = 8u;

struct hfgi_ViewKeyLight {
    vec4 direction;   // unit direction toward the light (xyz), angular radius α (w, radians)
    vec4 irradiance;  // L·2π(1 − cos α) (rgb): irradiance on a surface facing the light
};

// = view::SphereLighting (std430): counts.x = key lights.
layout(std430, binding = 1) readonly buffer Light {
    uvec4 hfgi_counts;
    vec4 hfgi_env[9];
    hfgi_ViewKeyLight hfgi_keys[];
};
// The renderer's heights (W×H f32, row-major, absolute; texel (i, j) at world (i·s, j·s)).
layout(std430, binding = 2) readonly buffer Heights { float hfgi_heights[]; };
layout(push_constant) uniform Push { hfgi_ViewPush pc; };

layout(location = 0) in vec3 hfgi_normal;
layout(location = 1) flat in vec3 hfgi_albedo;
layout(location = 2) flat in vec4 hfgi_center_radius;  // centre high part (xyz), radius (w)
layout(location = 3) flat in vec3 hfgi_center_lo;       // centre low part
layout(location = 0) out vec4 hfgi_out;

// Heights are read relative to the height of the texel nearest the projected point, so that
// differences of heights near 1e7 stay exact to f32.
float hfgi_ref = 0.0;

float height_rel(int x, int y) {
    return hfgi_heights[uint(y) * pc.width + uint(x)] - hfgi_ref;
}

// The bilinear surface at level-0 position q (clamped to the field), minus hfgi_ref.
float bilinear_rel(vec2 q) {
    vec2 c = clamp(q, vec2(0.0), vec2(pc.width - 1u, pc.height - 1u));
    ivec2 i = min(ivec2(floor(c)), ivec2(pc.width - 2u, pc.height - 2u));
    vec2 f = c - vec2(i);
    float a = mix(height_rel(i.x, i.y), height_rel(i.x + 1, i.y), f.x);
    float b = mix(height_rel(i.x, i.y + 1), height_rel(i.x + 1, i.y + 1), f.x);
    return mix(a, b, f.y);
}

// hfgi_piece_max, also for the first piece (t0 = 0) of a raised point, where F(0) = c = −h ≠ 0:
// c > 0 (the point is under the surface) blocks everything; c < 0 makes F/t → −∞ at 0, so the
// maximum is at the end or at the interior critical point √(c/a) (a < 0).
float piece_max_raised(float t0, float t1, float a, float b, float c) {
    if (t0 > 0.0 || c == 0.0) return hfgi_piece_max(t0, t1, a, b, c);
    if (c > 0.0) return 1e30;
    float best = ((a * t1 + b) * t1 + c) / t1;
    if (a < 0.0) {
        float ts = sqrt(c / a);
        if (ts < t1) best = max(best, a * ts + b + c / ts);
    }
    return best;
}

// The blocking slope tan ω of the field along unit planar direction d from level-0
// position p for a point h world units above the ground g (g relative to hfgi_ref): the largest
// (H(p + t·d) − (g + h)) / (t·s) over t ∈ (0, reach], reach = the distance to the field's edge
// (at most max(W, H) texels), one quadratic per cell crossed (as hfgi_local_slope in
// glsl/shade/local.comp.glsl). −1e30 where the ray leaves the field at once (nothing blocks).
float horizon_slope(vec2 p, vec2 d, float g, float h) {
    vec2 n = vec2(pc.width, pc.height);
    float ex = d.x > 0.0 ? (n.x - 1.0 - p.x) / d.x : (d.x < 0.0 ? p.x / -d.x : 1e30);
    float ey = d.y > 0.0 ? (n.y - 1.0 - p.y) / d.y : (d.y < 0.0 ? p.y / -d.y : 1e30);
    float t_end = min(max(n.x, n.y), min(ex, ey));
    if (t_end <= 0.0) return -1e30;
    vec2 stp = vec2(abs(d.x) > 1e-6 ? 1.0 / abs(d.x) : 1e30, abs(d.y) > 1e-6 ? 1.0 / abs(d.y) : 1e30);
    vec2 dist = vec2(d.x > 0.0 ? floor(p.x) + 1.0 - p.x : p.x - ceil(p.x) + 1.0,
                     d.y > 0.0 ? floor(p.y) + 1.0 - p.y : p.y - ceil(p.y) + 1.0);
    vec2 tn = dist * stp;
    float best = -1e30;
    float ta = 0.0, fa = -h;
    for (int guard = 0; guard < 4 * int(t_end) + 8; ++guard) {
        float tb = min(min(tn.x, tn.y), t_end);
        if (tb > ta + 1e-6) {
            float len = tb - ta;
            float fm = (bilinear_rel(p + (ta + 0.5 * len) * d) - g) - h;
            float fb = (bilinear_rel(p + tb * d) - g) - h;
            float a = 2.0 * (fb - 2.0 * fm + fa) / (len * len);
            float b = (fb - fa) / len - a * len;
            best = max(best, piece_max_raised(ta, tb, a, b, fa));
            fa = fb;
            ta = tb;
        }
        if (tb >= t_end) break;
        if (tn.x <= tb) tn.x += stp.x;
        if (tn.y <= tb) tn.y += stp.y;
    }
    return best / pc.texel_size;
}

void main() {
    vec3 n = normalize(hfgi_normal);
    float x = n.x, y = n.y, z = n.z;
    float b[9] = float[9](0.28209479177, 0.48860251190 * y, 0.48860251190 * z, 0.48860251190 * x,
                          1.09254843059 * x * y, 1.09254843059 * y * z, 0.31539156525 * (3.0 * z * z - 1.0),
                          1.09254843059 * x * z, 0.54627421529 * (x * x - y * y));
    vec3 env = vec3(0.0);
    for (int k = 0; k < 9; k++) {
        env += hfgi_env[k].rgb * b[k];
    }
    // The surface point X = centre + r·n, projected onto the field.
    float r = hfgi_center_radius.w;
    vec2 q = (hfgi_center_radius.xy + (hfgi_center_lo.xy + r * n.xy)) / pc.texel_size;
    vec2 last = vec2(pc.width - 1u, pc.height - 1u);
    bool on_field = all(greaterThanEqual(q, vec2(0.0))) && all(lessThanEqual(q, last));
    float g = 0.0, h = 0.0;
    if (on_field) {
        ivec2 kq = ivec2(round(q));
        hfgi_ref = hfgi_heights[uint(kq.y) * pc.width + uint(kq.x)];
        g = bilinear_rel(q);
        h = ((hfgi_center_radius.z - hfgi_ref) + (hfgi_center_lo.z + r * n.z)) - g;
        float open = 0.0;
        for (uint k = 0u; k < HFGI_AO_AZIMUTHS; k++) {
            float phi = 2.0 * HFGI_PI * float(k) / float(HFGI_AO_AZIMUTHS);
            // 1 − sin²ω = 1 / (1 + tan²ω) for ω > 0 (an infinite slope gives 0).
            float m = max(horizon_slope(q, vec2(cos(phi), sin(phi)), g, h), 0.0);
            open += 1.0 / (1.0 + m * m);
        }
        env *= open / float(HFGI_AO_AZIMUTHS);
    }
    vec3 e = env;
    for (uint i = 0u; i < hfgi_counts.x; i++) {
        vec4 d = hfgi_keys[i].direction;
        float cosine = max(dot(n, d.xyz), 0.0);
        if (cosine <= 0.0) continue;
        float vis = 1.0;
        float planar = length(d.xy);
        if (on_field && planar > 1e-6) {
            // e − ω_b as the angle between (planar, d_z) and (1, tan ω_b): accurate where the
            // light sits on the horizon (no asin, and atan of a small argument there).
            float m = horizon_slope(q, d.xy / planar, g, h);
            float diff = atan(d.z - m * planar, planar + m * d.z);
            vis = clamp((diff + d.w) / max(2.0 * d.w, 1e-6), 0.0, 1.0);
        }
        e += hfgi_keys[i].irradiance.rgb * (cosine * vis);
    }
    hfgi_out = vec4(hfgi_albedo * e / HFGI_PI, 1.0);
}
