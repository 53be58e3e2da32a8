// hfgi — height lookups in the pyramid, the way every scanning pass does them.
// The includer declares `float hfgi_levels[]`, `hfgi_Level hfgi_table[]`, `float hfgi_stack[]`
// and `uvec4 hfgi_hplanes[]` (in pyramid mode, bind the levels buffer as the stack and any
// buffer as the planes), or with HFGI_TEXELS their texel views (below), then includes this file.
// Positions are in level-0 texel units.
#ifndef HFGI_PYRAMID_GLSL
#define HFGI_PYRAMID_GLSL
#include "hfgi_filter.glsl"

// How a height-stack value and a plane's entry are read: with HFGI_TEXELS (hfgi_filter.glsl)
// through texel views, `uniform usamplerBuffer hfgi_stack_texels` (f32 bits) and
// `hfgi_hplanes_texels` (uvec4), which the includer declares instead of the storage buffers.
#ifdef HFGI_TEXELS
#define HFGI_STACK_AT(i) HFGI_TEXEL_F(hfgi_stack_texels, i)
#define HFGI_HPLANE(i) texelFetch(hfgi_hplanes_texels, int(i))
#else
#define HFGI_STACK_AT(i) hfgi_stack[i]
#define HFGI_HPLANE(i) hfgi_hplanes[i]
#endif

// Bilinear value of height-stack plane `plane` at level-0 position p0. The planes' sizes and
// offsets come from `uvec4 hfgi_hplanes[]`, which the includer declares (PyramidLayout::
// stack_planes: width, height, offset; a coarse level's plane is the working grid halved while
// it keeps the level's texels). The radiance stack has its own planes table
// (glsl/indirect/scan.comp.glsl reads it).
float hfgi_stack_bilinear(uint plane, vec2 p0, vec2 n0, bool wrap) {
    uvec4 pl = HFGI_HPLANE(plane);
    vec2 pw = (p0 + 0.5) * vec2(pl.xy) / n0 - 0.5;
    vec2 fl = floor(pw);
    vec2 f = pw - fl;
    ivec2 i = ivec2(fl);
    int w = int(pl.x), h = int(pl.y);
    uint x0 = uint(hfgi_address(i.x, w, wrap)), x1 = uint(hfgi_address(i.x + 1, w, wrap));
    uint r0 = pl.z + uint(hfgi_address(i.y, h, wrap)) * pl.x;
    uint r1 = pl.z + uint(hfgi_address(i.y + 1, h, wrap)) * pl.x;
    return hfgi_bilerp(HFGI_STACK_AT(r0 + x0), HFGI_STACK_AT(r0 + x1), HFGI_STACK_AT(r1 + x0), HFGI_STACK_AT(r1 + x1), f);
}

// Flags of hfgi_VisibilityPush.flags / hfgi_IndirectPush.flags (docs/accuracy.md §4; the Rust
// twins are `frame::shared::FLAG_*`).
const uint HFGI_FLAG_RAW_LEVEL0 = 1u; // level 0 is the bilinear surface itself, not its B-spline
const uint HFGI_FLAG_HORIZON_SAMPLES = 2u; // ω_max = largest sample, not eq. 17's spline maximum
const uint HFGI_FLAG_TANGENT = 4u; // ω_min = the exact tangent elevation, not −asin(N·d)
const uint HFGI_FLAG_ACCUMULATE = 8u; // add to the output (a later azimuth chunk of the same set)
const uint HFGI_FLAG_MAX_BOUND = 16u; // the indirect scan stops where the max pyramid's top rules the rest out
const uint HFGI_FLAG_SWEEP = 32u; // visibility: ω_max from the line sweep's horizons, no scan
// The height (radiance) stack's plane 0 holds level 0's own values (HeightPyramid::
// set_raw_plane0): with HFGI_FLAG_RAW_LEVEL0, level 0 is read through the stack like every other
// level, one read path per sample (docs/performance.md §17).
const uint HFGI_FLAG_RAW_PLANE0 = 64u;
const uint HFGI_FLAG_RAW_RPLANE0 = 128u;
const uint HFGI_FLAG_TANGENT_CLIP = 256u; // visibility: the window starts no lower than the tangent elevation
// Flags that change between the dispatches of one pipeline (frame::shared::DYNAMIC_FLAGS). The
// others, and the storage mode and wrap, are fixed at pipeline creation: the scanning shaders
// take them from specialization constants (frame::shared::static_modes), because lavapipe runs
// both sides of a branch even on a uniform value (docs/performance.md §5).
const uint HFGI_DYNAMIC_FLAGS = HFGI_FLAG_ACCUMULATE | HFGI_FLAG_MAX_BOUND;

// Value of table entry `plane` (level `l`, of a pyramid whose level 0 is `base`) at level-0
// position p0. `raw`: the unfiltered level as a bilinear surface (gi.level0 = "bilinear"; only
// meaningful on level 0, whose texels are the samples themselves). Otherwise, stack mode (the
// height stack only): bilinear on the synthesized plane; pyramid mode: the cubic B-spline of
// the decimated level, on the fly.
float hfgi_pyramid_at(hfgi_Level base, hfgi_Level l, uint plane, vec2 p0, bool stack_mode, bool wrap,
                      bool raw) {
    vec2 n0 = vec2(float(base.width), float(base.height));
    if (raw) return hfgi_bilinear_at(l, hfgi_rescale(p0, n0, l), wrap);
    if (stack_mode) return hfgi_stack_bilinear(plane, p0, n0, wrap); // the height stack's
    return hfgi_bspline_at(l, hfgi_rescale(p0, n0, l), wrap);
}

// The horizon scan of docs/direct.md §1–2 (eq. 14–16), shared by the visibility and the indirect
// passes: the receiver of grid cell r and, per azimuth, its samples.
struct hfgi_Scan {
    vec2 p;           // receiver, level-0 texels (§1)
    vec2 n0;          // level-0 size
    uint level_step;  // k
    uint level_bias;  // k·o
    float texel_size;
    bool stack_mode;
    bool wrap;
    bool raw0;        // HFGI_FLAG_RAW_LEVEL0, read from level 0 itself (not through a raw plane 0)
    int first;        // first sample index: −near_steps (sub-texel samples, docs/accuracy.md §4)
    int end;          // one past the last: n_v + far_steps (samples beyond max(W, H) texels)
    hfgi_Level l0;    // hfgi_table[0], read once per receiver
};

// Height at level `level` (hfgi_table) and level-0 position p0.
// Heights are source 0 (hfgi_scan_begin sets s.l0.source so): a shader reading two pyramids
// reads the heights' buffers without a per-sample choice or table read.
float hfgi_height_at(hfgi_Scan s, uint level, vec2 p0) {
    if (s.raw0 && level == 0u) return hfgi_bilinear_at(s.l0, hfgi_rescale(p0, s.n0, s.l0), s.wrap);
    if (s.stack_mode) return hfgi_stack_bilinear(level, p0, s.n0, s.wrap);
    return hfgi_pyramid_at(s.l0, hfgi_table[level], level, p0, s.stack_mode, s.wrap, false);
}

// Pyramid level read by scan sample i (NS09 §5.2 level offset; docs/direct.md §2): the level
// whose texel matches the step t_i, biased k·o levels finer ("sharper long-range shadows"),
// clamped to the pyramid (sub-texel samples read level 0, samples past max(W, H) the coarsest).
uint hfgi_scan_level(int i, uint bias, int n_v) {
    return uint(clamp(i - int(bias), 0, n_v - 1));
}

// Levels a scan reads: sample i < s.end reads level clamp(i − bias, 0, n_v − 1), so levels
// 0 … end − bias − 1 (at most n_v). A renderer's stack holds just these planes
// (frame::pyramid::scan_stack_levels, the same formula): no other level may be read from it.
int hfgi_scan_levels(hfgi_Scan s, int n_v) {
    return clamp(s.end - int(s.level_bias), 1, n_v);
}

// `extent` = near_steps | far_steps << 16 (hfgi_VisibilityPush.scan_extent).
hfgi_Scan hfgi_scan_begin(uvec2 r, uvec2 work, uint level_step, uint level_bias, float texel_size, bool stack_mode,
                          bool wrap, uint flags, uint extent, int n_v) {
    hfgi_Level l0 = hfgi_table[0];
    l0.source = 0u; // the heights
    vec2 n0 = vec2(float(l0.width), float(l0.height));
    vec2 p = (vec2(r) + 0.5) * n0 / vec2(work) - 0.5;
    return hfgi_Scan(p, n0, level_step, level_bias, texel_size, stack_mode, wrap,
                     (flags & (HFGI_FLAG_RAW_LEVEL0 | HFGI_FLAG_RAW_PLANE0)) == HFGI_FLAG_RAW_LEVEL0,
                     -int(extent & 0xffffu), n_v + int(extent >> 16), l0);
}

// The near-field limit t → 0 of the blocking angle's tangent (with near_steps > 0; docs/accuracy.md §4):
// the slope of the bilinear level-0 surface at p along d, in the cell the ray enters (the
// reference's first piece starts there). False where the ray leaves the domain at once.
bool hfgi_scan_limit_slope(hfgi_Scan s, vec2 d, out float slope) {
    slope = -3.402823466e38;
    vec2 e = s.p + 1e-3 * d;
    if (!s.wrap && (e.x < 0.0 || e.y < 0.0 || e.x > s.n0.x - 1.0 || e.y > s.n0.y - 1.0)) return false;
    hfgi_Level l0 = hfgi_table[0];
    ivec2 c = ivec2(floor(e));
    vec2 f = s.p - vec2(c);
    float h00 = hfgi_fetch(l0, c, s.wrap), h10 = hfgi_fetch(l0, c + ivec2(1, 0), s.wrap);
    float h01 = hfgi_fetch(l0, c + ivec2(0, 1), s.wrap), h11 = hfgi_fetch(l0, c + ivec2(1, 1), s.wrap);
    float fx = (h10 - h00) * (1.0 - f.y) + (h11 - h01) * f.y;
    float fy = (h01 - h00) * (1.0 - f.x) + (h11 - h10) * f.x;
    slope = (fx * d.x + fy * d.y) / s.texel_size;
    return true;
}

// The same as an angle, atan of the slope (−π/2 where the ray leaves the domain at once).
bool hfgi_scan_limit(hfgi_Scan s, vec2 d, out float omega) {
    float slope;
    bool inside = hfgi_scan_limit_slope(s, d, slope);
    omega = inside ? atan(slope) : -1.5707963267948966;
    return inside;
}

// The receiver's height at pyramid level `level` (eq. 15 compares f_L(q) with f_L(p)).
float hfgi_scan_base(hfgi_Scan s, uint level) {
    return hfgi_height_at(s, level, s.p);
}

// Step t_i = N·2^(−(n_v−1−i)/k) texels of sample i of n_v (eq. 14; i < 0: inside the first
// texel; i ≥ n_v: past N, toward the far corner).
float hfgi_scan_t(hfgi_Scan s, int i, int n_v) {
    return max(s.n0.x, s.n0.y) * exp2(-float(n_v - 1 - i) / float(s.level_step));
}

// t_{i+1} / t_i = 2^(1/k) (eq. 14): a scan walking its ladder in order takes t_first from
// hfgi_scan_t once and multiplies by this per sample, not an exp2 per sample (5% of the indirect
// scan on lavapipe, docs/performance.md §12; after 40 steps t differs by < 3e-6 relative).
float hfgi_scan_ratio(hfgi_Scan s) {
    return exp2(1.0 / float(s.level_step));
}

// Whether level-0 position q is still in the domain (always with wrap), with a 1e-3 texel
// tolerance so that rays along the border do not depend on rounding (docs/direct.md §2).
bool hfgi_scan_inside(hfgi_Scan s, vec2 q) {
    return s.wrap || !(q.x < -1e-3 || q.y < -1e-3 || q.x > s.n0.x - 1.0 + 1e-3 || q.y > s.n0.y - 1.0 + 1e-3);
}

// Sample i of n_v at step t along direction d: q = p + t·d, level hfgi_scan_level, and the slope
// tan ω_i = Δh / t of eq. 15 against `base` (the receiver at that level): a scan compares
// slopes and takes the atan only where a sample matters. False once q has left the domain.
bool hfgi_scan_slope(hfgi_Scan s, int i, float t, int n_v, vec2 d, float base, out vec2 q, out float slope) {
    q = s.p + t * d;
    slope = 0.0;
    if (!hfgi_scan_inside(s, q)) return false;
    float dh = hfgi_height_at(s, hfgi_scan_level(i, s.level_bias, n_v), q) - base;
    slope = dh / (t * s.texel_size);
    return true;
}

// The blocking angle ω_i = atan(slope) of sample i at step t (eq. 15).
bool hfgi_scan_sample(hfgi_Scan s, int i, float t, int n_v, vec2 d, float base, out vec2 q, out float omega) {
    bool ok = hfgi_scan_slope(s, i, t, n_v, d, base, q, omega);
    omega = atan(omega);
    return ok;
}

// CONVENTIONS.md height gradient at texel t of level 0 (one-sided at the border, periodic with
// wrap), per unit of `texel` (the texel size). Twin: reference::tangent::receiver_normal.
vec2 hfgi_gradient(ivec2 t, bool wrap, float texel) {
    hfgi_Level l0 = hfgi_table[0];
    int w = int(l0.width), h = int(l0.height);
    t = ivec2(hfgi_address(t.x, w, wrap), hfgi_address(t.y, h, wrap));
    ivec2 a = wrap ? t - 1 : max(t - 1, ivec2(0));
    ivec2 b = wrap ? t + 1 : min(t + 1, ivec2(w - 1, h - 1));
    float hx = hfgi_fetch(l0, ivec2(b.x, t.y), wrap) - hfgi_fetch(l0, ivec2(a.x, t.y), wrap);
    float hy = hfgi_fetch(l0, ivec2(t.x, b.y), wrap) - hfgi_fetch(l0, ivec2(t.x, a.y), wrap);
    return vec2(hx / (float(b.x - a.x) * texel), hy / (float(b.y - a.y) * texel));
}

// Normal at level-0 position q: the gradients of the four surrounding texels, bilinear, then
// normalised (docs/indirect.md §2; a receiver's — the indirect scan's ω_min, the visibility's
// tangent clip — and, in vector mode, a casting point's).
vec3 hfgi_normal_at(vec2 q, bool wrap, float texel) {
    vec2 fl = floor(q);
    vec2 f = q - fl;
    ivec2 b = ivec2(fl);
    vec2 g = (1.0 - f.x) * (1.0 - f.y) * hfgi_gradient(b, wrap, texel) + f.x * (1.0 - f.y) * hfgi_gradient(b + ivec2(1, 0), wrap, texel)
           + (1.0 - f.x) * f.y * hfgi_gradient(b + ivec2(0, 1), wrap, texel) + f.x * f.y * hfgi_gradient(b + ivec2(1, 1), wrap, texel);
    return normalize(vec3(-g, 1.0));
}

// The tangent elevation atan2(−N·d, N_z) of normal N along unit azimuth d (CONVENTIONS.md): the
// indirect scan's ω_min, the visibility's tangent clip. Twin: reference::tangent::omega_min.
float hfgi_tangent_elevation(vec3 N, vec2 d) {
    return atan(-dot(N.xy, d), N.z);
}

#endif
