#version 460
// View spheres (docs/view.md §6): every live sphere blocker as a UV sphere of
// HFGI_SPHERE_STACKS × HFGI_SPHERE_SLICES quads (two triangles each, six vertices per quad,
// no index buffer), generated from the vertex index; one instance per sphere. Positions are
// eye-relative like glsl/view/raster.vert.glsl: ((centre − eye) − eye_lo) + (centre_lo + r·n).
#include "hfgi_shared.glsl"

const uint HFGI_SPHERE_STACKS = 16u;  // = view::SPHERE_STACKS
const uint HFGI_SPHERE_SLICES = 32u;  // = view::SPHERE_SLICES
const float HFGI_PI = 3.14159265358979;

// One sphere (std430, 48 bytes; = view::GpuSphere).
struct hfgi_ViewSphere {
    vec4 center_radius;  // centre, high f32 part (xyz); radius (w)
    vec4 center_lo;      // centre, low part (xyz): centre = hi + lo (an f64 position in two f32)
    vec4 albedo;         // diffuse albedo (rgb)
};

layout(std430, binding = 0) readonly buffer Spheres { hfgi_ViewSphere hfgi_spheres[]; };
layout(push_constant) uniform Push { hfgi_ViewPush pc; };

layout(location = 0) out vec3 hfgi_normal;
layout(location = 1) flat out vec3 hfgi_albedo;
layout(location = 2) flat out vec4 hfgi_center_radius;  // for the field's shadow (sphere.frag)
layout(location = 3) flat out vec3 hfgi_center_lo;

// Corner k of a quad's two triangles, as (stack step, slice step).
const uint HFGI_DS[6] = uint[6](0u, 1u, 1u, 0u, 1u, 0u);
const uint HFGI_DL[6] = uint[6](0u, 0u, 1u, 0u, 1u, 1u);

void main() {
    hfgi_ViewSphere sp = hfgi_spheres[gl_InstanceIndex];
    uint v = uint(gl_VertexIndex);
    uint quad = v / 6u;
    uint corner = v % 6u;
    uint s = quad / HFGI_SPHERE_SLICES + HFGI_DS[corner];
    uint l = (quad % HFGI_SPHERE_SLICES + HFGI_DL[corner]) % HFGI_SPHERE_SLICES;
    float theta = HFGI_PI * float(s) / float(HFGI_SPHERE_STACKS);
    float phi = 2.0 * HFGI_PI * float(l) / float(HFGI_SPHERE_SLICES);
    vec3 n = vec3(sin(theta) * cos(phi), sin(theta) * sin(phi), cos(theta));
    // Exact poles (sin π is not 0 in f32).
    if (s == 0u) {
        n = vec3(0.0, 0.0, 1.0);
    } else if (s == HFGI_SPHERE_STACKS) {
        n = vec3(0.0, 0.0, -1.0);
    }
    hfgi_normal = n;
    hfgi_albedo = sp.albedo.rgb;
    hfgi_center_radius = sp.center_radius;
    hfgi_center_lo = sp.center_lo.xyz;
    precise vec3 rel = ((sp.center_radius.xyz - pc.eye.xyz) - pc.eye_lo.xyz) + (sp.center_lo.xyz + sp.center_radius.w * n);
    gl_Position = pc.view_proj * vec4(rel, 1.0);
}
