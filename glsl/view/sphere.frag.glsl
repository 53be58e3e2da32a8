#version 460
// View spheres (docs/view.md §6): diffuse albedo/π · E(N), unshadowed. E = the environment's
// irradiance from its first 9 SH coefficients (pre-multiplied on the host by the clamped-cosine
// factors Â_0 = π, Â_1 = 2π/3, Â_2 = π/4, so E(N) = Σ_k env[k] y_k(N), CONVENTIONS.md real SH in
// Cartesian form) plus every key light's L·2π(1 − cos α)·max(N·d, 0) (pre-multiplied too).
// Not clamped (CONVENTIONS.md: the SH lighting is used as it is). Alpha 1.
const float HFGI_PI = 3.14159265358979;

struct hfgi_ViewKeyLight {
    vec4 direction;   // unit direction toward the light (xyz)
    vec4 irradiance;  // L·2π(1 − cos α) (rgb): irradiance on a surface facing the light
};

// = view::SphereLighting (std430): counts.x = key lights.
layout(std430, binding = 1) readonly buffer Light {
    uvec4 hfgi_counts;
    vec4 hfgi_env[9];
    hfgi_ViewKeyLight hfgi_keys[];
};

layout(location = 0) in vec3 hfgi_normal;
layout(location = 1) flat in vec3 hfgi_albedo;
layout(location = 0) out vec4 hfgi_out;

void main() {
    vec3 n = normalize(hfgi_normal);
    float x = n.x, y = n.y, z = n.z;
    float b[9] = float[9](0.28209479177, 0.48860251190 * y, 0.48860251190 * z, 0.48860251190 * x,
                          1.09254843059 * x * y, 1.09254843059 * y * z, 0.31539156525 * (3.0 * z * z - 1.0),
                          1.09254843059 * x * z, 0.54627421529 * (x * x - y * y));
    vec3 e = vec3(0.0);
    for (int k = 0; k < 9; k++) {
        e += hfgi_env[k].rgb * b[k];
    }
    for (uint i = 0u; i < hfgi_counts.x; i++) {
        e += hfgi_keys[i].irradiance.rgb * max(dot(n, hfgi_keys[i].direction.xyz), 0.0);
    }
    hfgi_out = vec4(hfgi_albedo * e / HFGI_PI, 1.0);
}
