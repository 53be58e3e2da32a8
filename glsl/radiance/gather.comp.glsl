#version 460
// Radiance pyramid, input step (NS09 §5.3; docs/indirect.md §1): level 0 of the channel
// pyramids ← the direct exit radiance (shading planes) for bounce 1. At full resolution later
// bounces need no gather: the indirect shade writes its bounce's exit radiance into level 0
// itself (glsl/shade/direct.comp.glsl, indirect mode). On the working grid (sub-sampled scalar
// pyramid) level 0 averages the cell's field texels, and later bounces gather too, from the
// total plane, where the previous indirect shade left its exit radiance.
// Scalar pyramid: channels 0-2 = diffuse + glossy. Vector pyramid: channels 0-2 = diffuse and
// channel 3 + 3k + c = the incident SH coefficient T_k (colour c) of the direct light.
#include "hfgi_shared.glsl"
layout(local_size_x = HFGI_WORKGROUP, local_size_y = HFGI_WORKGROUP) in;
layout(std430, binding = 0) readonly buffer Shade { uint hfgi_shade[]; };    // shade planes (W×H texels each, hfgi_plane.glsl)
layout(std430, binding = 1) writeonly buffer Levels { float hfgi_radiance_levels[]; };
layout(std430, binding = 2) readonly buffer IncDirect { vec4 hfgi_incident_direct[]; }; // texel × n²
layout(push_constant) uniform Push { hfgi_GatherPush pc; };
#define HFGI_PACKED_PLANES (pc.packed != 0u)
#include "hfgi_plane.glsl"

// Texel `at` (plane · W·H + texel) of the shading planes.
vec3 shade_rgb(uint at) {
    return HFGI_PLANE_LOAD(hfgi_shade, at);
}

// The cell of a `to`-texel row that texel x of a `from`-texel row falls in (texel centres, edges
// aligned; rules::scene::radiance_cell): ⌊(2x + 1)·to / (2·from)⌋.
uint cell_of(uint x, uint from, uint to) {
    return min((2u * x + 1u) * to / (2u * from), to - 1u);
}

// The first texel of a `from`-texel row in cell c of a `to`-texel row: the least x with
// (2x + 1)·to ≥ 2c·from (cell_of(x) ≥ c), i.e. ⌈(2c·from − to) / (2·to)⌉, at least 0.
uint cell_first(uint c, uint from, uint to) {
    uint a = 2u * c * from;
    return a <= to ? 0u : (a - to + 2u * to - 1u) / (2u * to);
}

// The radiance of the shading planes at texel (x, y): pc.plane, plus the direct glossy plane
// for bounce 1 of a glossy scalar pyramid.
vec3 source_rgb(uint x, uint y) {
    uint at = y * pc.src_width + x;
    uint plane = pc.src_width * pc.src_height;
    vec3 c = shade_rgb(pc.plane * plane + at);
    bool glossy = pc.vector == 0u && pc.glossy != 0u && pc.plane == HFGI_PLANE_DIRECT;
    return glossy ? c + shade_rgb(HFGI_PLANE_GLOSSY_DIRECT * plane + at) : c;
}

void main() {
    uvec2 p = gl_GlobalInvocationID.xy;
    if (p.x >= pc.width || p.y >= pc.height) return;
    uint idx = p.y * pc.width + p.x;
    vec3 c;
    if (pc.width == pc.src_width && pc.height == pc.src_height) {
        c = source_rgb(p.x, p.y);
    } else {
        // Level 0 on the working grid: the mean of the field texels in the cell, summed in rows
        // as the twin does (reference::indirect::average_to).
        c = vec3(0.0);
        uint n = 0u;
        for (uint y = cell_first(p.y, pc.src_height, pc.height); y < pc.src_height; ++y) {
            if (cell_of(y, pc.src_height, pc.height) != p.y) break;
            for (uint x = cell_first(p.x, pc.src_width, pc.width); x < pc.src_width; ++x) {
                if (cell_of(x, pc.src_width, pc.width) != p.x) break;
                c += source_rgb(x, y);
                ++n;
            }
        }
        c /= float(max(n, 1u));
    }
    for (uint ch = 0u; ch < 3u; ++ch) hfgi_radiance_levels[ch * pc.channel_stride + idx] = c[ch];
    if (pc.vector != 0u) {
        for (uint k = 0u; k < pc.n2; ++k) {
            vec3 t = hfgi_incident_direct[idx * pc.n2 + k].rgb;
            for (uint ch = 0u; ch < 3u; ++ch) hfgi_radiance_levels[(3u + 3u * k + ch) * pc.channel_stride + idx] = t[ch];
        }
    }
}
