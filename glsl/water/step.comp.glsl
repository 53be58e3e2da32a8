#version 460
// Water surface, one simulation step (stage `water.step`; docs/dynamic.md).
//
// Model: the course notes, ch. 3 §3.7 ("GPU-Based water simulation for dynamic puddle
// rendering"): the water surface is a thin elastic membrane on a lattice; each lattice point
// stores its current and its previous height (fig. 26), and is pulled by its four direct
// neighbours (fig. 27). With surface tension as the only force this is the 2-D wave equation
//     dz/dt = v,   dv/dt = c^2 (d2z/dx2 + d2z/dy2)
// (z the displacement, v the velocity of the cell, x and y the lattice coordinates), which the
// notes integrate with Euler steps in a texture feedback loop. The explicit step used here is
// semi-implicit (symplectic) Euler on that PDE, with damping:
//     v^{n+1} = (1 - delta) v^n + k L(z^n),    z^{n+1} = z^n + v^{n+1} + D^{n+1},
//     L(z)_ij = (z_{i-1,j} - z_ij) + (z_{i+1,j} - z_ij) + (z_{i,j-1} - z_ij) + (z_{i,j+1} - z_ij),
//     k = (c dt/dx)^2 = speed^2, v in texel heights per step.
// With v^n = z^n - z^{n-1} it is exactly the notes' two-level form (fig. 26 stores the current
// and the previous height), z^{n+1} = z^n + (1 - delta)(z^n - z^{n-1}) + k L(z^n) + D, which the
// CPU twin (src/reference/water.rs) runs (there a drop is written into both the current and the
// previous height, so that v = z^n - z^{n-1} excludes it); carrying v instead of z^{n-1} keeps the f32 rounding
// at the scale of v and of the neighbour differences, not of z (see docs/dynamic.md, volume).
// Stable iff 0 < k < (2 - delta)/4 (checked on the host, WaterParams::validate).
// Raindrops D (the notes' "wave seeding": a dampened wave per drop rendered into the simulation
// texture) arrive in push constants and displace the surface at rest (zero velocity): the
// profile (1 - t^2)^2 (1 - 4 t^2), t = r/R < 1, a crest and a trough ring of zero total volume,
// so rain adds (almost) no water and does not drift the mean level.
//
// Buffers: (z^n, v^n) interleaved is read (z with its 4 neighbours), (z^{n+1}, v^{n+1}) is
// written to the other buffer (ping-pong); the caller's heights buffer receives
// rest_level + scale * z^{n+1} at offset 0, row-major.
#include "hfgi_shared.glsl"
layout(local_size_x = HFGI_WORKGROUP, local_size_y = HFGI_WORKGROUP) in;
layout(std430, binding = 0) readonly buffer Src { vec2 hfgi_src[]; };  // (z^n, v^n)
layout(std430, binding = 1) writeonly buffer Dst { vec2 hfgi_dst[]; }; // (z^{n+1}, v^{n+1})
layout(std430, binding = 2) writeonly buffer Heights { float hfgi_heights_out[]; };
layout(push_constant) uniform Push { hfgi_WaterPush pc; };

// Neighbour index along one axis: clamp to edge (reflective, zero flux) or wrap (periodic).
int hfgi_water_addr(int p, int n) {
    if (pc.wrap != 0u) {
        return (p + n) % n;
    }
    return clamp(p, 0, n - 1);
}

// Signed distance along one axis, the shortest way round when periodic.
float hfgi_water_delta(float d, float n) {
    if (pc.wrap != 0u) {
        d -= n * floor(d / n + 0.5);
    }
    return d;
}

void main() {
    ivec2 p = ivec2(gl_GlobalInvocationID.xy);
    int w = int(pc.width);
    int h = int(pc.height);
    if (p.x >= w || p.y >= h) return;
    int i = p.y * w + p.x;
    vec2 zv = hfgi_src[i];
    float z = zv.x;
    float zl = hfgi_src[p.y * w + hfgi_water_addr(p.x - 1, w)].x;
    float zr = hfgi_src[p.y * w + hfgi_water_addr(p.x + 1, w)].x;
    float zd = hfgi_src[hfgi_water_addr(p.y - 1, h) * w + p.x].x;
    float zu = hfgi_src[hfgi_water_addr(p.y + 1, h) * w + p.x].x;
    float lap = ((zl - z) + (zr - z)) + ((zd - z) + (zu - z));
    float v = pc.retain * zv.y + pc.k * lap;
    float drop_sum = 0.0;
    for (uint d = 0u; d < pc.drop_count; ++d) {
        vec4 drop = pc.drops[d];
        float dx = hfgi_water_delta(float(p.x) - drop.x, float(w));
        float dy = hfgi_water_delta(float(p.y) - drop.y, float(h));
        float t2 = (dx * dx + dy * dy) / (drop.w * drop.w);
        if (t2 < 1.0) {
            float e = 1.0 - t2;
            drop_sum += drop.z * e * e * (1.0 - 4.0 * t2);
        }
    }
    float next = z + v + drop_sum;
    hfgi_dst[i] = vec2(next, v);
    hfgi_heights_out[i] = pc.rest_level + pc.scale * next;
}
