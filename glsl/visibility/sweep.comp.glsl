#version 460
// The far field of the swept horizons (gi.visibility = "sweep"; docs/direct.md §7; Timonen &
// Westerholm 2010). One invocation walks one sweep line of one azimuth from its far end to its
// near end, keeping the upper convex hull of the surface points it crosses as a stack in
// hfgi_hull (amortised O(1) per point); at every receiver column it queries the tangent from its
// own point there to the hull of what lies more than `reach` texels ahead (binary search) and
// writes it, weighted by closeness, into the slot of each receiver beside it: slot 0 from the
// line below (weight 1 − f), slot 1 from the line above (weight f), so that ω_far = slot 0 +
// slot 1 (the visibility pass adds them and takes the near field itself). The CPU twin, with
// the full description, is src/reference/sweep.rs; both take the same steps.
#include "hfgi_shared.glsl"
layout(local_size_x = HFGI_WORKGROUP_1D) in;
// Static modes (frame::shared::static_modes: the push constants' stack_mode and flags; no wrap):
// branches on them are compiled out (docs/performance.md §5).
layout(constant_id = 0) const uint HFGI_STACK = 1u;
layout(constant_id = 1) const uint HFGI_WRAP = 0u;
layout(constant_id = 2) const uint HFGI_STATIC_FLAGS = 0u;

layout(std430, binding = 0) readonly buffer Levels { float hfgi_levels[]; };
layout(std430, binding = 1) readonly buffer Table { hfgi_Level hfgi_table[]; };
layout(std430, binding = 2) readonly buffer Stack { float hfgi_stack[]; };
layout(std430, binding = 3) readonly buffer Samples { vec4 hfgi_samples[]; };  // cos φ, sin φ, lo, hi
layout(std430, binding = 4) writeonly buffer Horizons { float hfgi_horizons[]; }; // [azimuth][receiver][2]
layout(std430, binding = 5) buffer Hull { vec2 hfgi_hull[]; };                    // [line][entry]: (u, h)
layout(std430, binding = 6) readonly buffer HPlanes { uvec4 hfgi_hplanes[]; };     // the height stack's planes (hfgi_pyramid.glsl)
layout(push_constant) uniform Push { hfgi_SweepPush pc; };
#include "hfgi_pyramid.glsl"

const float HFGI_SWEEP_SAME = 1e-5; // reference::sweep::SAME_POINT
const float HFGI_HALF_PI = 1.5707963267948966;

// The azimuth's frame: major axis X (the larger |d| component), minor Y; receivers along both.
struct hfgi_SweepFrame {
    bool swap;   // the major axis is y
    vec2 d;      // (d_X, d_Y)
    float s;     // d_Y / d_X
    uvec2 n;     // level-0 size (major, minor)
    uvec2 work;  // receiver grid (major, minor)
};

float hfgi_sweep_receiver(hfgi_SweepFrame f, uint k, int i) {
    return (float(i) + 0.5) * float(f.n[k]) / float(f.work[k]) - 0.5;
}

float hfgi_sweep_rel(hfgi_SweepFrame f, int a, int b) {
    return hfgi_sweep_receiver(f, 1u, b) - f.s * hfgi_sweep_receiver(f, 0u, a);
}

float hfgi_sweep_slope(vec2 a, vec2 b) {
    return (b.y - a.y) / (b.x - a.x);
}

// Pushes p = (u, h) onto the stack at `base` (every entry ahead of p), popping what p hides.
void hfgi_sweep_push(uint base, inout uint top, vec2 p) {
    while (top > 0u && hfgi_hull[base + top - 1u].x - p.x <= HFGI_SWEEP_SAME) --top;
    while (top >= 2u &&
           hfgi_sweep_slope(p, hfgi_hull[base + top - 2u]) >= hfgi_sweep_slope(p, hfgi_hull[base + top - 1u]))
        --top;
    if (top < pc.hull_capacity) {
        hfgi_hull[base + top] = p;
        ++top;
    }
}

// The horizon angle from q (behind every entry) to the hull: the largest i with
// slope(q, st[i]) ≥ slope(st[i], st[i−1]), by binary search; −π/2 for an empty stack.
float hfgi_sweep_tangent(uint base, uint top, vec2 q) {
    if (top == 0u) return -HFGI_HALF_PI;
    uint lo = 0u, hi = top - 1u;
    while (lo < hi) {
        uint mid = (lo + hi + 1u) / 2u;
        vec2 m = hfgi_hull[base + mid];
        if (hfgi_sweep_slope(q, m) >= hfgi_sweep_slope(m, hfgi_hull[base + mid - 1u])) lo = mid;
        else hi = mid - 1u;
    }
    return atan(hfgi_sweep_slope(q, hfgi_hull[base + lo]) / pc.texel_size);
}

// The point of line j at major coordinate x: (u, h) and its minor coordinate.
vec2 hfgi_sweep_at(hfgi_SweepFrame f, hfgi_Scan scan, int j, float x, out float y) {
    y = float(j) + f.s * x;
    vec2 q = f.swap ? vec2(y, x) : vec2(x, y);
    return vec2(x * f.d.x + y * f.d.y, hfgi_height_at(scan, 0u, q));
}

// Writes line j's far horizon omega at receiver column a into the slots of the receivers beside it.
void hfgi_sweep_contribute(hfgi_SweepFrame f, int j, int a, float omega, uint out_base) {
    float y = float(j) + f.s * hfgi_sweep_receiver(f, 0u, a);
    float wy = float(f.work.y), ny = float(f.n.y);
    int lo = max(int(ceil((y - 0.5) * wy / ny - 0.5)) - 1, 0);
    int hi = min(int(floor((y + 1.5) * wy / ny - 0.5)) + 1, int(f.work.y) - 1);
    for (int b = lo; b <= hi; ++b) {
        float rel = hfgi_sweep_rel(f, a, b);
        int fl = int(floor(rel));
        uint slot;
        float weight;
        if (fl == j) {
            slot = 0u;
            weight = 1.0 - (rel - float(j));
        } else if (fl == j - 1) {
            slot = 1u;
            weight = rel - float(j - 1);
        } else {
            continue;
        }
        uint r = f.swap ? uint(a) * f.work.y + uint(b) : uint(b) * f.work.x + uint(a);
        hfgi_horizons[(out_base + r) * 2u + slot] = weight * omega;
    }
}

// The sweep's state along one line.
struct hfgi_SweepLine {
    int j;
    uint base;     // first stack entry
    uint top;      // stack entries
    int next;      // the receiver column whose query is pending
    int next_step; // −1 or +1: receiver columns in sweep order
    uint out_base; // first receiver of this azimuth in hfgi_horizons (× 2)
};

// Visits the line's point at major coordinate x: first answers the queries of the receiver
// columns it is within `reach` of, then pushes it (inside the band [−1, N_Y] only).
void hfgi_sweep_visit(hfgi_SweepFrame f, hfgi_Scan scan, inout hfgi_SweepLine l, float x) {
    float y, yq;
    vec2 p = hfgi_sweep_at(f, scan, l.j, x, y);
    while (l.next >= 0 && l.next < int(f.work.x)) {
        vec2 q = hfgi_sweep_at(f, scan, l.j, hfgi_sweep_receiver(f, 0u, l.next), yq);
        if (p.x > q.x + pc.reach + HFGI_SWEEP_SAME) break;
        hfgi_sweep_contribute(f, l.j, l.next, hfgi_sweep_tangent(l.base, l.top, q), l.out_base);
        l.next += l.next_step;
    }
    if (y >= -1.0 && y <= float(f.n.y)) hfgi_sweep_push(l.base, l.top, p);
}

void main() {
    uint li = gl_GlobalInvocationID.x, ai = gl_GlobalInvocationID.y;
    if (li >= pc.line_count || ai >= pc.sample_count) return;
    vec2 dd = hfgi_samples[pc.sample_offset + ai].xy;
    hfgi_Scan scan = hfgi_scan_begin(uvec2(0u), uvec2(pc.work_width, pc.work_height), 1u, 0u, pc.texel_size,
                                     HFGI_STACK != 0u, false, HFGI_STATIC_FLAGS, 0u, 1);
    hfgi_SweepFrame f;
    f.swap = abs(dd.y) > abs(dd.x);
    f.d = f.swap ? dd.yx : dd;
    f.s = f.d.y / f.d.x;
    uvec2 n0 = uvec2(scan.n0);
    f.n = f.swap ? n0.yx : n0;
    f.work = f.swap ? uvec2(pc.work_height, pc.work_width) : uvec2(pc.work_width, pc.work_height);
    int wa = int(f.work.x) - 1, wb = int(f.work.y) - 1;
    float r00 = hfgi_sweep_rel(f, 0, 0), r01 = hfgi_sweep_rel(f, 0, wb);
    float r10 = hfgi_sweep_rel(f, wa, 0), r11 = hfgi_sweep_rel(f, wa, wb);
    int j0 = int(floor(min(min(r00, r01), min(r10, r11)))) - 1;
    int j1 = int(floor(max(max(r00, r01), max(r10, r11)))) + 1;
    int j = j0 + int(pc.line_first + li);
    if (j > j1) return;

    float sx = f.d.x > 0.0 ? 1.0 : -1.0;
    float far = sx > 0.0 ? float(f.n.x - 1u) : 0.0;
    hfgi_SweepLine l;
    l.j = j;
    l.base = (ai * pc.line_count + li) * pc.hull_capacity;
    l.top = 0u;
    l.next = sx > 0.0 ? wa : 0;
    l.next_step = sx > 0.0 ? -1 : 1;
    l.out_base = ai * pc.work_width * pc.work_height;
    for (uint k = 0u; k < f.n.x; ++k) {
        float x = far - sx * float(k);
        if (k > 0u) {
            // The row crossing between the previous column and this one, if any.
            float xp = x + sx;
            float ya = float(j) + f.s * xp, yb = float(j) + f.s * x;
            if (floor(ya) != floor(yb)) {
                float yc = max(floor(ya), floor(yb));
                float xc = (yc - float(j)) / f.s;
                float lam = sx * (xp - xc);
                if (yc >= 0.0 && yc <= float(f.n.y - 1u) && lam > 1e-6 && lam < 1.0 - 1e-6)
                    hfgi_sweep_visit(f, scan, l, xc);
            }
        }
        hfgi_sweep_visit(f, scan, l, x);
    }
    // Queries still pending see nothing farther than `reach`.
    while (l.next >= 0 && l.next < int(f.work.x)) {
        float yq;
        vec2 q = hfgi_sweep_at(f, scan, j, hfgi_sweep_receiver(f, 0u, l.next), yq);
        hfgi_sweep_contribute(f, j, l.next, hfgi_sweep_tangent(l.base, l.top, q), l.out_base);
        l.next += l.next_step;
    }
}
