#version 460
// Radiance pyramid, input step of bounce 1 (NS09 §5.3; docs/indirect.md §1): level 0 of the
// channel pyramids ← the direct exit radiance (shading planes). Later bounces need no gather:
// the indirect shade writes its bounce's exit radiance into level 0 itself
// (glsl/shade/direct.comp.glsl, indirect mode).
// Scalar pyramid: channels 0-2 = diffuse + glossy. Vector pyramid: channels 0-2 = diffuse and
// channel 3 + 3k + c = the incident SH coefficient T_k (colour c) of the direct light.
#include "hfgi_shared.glsl"
layout(local_size_x = HFGI_WORKGROUP, local_size_y = HFGI_WORKGROUP) in;
layout(std430, binding = 0) readonly buffer Shade { float hfgi_shade[]; };   // shade planes (W×H rgb each)
layout(std430, binding = 1) writeonly buffer Levels { float hfgi_radiance_levels[]; };
layout(std430, binding = 2) readonly buffer IncDirect { vec4 hfgi_incident_direct[]; }; // texel × n²
layout(push_constant) uniform Push { hfgi_GatherPush pc; };

// Texel `at` (plane · W·H + texel) of the shading planes.
vec3 shade_rgb(uint at) {
    return vec3(hfgi_shade[3u * at], hfgi_shade[3u * at + 1u], hfgi_shade[3u * at + 2u]);
}

void main() {
    uvec2 p = gl_GlobalInvocationID.xy;
    if (p.x >= pc.width || p.y >= pc.height) return;
    uint idx = p.y * pc.width + p.x;
    uint plane = pc.width * pc.height;
    vec3 diffuse = shade_rgb(HFGI_PLANE_DIRECT * plane + idx);
    // The direct glossy plane exists only for a glossy surface (pc.glossy).
    vec3 c = pc.vector != 0u || pc.glossy == 0u ? diffuse : diffuse + shade_rgb(HFGI_PLANE_GLOSSY_DIRECT * plane + idx);
    for (uint ch = 0u; ch < 3u; ++ch) hfgi_radiance_levels[ch * pc.channel_stride + idx] = c[ch];
    if (pc.vector != 0u) {
        for (uint k = 0u; k < pc.n2; ++k) {
            vec3 t = hfgi_incident_direct[idx * pc.n2 + k].rgb;
            for (uint ch = 0u; ch < 3u; ++ch) hfgi_radiance_levels[(3u + 3u * k + ch) * pc.channel_stride + idx] = t[ch];
        }
    }
}
