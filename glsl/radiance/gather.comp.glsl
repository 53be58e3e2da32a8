#version 460
// Radiance pyramid, input step (NS09 §5.3; docs/indirect.md §1): level 0 of the three channel
// pyramids ← the previous bounce's exit radiance. Bounce 1 reads the direct light (diffuse +
// glossy toward the camera: the scalar shade pyramid); later bounces read the bounce buffer.
#include "hfgi_shared.glsl"
layout(local_size_x = 8, local_size_y = 8) in;
layout(std430, binding = 0) readonly buffer Shade { vec4 hfgi_shade[]; };   // shade planes (W×H each)
layout(std430, binding = 1) readonly buffer Bounce { vec4 hfgi_bounce[]; }; // last bounce (W×H)
layout(std430, binding = 2) writeonly buffer Levels { float hfgi_radiance_levels[]; };
layout(push_constant) uniform Push { hfgi_GatherPush pc; };

void main() {
    uvec2 p = gl_GlobalInvocationID.xy;
    if (p.x >= pc.width || p.y >= pc.height) return;
    uint idx = p.y * pc.width + p.x;
    uint plane = pc.width * pc.height;
    vec3 c = pc.from_bounce != 0u ? hfgi_bounce[idx].rgb : hfgi_shade[plane + idx].rgb + hfgi_shade[4u * plane + idx].rgb;
    for (uint ch = 0u; ch < 3u; ++ch) hfgi_radiance_levels[ch * pc.channel_stride + idx] = c[ch];
}
