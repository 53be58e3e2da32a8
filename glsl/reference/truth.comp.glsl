#version 460
// Brute-force ground truth (CONVENTIONS.md "Accuracy"; docs/accuracy.md §1), one invocation per
// texel of rows [row_offset, row_offset + rows). Per azimuth the ray from the receiver vertex is
// intersected exactly with the bilinear patches (a DDA over cells, one quadratic per cell;
// src/reference/ray.rs is the f64 twin), or, with `march`, marched at `step`-texel samples.
// Rays leaving the domain escape; with wrap they end after max(W, H) texels. Elevation
// integrals: Gauss–Legendre on [max(ω_hor, ω_t), π/2] (open directions: lighting) and on
// [ω_t, ω_hor] (blocked directions: the previous bounce's radiance at the first hit), ω_t the
// exact tangent elevation. Azimuths: the A uniform ones (cap = 0), or the samples (φ, weight)
// of one key light's cap from binding 6 (cap = 1: exact reference, direct light; the cap is
// cap_dir/cap_radiance, its elevation window on each azimuth intersected with the open
// interval). Outputs per texel:
//   exact mode:  E = ∫ L_in max(N·ω, 0) dω (rgb) in element 0;
//   SH mode:     V_k = ∫_open y_k dω (direct, .x) or U_k = ∫_blocked L_hit y_k dω (indirect, rgb).
// Local lights (cap = 2, both modes, direct light; src/reference/local_truth.rs is the f64
// twin): one light per dispatch, its cap formed per texel, E = L ∫ max(N·ω, 0) dω over the
// directions whose ray reaches the sphere before the height field, accumulated (rgb) in a
// region after the W·H·n² texels' (element W·H·n² + texel).
// Sphere blockers (HFGI_SPHERES of them, binding 7; opaque, they do not reflect): a receiver
// inside one gets nothing (every mode adds 0). Direct light: the environment dispatches
// integrate the open interval as if there were no spheres; the sphere dispatches (cap = 3,
// both modes) take out, per sphere k over its own per-receiver azimuth samples (as a local
// light's), the environment (exact: L (N·ω)⁺; SH mode: y_k) on (W_k ∩ open) minus the windows
// of spheres j < k (next_gap), so overlaps count once; a key light's window loses every
// sphere's window (cap = 1); a local light's node counts only if its ray enters no sphere
// before the light. Bounces: a node whose ray enters a sphere before its first hit carries 0.
// The host finishes the shading in f64 (ρ/π, L ⊛ V, clamped-cosine ZH; ρ/π · E of the local
// lights added to the direct exit radiance).
#include "hfgi_shared.glsl"
layout(local_size_x = HFGI_WORKGROUP, local_size_y = HFGI_WORKGROUP) in;
layout(constant_id = 0) const int HFGI_N = 4;
layout(constant_id = 1) const int HFGI_NODES = 16;
// Fixed for a reference run (frame::truth: the push constants' wrap, march and sh_visibility):
// branches on them are compiled out, since lavapipe runs both sides of a branch even on a
// uniform value (docs/performance.md §5).
layout(constant_id = 2) const uint HFGI_WRAP = 0u;
layout(constant_id = 3) const uint HFGI_MARCH = 0u;
layout(constant_id = 4) const uint HFGI_SHVIS = 0u;
// Sphere blockers in binding 7 (0: none; the loops over them compile out).
layout(constant_id = 5) const int HFGI_SPHERES = 0;
const int HFGI_N2 = HFGI_N * HFGI_N;

layout(std430, binding = 0) readonly buffer Heights { float hfgi_h[]; };       // W×H
layout(std430, binding = 1) readonly buffer Light { vec4 hfgi_light[]; };      // n² rgb
layout(std430, binding = 2) readonly buffer Source { vec4 hfgi_source[]; };    // W×H rgb: L_{b-1}
layout(std430, binding = 3) readonly buffer Gauss { vec2 hfgi_gauss[]; };      // nodes, weights on [-1, 1]
layout(std430, binding = 4) readonly buffer Consts { float hfgi_klm[HFGI_MAX_SH_ORDER * HFGI_MAX_SH_ORDER]; };
layout(std430, binding = 5) buffer Out { vec4 hfgi_out[]; };                   // texel × n² (accumulated over azimuth chunks), then texel: local lights' E
layout(std430, binding = 6) readonly buffer Caps { vec2 hfgi_caps[]; };        // local lights' and spheres' (sin u, π/2·w·cos u) [0, local_nodes), then key-light samples (φ, weight)
layout(std430, binding = 7) readonly buffer Spheres { vec4 hfgi_spheres[]; };  // per sphere: centre high f32 + radius (w), centre low f32
layout(push_constant) uniform Push { hfgi_TruthPush pc; };
#include "hfgi_sh.glsl"
#include "hfgi_address.glsl"

// Index of texel t, clamped to the edge or periodic with wrap.
uint texel_index(ivec2 t) {
    bool wrap = HFGI_WRAP != 0u;
    t = ivec2(hfgi_address(t.x, int(pc.width), wrap), hfgi_address(t.y, int(pc.height), wrap));
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
    ivec2 a = HFGI_WRAP != 0u ? p - 1 : max(p - 1, ivec2(0));
    ivec2 b = HFGI_WRAP != 0u ? p + 1 : min(p + 1, ivec2(w - 1, h - 1));
    float hx = (height_at(ivec2(b.x, p.y)) - height_at(ivec2(a.x, p.y))) / (float(b.x - a.x) * pc.texel_size);
    float hy = (height_at(ivec2(p.x, b.y)) - height_at(ivec2(p.x, a.y))) / (float(b.y - a.y) * pc.texel_size);
    return normalize(vec3(-hx, -hy, 1.0));
}

bool inside(vec2 q, float t) {
    if (HFGI_WRAP != 0u) return t <= float(max(pc.width, pc.height));
    return q.x >= 0.0 && q.y >= 0.0 && q.x <= float(pc.width - 1u) && q.y <= float(pc.height - 1u);
}

// A bound on the march length (steps) from p along d: the domain is left by then (or, with
// wrap, max(W, H) texels are covered). Loops get an explicit trip count: lavapipe cuts
// unbounded loops short after a few thousand iterations.
uint march_bound(vec2 p, vec2 d) {
    float t = float(max(pc.width, pc.height));
    if (HFGI_WRAP == 0u) {
        vec2 hi = vec2(float(pc.width - 1u), float(pc.height - 1u));
        float tx = d.x > 1e-6 ? (hi.x - p.x) / d.x : (d.x < -1e-6 ? -p.x / d.x : 1e9);
        float ty = d.y > 1e-6 ? (hi.y - p.y) / d.y : (d.y < -1e-6 ? -p.y / d.y : 1e9);
        t = min(tx, ty);
    }
    return uint(max(t, 0.0) / pc.step) + 2u;
}

// ---- Exact intersection with the bilinear patches (src/reference/ray.rs) ----

// The ray inside one cell: t in [t0, t1] texels, height relative to the receiver
// F(t0 + τ) = (a τ + b) τ + c.
struct Piece { float t0; float t1; float a; float b; float c; };

// DDA state: integer lines are crossed at t = kx/|d.x| and t = ky/|d.y| (p is a vertex).
struct Ray { ivec2 p; vec2 d; float h0; float t_end; vec2 inv; float kx; float ky; float ta; };

float ray_end(vec2 p, vec2 d) {
    if (HFGI_WRAP != 0u) return float(max(pc.width, pc.height));
    vec2 hi = vec2(float(pc.width - 1u), float(pc.height - 1u));
    float tx = d.x > 0.0 ? (hi.x - p.x) / d.x : (d.x < 0.0 ? p.x / -d.x : 1e30);
    float ty = d.y > 0.0 ? (hi.y - p.y) / d.y : (d.y < 0.0 ? p.y / -d.y : 1e30);
    return max(min(tx, ty), 0.0);
}

Ray ray_start(ivec2 p, vec2 d, float h0) {
    Ray r;
    r.p = p; r.d = d; r.h0 = h0;
    r.t_end = ray_end(vec2(p), d);
    r.inv = vec2(abs(d.x) > 1e-12 ? 1.0 / abs(d.x) : 1e30, abs(d.y) > 1e-12 ? 1.0 / abs(d.y) : 1e30);
    r.kx = 1.0; r.ky = 1.0; r.ta = 0.0;
    return r;
}

// A bound on the pieces of a ray (each crossing of an integer line starts one). Loops get an
// explicit trip count: lavapipe cuts unbounded loops short.
uint piece_bound(Ray r) {
    return uint(min(r.t_end, 1e6) * (abs(r.d.x) + abs(r.d.y))) + 3u;
}

// The quadratic on [ta, tb], inside the cell holding its middle; corner heights relative to
// the receiver first (f32 robustness).
Piece cell_piece(Ray r, float ta, float tb) {
    ivec2 c = ivec2(floor(vec2(r.p) + (0.5 * (ta + tb)) * r.d));
    if (HFGI_WRAP == 0u) c = clamp(c, ivec2(0), max(ivec2(int(pc.width) - 2, int(pc.height) - 2), ivec2(0)));
    float g00 = height_at(c) - r.h0, g10 = height_at(c + ivec2(1, 0)) - r.h0;
    float g01 = height_at(c + ivec2(0, 1)) - r.h0, g11 = height_at(c + ivec2(1, 1)) - r.h0;
    float ca = g10 - g00, cb = g01 - g00, cc = (g00 - g10) + (g11 - g01);
    vec2 uv = vec2(r.p - c) + ta * r.d;
    Piece q;
    q.t0 = ta; q.t1 = tb;
    q.a = cc * r.d.x * r.d.y;
    q.b = ca * r.d.x + cb * r.d.y + cc * (uv.x * r.d.y + uv.y * r.d.x);
    q.c = ta > 0.0 ? g00 + ca * uv.x + cb * uv.y + cc * uv.x * uv.y : 0.0;
    return q;
}

// The next piece, false when the ray has ended.
bool ray_next(inout Ray r, out Piece q) {
    q = Piece(0.0, 0.0, 0.0, 0.0, 0.0);
    if (r.ta >= r.t_end) return false;
    float tx = r.kx * r.inv.x, ty = r.ky * r.inv.y;
    float tb = min(min(tx, ty), r.t_end);
    q = cell_piece(r, r.ta, tb);
    if (tx <= tb) r.kx += 1.0;
    if (ty <= tb) r.ky += 1.0;
    r.ta = tb;
    return true;
}

float piece_value(Piece q, float tau) { return (q.a * tau + q.b) * tau + q.c; }

// sup F(t)/t over the piece (first piece: the limit t → 0, the surface's slope, included) and
// the τ where it is reached; F/t = a t + b' + c'/t has its one stationary point at √(c'/a).
vec2 piece_max(Piece q) {
    float len = q.t1 - q.t0;
    vec2 best = vec2(piece_value(q, len) / q.t1, len);
    float start = q.t0 > 0.0 ? q.c / q.t0 : q.b;
    if (start >= best.x) best = vec2(start, 0.0);
    float cp = (q.a * q.t0 - q.b) * q.t0 + q.c;
    if (q.a < 0.0 && cp < 0.0) {
        float ts = sqrt(cp / q.a);
        if (ts > q.t0 && ts < q.t1) {
            float s = piece_value(q, ts - q.t0) / ts;
            if (s > best.x) best = vec2(s, ts - q.t0);
        }
    }
    return best;
}

// The smallest τ in [0, tau_max] with F ≥ k t (G(τ) = aτ² + (b − k)τ + (c − k t0) rises through
// zero there; robust quadratic formula).
float first_reach(Piece q, float k, float tau_max) {
    float b2 = q.b - k, c2 = q.c - k * q.t0;
    if (c2 >= 0.0 && (q.t0 > 0.0 || b2 >= 0.0)) return 0.0;
    float sq = sqrt(max(b2 * b2 - 4.0 * q.a * c2, 0.0));
    float r;
    if (b2 >= 0.0) {
        float den = -b2 - sq;
        r = den < 0.0 ? 2.0 * c2 / den : 0.0;
    } else {
        r = q.a != 0.0 ? (sq - b2) / (2.0 * q.a) : tau_max;
    }
    return clamp(r, 0.0, tau_max);
}

// Horizon elevation from vertex p along d (−π/2 where the ray leaves the domain at once).
float horizon(ivec2 p, vec2 d, float h0) {
    float hor = -1.5707963267948966;
    if (HFGI_MARCH != 0u) {
        uint bound = march_bound(vec2(p), d);
        for (uint k = 1u; k <= bound; ++k) {
            float t = float(k) * pc.step;
            vec2 q = vec2(p) + t * d;
            if (!inside(q, t)) break;
            hor = max(hor, atan((bilinear_h(q) - h0) / (t * pc.texel_size)));
        }
        return hor;
    }
    Ray r = ray_start(p, d, h0);
    uint bound = piece_bound(r);
    float slope = -1e30;
    Piece q;
    for (uint k = 0u; k < bound; ++k) {
        if (!ray_next(r, q)) break;
        slope = max(slope, piece_max(q).x);
    }
    return slope > -1e30 ? atan(slope / pc.texel_size) : hor;
}

vec3 hfgi_acc[HFGI_N2];

// ---- Sphere blockers (src/reference/cap.rs SphereCaps, gaps) ----

// asin to f32 precision (Cephes asinf: an odd polynomial on [0, ½], and asin x = π/2 −
// 2 asin √((1 − x)/2) above), for every cap's δ and β (key lights, local lights, spheres).
// lavapipe's own asin is far less accurate: with it the spheres' GPU-vs-CPU error was 2.3e-5
// (texels off by up to 7e-4 where a cap nearly holds the pole) and the local lights' 2.5e-6;
// with this one, 2.6e-7 and 5.6e-7 (tests/truth.rs).
float precise_asin(float x) {
    float a = abs(x);
    bool big = a > 0.5;
    float z = big ? 0.5 * (1.0 - a) : a * a;
    float y = big ? sqrt(z) : a;
    float p = ((((4.2163199048e-2 * z + 2.4181311049e-2) * z + 4.5470025998e-2) * z + 7.4953002686e-2) * z + 1.6666752422e-1) * z * y + y;
    return sign(x) * (big ? 1.5707963267948966 - 2.0 * p : p);
}

// Per sphere, seen from this receiver: (C = c − P, q = d² − r²), (l = C/d, sin α), cos α; and
// its elevation window on the current azimuth (vec2(4.0): none — it covers nothing and ends no
// gap, every elevation being ≤ π/2).
vec4 hfgi_sC[HFGI_SPHERES + 1];
vec4 hfgi_sl[HFGI_SPHERES + 1];
float hfgi_scos[HFGI_SPHERES + 1];
vec2 hfgi_win[HFGI_SPHERES + 1];

// The spheres from receiver P; true when P lies inside one (fully blocked).
bool spheres_setup(ivec2 p, float h0) {
    bool inside = false;
    for (int k = 0; k < HFGI_SPHERES; ++k) {
        // (c_hi − P) + c_lo: the f64 centre relative to the receiver.
        precise vec3 C = (hfgi_spheres[2 * k].xyz - vec3(vec2(p) * pc.texel_size, h0)) + hfgi_spheres[2 * k + 1].xyz;
        float r = hfgi_spheres[2 * k].w;
        float d = length(C);
        inside = inside || d <= r;
        float q = (d - r) * (d + r);
        hfgi_sC[k] = vec4(C, q);
        hfgi_sl[k] = vec4(C / max(d, 1e-30), r / max(d, 1e-30));
        hfgi_scos[k] = sqrt(max(q, 0.0)) / max(d, 1e-30);
    }
    return inside;
}

// Every sphere's elevation window on the half-plane of d (src/reference/cap.rs cap_window).
void sphere_windows(vec2 d) {
    for (int k = 0; k < HFGI_SPHERES; ++k) {
        vec3 l = hfgi_sl[k].xyz;
        float sin_a = hfgi_sl[k].w, cos_a = hfgi_scos[k];
        float dl = dot(d, l.xy), cr = d.x * l.y - d.y * l.x;
        float x = sin_a * sin_a - cr * cr;
        if (x < 0.0) {
            hfgi_win[k] = vec2(4.0);
            continue;
        }
        float R = length(vec2(dl, l.z));
        float delta = 2.0 * precise_asin(min(sqrt(x / ((R + cos_a) * 2.0 * R)), 1.0));
        float wc = atan(l.z, dl);
        hfgi_win[k] = vec2(wc - delta, wc + delta);
    }
}

// The next piece [x, end] of [x, b] outside the windows [0, count) (src/reference/cap.rs gaps):
// the cursor jumps over the windows holding it (each moves it at most once), then the gap runs
// to the nearest window start beyond it, or b. False when nothing is left.
bool next_gap(inout float x, float b, int count, out float end) {
    end = b;
    for (int pass = 0; pass <= count; ++pass) {
        bool moved = false;
        for (int j = 0; j < count; ++j) {
            vec2 w = hfgi_win[j];
            if (w.x <= x && x < w.y) { x = w.y; moved = true; }
        }
        if (!moved) break;
    }
    if (x >= b) return false;
    for (int j = 0; j < count; ++j) if (hfgi_win[j].x > x) end = min(end, hfgi_win[j].x);
    return true;
}

// Distance (world units) along unit u to the nearest sphere it enters (1e30: none):
// τ = q/(u·C + √((u·C)² − q)) where u·C > 0 and (u·C)² ≥ q.
float sphere_hit(vec3 u) {
    float t = 1e30;
    for (int k = 0; k < HFGI_SPHERES; ++k) {
        float b = dot(u, hfgi_sC[k].xyz), q = hfgi_sC[k].w;
        float disc = b * b - q;
        if (b > 0.0 && disc >= 0.0) t = min(t, q / (b + sqrt(disc)));
    }
    return t;
}

// Blocked node e of [tangent, hor] (elevation om) hits at `hit`: add its radiance, unless its
// ray enters a sphere first (planar distances in texels).
void add_hit(int e, float mid, float half_w, vec2 d, vec3 N, float dphi, ivec2 p, vec2 hit) {
    float om = mid + half_w * hfgi_gauss[e].x;
    vec3 dir = vec3(cos(om) * d, sin(om));
    if (HFGI_SPHERES > 0 && sphere_hit(dir) * cos(om) / pc.texel_size < length(hit - vec2(p))) return;
    vec3 r = bilinear_source(hit);
    float wt = half_w * hfgi_gauss[e].y * cos(om) * dphi;
    if (HFGI_SHVIS != 0u) {
        hfgi_sh_eval(dir);
        for (int c = 0; c < HFGI_N2; ++c) hfgi_acc[c] += wt * hfgi_y[c] * r;
    } else {
        hfgi_acc[0] += wt * max(dot(N, dir), 0.0) * r;
    }
}

// Blocked directions of one azimuth: nodes ascend and the running maximum sweeps them; a
// node's first hit is where the surface first reaches it (march: the sample that lifts the
// maximum past it; exact: the root in the first piece whose maximum reaches it).
void bounce_azimuth(ivec2 p, vec2 d, float h0, vec3 N, float dphi, float hor, float tangent) {
    float half_w = 0.5 * (hor - tangent), mid = 0.5 * (hor + tangent);
    int e = 0;
    if (HFGI_MARCH != 0u) {
        float running = -1.5707963267948966;
        uint bound = march_bound(vec2(p), d);
        vec2 hit = vec2(p);
        uint k = 1u;
        for (; e < HFGI_NODES; ++e) {
            float om = mid + half_w * hfgi_gauss[e].x;
            while (running < om && k <= bound) {
                float t = float(k) * pc.step;
                vec2 q = vec2(p) + t * d;
                if (!inside(q, t)) break;
                k += 1u;
                float w_k = atan((bilinear_h(q) - h0) / (t * pc.texel_size));
                if (w_k > running) { running = w_k; hit = q; }
            }
            if (running < om) break;
            add_hit(e, mid, half_w, d, N, dphi, p, hit);
        }
        return;
    }
    Ray r = ray_start(p, d, h0);
    uint bound = piece_bound(r);
    float running = -1e30;
    Piece q;
    for (uint it = 0u; it < bound && e < HFGI_NODES; ++it) {
        if (!ray_next(r, q)) break;
        vec2 m = piece_max(q);
        float top = max(running, m.x);
        for (; e < HFGI_NODES; ++e) {
            float k = tan(mid + half_w * hfgi_gauss[e].x) * pc.texel_size;
            if (k > top) break;
            float t = q.t0 + first_reach(q, k, m.y);
            add_hit(e, mid, half_w, d, N, dphi, p, vec2(p) + t * d);
        }
        running = top;
    }
}

// Open directions of one uniform azimuth: the environment (exact) or V (SH mode).
void direct_azimuth(vec2 d, vec3 N, float dphi, float hor, float tangent) {
    bool sh_mode = HFGI_SHVIS != 0u;
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
}

// The key light's cap on one azimuth sample (weight wphi): its elevation window
// |ω − ω_c| ≤ δ (src/reference/cap.rs) intersected with the open interval [max(ω_hor, ω_t), π/2],
// minus the spheres' windows (each gap its own Gauss–Legendre nodes).
void cap_azimuth(vec2 d, vec3 N, float wphi, float hor, float tangent) {
    vec3 l = pc.cap_dir.xyz;
    float cos_a = pc.cap_dir.w, sin_a = pc.cap_radiance.w;
    float dl = dot(d, l.xy), cr = d.x * l.y - d.y * l.x;
    float x = sin_a * sin_a - cr * cr;
    if (x < 0.0) return;
    float R = length(vec2(dl, l.z));
    float delta = 2.0 * precise_asin(min(sqrt(x / ((R + cos_a) * 2.0 * R)), 1.0));
    float wc = atan(l.z, dl);
    float lo = max(max(wc - delta, hor), tangent), hi = min(wc + delta, 1.5707963267948966);
    if (hi <= lo) return;
    sphere_windows(d);
    float g0 = lo, g1;
    for (int g = 0; g <= HFGI_SPHERES; ++g) {
        if (!next_gap(g0, hi, HFGI_SPHERES, g1)) break;
        float half_w = 0.5 * (g1 - g0), mid = 0.5 * (g1 + g0);
        for (int e = 0; e < HFGI_NODES; ++e) {
            float om = mid + half_w * hfgi_gauss[e].x;
            vec3 dir = vec3(cos(om) * d, sin(om));
            hfgi_acc[0] += (wphi * half_w * hfgi_gauss[e].y * cos(om) * max(dot(N, dir), 0.0)) * pc.cap_radiance.rgb;
        }
        g0 = g1;
    }
}

// Sphere sample a of this dispatch (cap = 3): sphere k = a / M, its sample a % M, M =
// max(A, local_nodes); the sphere's azimuth samples as a local light's (local_nodes
// Gauss–Legendre ones in the sin u substitution, or the A uniform ones for a cap holding a
// pole). Takes out of the direct integral the environment on (W_k ∩ open) minus the windows of
// spheres j < k.
void sphere_azimuth(ivec2 p, float h0, vec3 N, uint a) {
    uint M = max(pc.azimuths, pc.local_nodes);
    int k = int(a / M);
    uint s = a % M;
    vec3 l = hfgi_sl[k].xyz;
    float sin_a = hfgi_sl[k].w;
    float cos_e = length(l.xy);
    bool pole = cos_e <= sin_a;
    if (s >= (pole ? pc.azimuths : pc.local_nodes)) return;
    float dphi = 6.283185307179586 / float(pc.azimuths);
    vec2 g = hfgi_caps[min(s, pc.local_nodes - 1u)];
    float beta = pole ? 0.0 : precise_asin(min(sin_a / cos_e, 1.0));
    float phi = pole ? (float(s) + 0.5) * dphi : atan(l.y, l.x) + beta * g.x;
    float wphi = pole ? dphi : beta * g.y;
    vec2 d = vec2(cos(phi), sin(phi));
    sphere_windows(d);
    vec2 wk = hfgi_win[k];
    if (wk.x == 4.0) return;
    bool sh_mode = HFGI_SHVIS != 0u;
    float hor = horizon(p, d, h0);
    float tangent = atan(-(N.x * d.x + N.y * d.y), N.z);
    float lo = max(wk.x, sh_mode ? hor : max(hor, tangent)), hi = min(wk.y, 1.5707963267948966);
    if (hi <= lo) return;
    float g0 = lo, g1;
    for (int gi = 0; gi <= HFGI_SPHERES; ++gi) {
        if (!next_gap(g0, hi, k, g1)) break;
        float half_w = 0.5 * (g1 - g0), mid = 0.5 * (g1 + g0);
        for (int e = 0; e < HFGI_NODES; ++e) {
            float om = mid + half_w * hfgi_gauss[e].x;
            float wt = wphi * half_w * hfgi_gauss[e].y * cos(om);
            vec3 dir = vec3(cos(om) * d, sin(om));
            hfgi_sh_eval(dir);
            if (sh_mode) {
                for (int c = 0; c < HFGI_N2; ++c) hfgi_acc[c].x -= wt * hfgi_y[c];
            } else {
                vec3 L = vec3(0.0);
                for (int c = 0; c < HFGI_N2; ++c) L += hfgi_light[c].rgb * hfgi_y[c];
                hfgi_acc[0] -= wt * max(dot(N, dir), 0.0) * L;
            }
        }
        g0 = g1;
    }
}

// ---- Local lights (cap = 2; src/reference/local_truth.rs) ----

// The ray along unit u enters a sphere blocker before the local light (C, q = d² − r²; a
// receiver inside the light: never).
bool local_hidden(vec3 u, vec3 C, float q, bool in_light) {
    if (HFGI_SPHERES == 0 || in_light) return false;
    float b = dot(u, C);
    return sphere_hit(u) < q / (b + sqrt(max(b * b - q, 0.0)));
}

// ∫_a^b (N·ω) cos ω dω on the half-plane of azimuth d, Gauss–Legendre, every node that no
// sphere blocker hides.
float local_open(vec2 d, vec3 N, float a, float b, vec3 C, float q, bool in_light) {
    float half_w = 0.5 * (b - a), mid = 0.5 * (b + a), sum = 0.0;
    for (int e = 0; e < HFGI_NODES; ++e) {
        float om = mid + half_w * hfgi_gauss[e].x;
        vec3 dir = vec3(cos(om) * d, sin(om));
        if (local_hidden(dir, C, q, in_light)) continue;
        sum += half_w * hfgi_gauss[e].y * cos(om) * max(dot(N, dir), 0.0);
    }
    return sum;
}

// Node e of the interval (mid ± half_w) below the horizon, first hit at planar distance t_hit
// texels (< 0: it escapes): its (N·ω) cos ω·weight if it reaches the sphere first. Sphere
// entry: τ = q/(u·C + √((u·C)² − q)), q = d² − r², planar τ·cos ω / s.
float local_node(int e, float mid, float half_w, vec2 d, vec3 N, vec3 C, float q, float t_hit) {
    float om = mid + half_w * hfgi_gauss[e].x;
    float co = cos(om);
    vec3 u = vec3(co * d, sin(om));
    if (t_hit >= 0.0) {
        float b = dot(u, C);
        float t_s = q / (b + sqrt(max(b * b - q, 0.0))) * co / pc.texel_size;
        if (t_hit <= t_s) return 0.0;
    }
    if (local_hidden(u, C, q, false)) return 0.0;
    return half_w * hfgi_gauss[e].y * co * max(dot(N, u), 0.0);
}

// ∫_a^b (N·ω) cos ω dω below the horizon, node by node: the first hits of the ascending nodes
// in one sweep along the ray (as bounce_azimuth), a node counting iff it escapes or its first
// hit lies beyond the sphere entry.
float local_below(ivec2 p, vec2 d, float h0, vec3 N, float a, float b, vec3 C, float q) {
    float half_w = 0.5 * (b - a), mid = 0.5 * (b + a), sum = 0.0;
    int e = 0;
    if (HFGI_MARCH != 0u) {
        float running = -1.5707963267948966;
        uint bound = march_bound(vec2(p), d);
        float hit_t = 0.0;
        uint k = 1u;
        for (; e < HFGI_NODES; ++e) {
            float om = mid + half_w * hfgi_gauss[e].x;
            while (running < om && k <= bound) {
                float t = float(k) * pc.step;
                vec2 s = vec2(p) + t * d;
                if (!inside(s, t)) break;
                k += 1u;
                float w_k = atan((bilinear_h(s) - h0) / (t * pc.texel_size));
                if (w_k > running) { running = w_k; hit_t = t; }
            }
            if (running < om) break;
            sum += local_node(e, mid, half_w, d, N, C, q, hit_t);
        }
    } else {
        Ray r = ray_start(p, d, h0);
        uint bound = piece_bound(r);
        float running = -1e30;
        Piece pq;
        for (uint it = 0u; it < bound && e < HFGI_NODES; ++it) {
            if (!ray_next(r, pq)) break;
            vec2 m = piece_max(pq);
            float top = max(running, m.x);
            for (; e < HFGI_NODES; ++e) {
                float k = tan(mid + half_w * hfgi_gauss[e].x) * pc.texel_size;
                if (k > top) break;
                sum += local_node(e, mid, half_w, d, N, C, q, pq.t0 + first_reach(pq, k, m.y));
            }
            running = top;
        }
    }
    for (; e < HFGI_NODES; ++e) sum += local_node(e, mid, half_w, d, N, C, q, -1.0);
    return sum;
}

// ∫ max(N·ω, 0) dω over the directions of the local light's cap that reach the sphere before
// the height field, for this dispatch's samples [azimuth_first, azimuth_first + azimuth_count)
// of the texel's own count (local_nodes, or the A uniform azimuths for a cap holding a pole).
// Inside the sphere (d ≤ r): the hemisphere toward the centre (+z at d = 0), unblocked.
float local_light(ivec2 p, float h0, vec3 N) {
    // (c_hi − P) + c_lo: the f64 centre relative to the receiver, exact near the surface.
    precise vec3 C = (pc.local_centre.xyz - vec3(vec2(p) * pc.texel_size, h0)) + pc.local_lo.xyz;
    float r = pc.local_centre.w;
    float dist = length(C);
    bool in_sphere = dist <= r;
    vec3 l = dist > 0.0 ? C / dist : vec3(0.0, 0.0, 1.0);
    float q = (dist - r) * (dist + r);
    float sin_a = in_sphere ? 1.0 : r / dist;
    float cos_a = in_sphere ? 0.0 : sqrt(q) / dist;
    float cos_e = length(l.xy);
    bool pole = cos_e <= sin_a;
    uint count = pole ? pc.azimuths : pc.local_nodes;
    float phi_c = atan(l.y, l.x);
    float beta = pole ? 0.0 : precise_asin(min(sin_a / cos_e, 1.0));
    float dphi = 6.283185307179586 / float(pc.azimuths);
    float sum = 0.0;
    uint end = min(pc.azimuth_first + pc.azimuth_count, count);
    for (uint a = pc.azimuth_first; a < end; ++a) {
        vec2 g = hfgi_caps[min(a, pc.local_nodes - 1u)];
        float phi = pole ? (float(a) + 0.5) * dphi : phi_c + beta * g.x;
        float wphi = pole ? dphi : beta * g.y;
        vec2 d = vec2(cos(phi), sin(phi));
        // The cap's elevation window (src/reference/cap.rs cap_window).
        float dl = dot(d, l.xy), cr = d.x * l.y - d.y * l.x;
        float x = sin_a * sin_a - cr * cr;
        if (x < 0.0) continue;
        float R = length(vec2(dl, l.z));
        // Inside: δ = π/2 exactly (the formula's 0/0 where R → 0 loses it in f32).
        float delta = in_sphere ? 1.5707963267948966 : 2.0 * precise_asin(min(sqrt(x / ((R + cos_a) * 2.0 * R)), 1.0));
        float wc = atan(l.z, dl);
        float tangent = atan(-(N.x * d.x + N.y * d.y), N.z);
        float lo = max(wc - delta, tangent), hi = min(wc + delta, 1.5707963267948966);
        if (hi <= lo) continue;
        if (in_sphere) {
            sum += wphi * local_open(d, N, lo, hi, C, q, true);
            continue;
        }
        // Above the horizon every direction escapes; below it, node by node.
        float hor = horizon(p, d, h0);
        float lo_open = max(lo, hor);
        if (hi > lo_open) sum += wphi * local_open(d, N, lo_open, hi, C, q, false);
        float hi_below = min(hi, hor);
        if (hi_below > lo) sum += wphi * local_below(p, d, h0, N, lo, hi_below, C, q);
    }
    return sum;
}

void main() {
    ivec2 p = ivec2(gl_GlobalInvocationID.x, gl_GlobalInvocationID.y + pc.row_offset);
    if (p.x >= int(pc.width) || p.y >= int(pc.height) || gl_GlobalInvocationID.y >= pc.rows) return;
    float h0 = height_at(p);
    vec3 N = normal_at(p);
    // Inside a sphere blocker: nothing, in every mode.
    bool inside = HFGI_SPHERES > 0 && spheres_setup(p, h0);
    if (pc.cap == 2u) {
        uint o = pc.width * pc.height * uint(HFGI_N2) + uint(p.y) * pc.width + uint(p.x);
        vec3 prev = pc.accumulate != 0u ? hfgi_out[o].rgb : vec3(0.0);
        hfgi_out[o] = vec4(prev + (inside ? 0.0 : local_light(p, h0, N)) * pc.cap_radiance.rgb, 0.0);
        return;
    }
    bool sh_mode = HFGI_SHVIS != 0u;
    bool indirect = pc.indirect != 0u;
    for (int k = 0; k < HFGI_N2; ++k) hfgi_acc[k] = vec3(0.0);
    float dphi = 6.283185307179586 / float(pc.azimuths);
    // Azimuths [azimuth_first, azimuth_first + azimuth_count): lavapipe truncates an
    // invocation's loops after 65535 iterations, so the host splits them into chunks.
    uint end = inside ? pc.azimuth_first : pc.azimuth_first + pc.azimuth_count;
    if (pc.cap == 3u) {
        for (uint a = pc.azimuth_first; a < end; ++a) sphere_azimuth(p, h0, N, a);
        end = pc.azimuth_first;
    }
    for (uint a = pc.azimuth_first; a < end; ++a) {
        float phi = pc.cap != 0u ? hfgi_caps[a].x : (float(a) + 0.5) * dphi;
        vec2 d = vec2(cos(phi), sin(phi));
        float hor = horizon(p, d, h0);
        float tangent = atan(-(N.x * d.x + N.y * d.y), N.z);
        if (pc.cap != 0u) {
            cap_azimuth(d, N, hfgi_caps[a].y, hor, tangent);
        } else if (!indirect) {
            direct_azimuth(d, N, dphi, hor, tangent);
        } else if (hor > tangent) {
            bounce_azimuth(p, d, h0, N, dphi, hor, tangent);
        }
    }
    uint base = (uint(p.y) * pc.width + uint(p.x)) * uint(HFGI_N2);
    for (int k = 0; k < (sh_mode ? HFGI_N2 : 1); ++k) {
        vec3 prev = pc.accumulate != 0u ? hfgi_out[base + uint(k)].rgb : vec3(0.0);
        hfgi_out[base + uint(k)] = vec4(prev + hfgi_acc[k], 0.0);
    }
}
