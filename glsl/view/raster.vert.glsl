#version 460
// View raster (docs/view.md): one vertex per height sample at world (i·s, j·s, H[j][i]),
// generated from the vertex index. The draw is instanced per quad row: instance j covers
// rows j and j+1, and its index buffer (built once) addresses v = row·W + i with row ∈ {0, 1}.
// The colour is the shading texture's total layer at the same texel (plane 0 of the buffer).
#include "hfgi_shared.glsl"

layout(std430, binding = 0) readonly buffer Heights { float hfgi_heights[]; };  // W×H f32, row-major
layout(std430, binding = 1) readonly buffer Shading { uint hfgi_shading[]; };   // plane 0 = total (hfgi_plane.glsl)
layout(push_constant) uniform Push { hfgi_ViewPush pc; };
#define HFGI_PACKED_PLANES (pc.packed != 0u)
#include "hfgi_plane.glsl"

layout(location = 0) out vec3 hfgi_colour;

void main() {
    uint v = uint(gl_VertexIndex);
    uint i = v % pc.width;
    uint j = uint(gl_InstanceIndex) + v / pc.width;
    uint t = j * pc.width + i;
    vec3 p = vec3(float(i) * pc.texel_size, float(j) * pc.texel_size, hfgi_heights[t]);
    hfgi_colour = HFGI_PLANE_LOAD(hfgi_shading, t);
    // Eye-relative ("relative to eye") transform: (p − eye) − eye_lo is exact to f32 of the
    // result even when p is near 1e7, where p itself times a world → clip matrix would cancel.
    precise vec3 rel = (p - pc.eye.xyz) - pc.eye_lo.xyz;
    gl_Position = pc.view_proj * vec4(rel, 1.0);
}
