#version 460
// Radiance pyramid, input step (NS09 §5.3; docs/indirect.md §1): level 0 of the channel
// pyramids ← the previous bounce's exit radiance. Bounce 1 reads the direct light (shading
// planes), later bounces the bounce buffer (rgb per texel, already the sum below: the indirect
// shade writes it, glsl/shade/direct.comp.glsl).
// Scalar pyramid: channels 0-2 = diffuse + glossy. Vector pyramid: channels 0-2 = diffuse and
// channel 3 + 3k + c = the incident SH coefficient T_k (colour c) of the same bounce.
#include "hfgi_shared.glsl"
layout(local_size_x = HFGI_WORKGROUP, local_size_y = HFGI_WORKGROUP) in;
layout(std430, binding = 0) readonly buffer Shade { float hfgi_shade[]; };   // shade planes (W×H rgb each)
layout(std430, binding = 1) readonly buffer Bounce { float hfgi_bounce[]; }; // rgb per texel
layout(std430, binding = 2) writeonly buffer Levels { float hfgi_radiance_levels[]; };
layout(std430, binding = 3) readonly buffer IncDirect { vec4 hfgi_incident_direct[]; }; // texel × n²
layout(std430, binding = 4) readonly buffer IncBounce { vec4 hfgi_incident_bounce[]; }; // texel × n²
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
    vec3 c;
    if (pc.from_bounce != 0u) {
        c = vec3(hfgi_bounce[3u * idx], hfgi_bounce[3u * idx + 1u], hfgi_bounce[3u * idx + 2u]);
    } else {
        vec3 diffuse = shade_rgb(HFGI_PLANE_DIRECT * plane + idx);
        // The direct glossy plane exists only for a glossy surface (pc.glossy).
        c = pc.vector != 0u || pc.glossy == 0u ? diffuse : diffuse + shade_rgb(HFGI_PLANE_GLOSSY_DIRECT * plane + idx);
    }
    for (uint ch = 0u; ch < 3u; ++ch) hfgi_radiance_levels[ch * pc.channel_stride + idx] = c[ch];
    if (pc.vector != 0u) {
        for (uint k = 0u; k < pc.n2; ++k) {
            vec3 t = pc.from_bounce != 0u ? hfgi_incident_bounce[idx * pc.n2 + k].rgb : hfgi_incident_direct[idx * pc.n2 + k].rgb;
            for (uint ch = 0u; ch < 3u; ++ch) hfgi_radiance_levels[(3u + 3u * k + ch) * pc.channel_stride + idx] = t[ch];
        }
    }
}
