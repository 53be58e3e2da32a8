// hfgi — structs shared between Rust (#[repr(C)] + bytemuck, sizes asserted in
// src/frame/shared.rs) and GLSL. Every symbol is prefixed hfgi_ so host engines can include
// this file without clashes.
#ifndef HFGI_SHARED_GLSL
#define HFGI_SHARED_GLSL

// One level of the height pyramid inside the levels buffer (offset in floats, row-major).
struct hfgi_Level {
    uint width;
    uint height;
    uint offset;
    uint pad;
};

// Push constants of the pyramid passes (decimate, synthesize, probe). 16 bytes.
struct hfgi_PyramidPush {
    uint level;     // decimate: level written; synthesize: unused (z = level); probe: mode
    uint wrap;      // 1: periodic addressing, 0: clamp to edge
    uint out_width; // working resolution of the stack / probe query count
    uint out_height;
};

// Push constants of the visibility pass (one dispatch per light set). 48 bytes.
struct hfgi_VisibilityPush {
    uint sample_offset; // first azimuth sample of the set in the samples / A-matrix buffers
    uint sample_count;
    uint out_offset;    // first float of the set's V vectors in the output buffer
    uint wrap;
    uint work_width;    // receiver grid (working resolution)
    uint work_height;
    uint level_step;    // k_v
    uint level_bias;    // k_v * o_v: scan sample i reads level max(i - level_bias, 0)
    float texel_size;   // world units per texel
    uint stack_mode;    // 1: stack, 0: true pyramid
    uint pad0;
    uint pad1;
};

// Push constants of the direct shading pass. 96 bytes.
struct hfgi_ShadePush {
    uint width;         // full resolution
    uint height;
    uint work_width;    // receiver grid
    uint work_height;
    uint set_count;     // light sets (environment, key lights)
    uint wrap;
    uint glossy;        // 1: material has a Phong lobe
    uint albedo_map;    // 1: per-texel albedo buffer
    float texel_size;
    float pad0;
    float pad1;
    float pad2;
    vec4 camera;        // world position of the camera (xyz)
    vec4 specular;      // Phong k_s (rgb)
    vec4 albedo;        // constant albedo (rgb) when albedo_map == 0
};

// Push constants of the water step (glsl/water/step.comp.glsl). 96 bytes.
struct hfgi_WaterPush {
    uint width;
    uint height;
    uint wrap;          // 1: periodic neighbours, 0: clamp to edge (reflective wall)
    uint drop_count;    // drops[0 .. drop_count) fall in this step
    float k;            // Laplacian weight k = speed^2 (Courant number squared)
    float retain;       // 1 - damping
    float rest_level;   // output height = rest_level + scale * z
    float scale;
    vec4 drops[4];      // (x, y, amplitude, radius), texels
};

#endif
