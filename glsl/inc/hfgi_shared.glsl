// hfgi — structs shared between Rust (#[repr(C)] + bytemuck, sizes asserted in
// src/frame/shared.rs) and GLSL. Every symbol is prefixed hfgi_ so host engines can include
// this file without clashes.
#ifndef HFGI_SHARED_GLSL
#define HFGI_SHARED_GLSL

// One level of a pyramid inside its levels buffer (offset in floats, row-major). `source`
// names the buffer: 0 = the height pyramid, 1 = the radiance pyramid (see HFGI_LEVEL_READ in
// hfgi_filter.glsl); a pyramid of C channels has C·n_levels entries, channel c at c·n_levels.
// `bias` is subtracted from every sample read (hfgi_fetch): the height origin z0 on level 0 of
// a renderer's height pyramid, so that every filtered height is relative to z0 (docs/pyramid.md);
// 0 elsewhere. 20 bytes (std430 array stride 20).
struct hfgi_Level {
    uint width;
    uint height;
    uint offset;
    uint source;
    float bias;
};

// Push constants of the pyramid passes (decimate, synthesize, probe). 20 bytes.
struct hfgi_PyramidPush {
    uint level;     // decimate: level written; synthesize: stack levels K | n_v << 16; probe: mode
    uint wrap;      // 1: periodic addressing, 0: clamp to edge
    uint out_width; // working resolution of the stack / probe query count; decimate: levels per channel
    uint out_height;
    float scale;    // synthesize into an f16 stack: the pre-exposure its values are stored at (hfgi_store.glsl)
    uint flags;     // synthesize: 1 = plane 0 holds level 0's own values (raw plane 0)
};

// Push constants of the visibility pass (one dispatch per light set). 64 bytes.
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
    uint flags;         // HFGI_FLAG_* (hfgi_pyramid.glsl; docs/accuracy.md §4)
    uint scan_extent;   // near_steps | far_steps << 16: scan samples before t = 1 texel and past N
    uint horizon_first; // HFGI_FLAG_SWEEP: the sample whose horizons start the horizons buffer
    float sweep_near;   // HFGI_FLAG_SWEEP: texels of the near field marched along each receiver's ray
    uint pad1;
    uint pad2;
};

// Push constants of the line sweep (glsl/visibility/sweep.comp.glsl, gi.visibility = "sweep").
// One dispatch covers azimuth samples [sample_offset, + sample_count) and, of each, the sweep
// lines [line_first, + line_count). 48 bytes.
struct hfgi_SweepPush {
    uint sample_offset; // first azimuth sample (samples buffer); its horizons go to azimuth slot 0
    uint sample_count;
    uint line_first;    // first line of this dispatch (0 = the azimuth's first line)
    uint line_count;    // lines per azimuth in this dispatch (invocations along x)
    uint work_width;    // receiver grid
    uint work_height;
    uint stack_mode;
    uint flags;         // HFGI_FLAG_* (level 0 raw or filtered)
    float texel_size;
    uint hull_capacity; // stack entries per line (2·max(W, H) + 4: every point a line pushes)
    float reach;        // gi.sweep_near: the far field starts this many texels ahead
    uint pad1;
};

// Push constants of the direct shading pass. 128 bytes.
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
    uint accumulate;    // indirect mode: 1 adds this bounce to planes 2 and 5, 0 overwrites
    uint sphere_count;  // sphere slots (binding 10: 2 vec4 per slot), for the key lights' shadows
    uint key_overlap;   // 1: key lights shadowed by the exact cap overlap with the spheres
    float u_scale;      // indirect mode: the pre-exposure U is stored at (hfgi_store.glsl); read as U / u_scale
    uint next_mode;     // indirect mode: the exit radiance → HFGI_NEXT_LEVEL0 (radiance level 0), HFGI_NEXT_TOTAL (total plane), HFGI_NEXT_NONE
    uint pad1;
    uint pad2;
    vec4 camera;        // world position of the camera (xyz), high part
    vec4 specular;      // Phong k_s (rgb)
    vec4 albedo;        // constant albedo (rgb) when albedo_map == 0
    vec4 camera_lo;     // low part: position = camera + camera_lo (f64 split in two f32)
};

// Push constants of the local lights' shading (glsl/shade/local.comp.glsl,
// docs/local-lights.md). 96 bytes.
struct hfgi_LocalPush {
    uint width;         // full resolution
    uint height;
    uint light_count;   // local-light slots (hfgi.local.lights holds 3 vec4 per slot)
    uint azimuths;      // gi.local_light_azimuths: azimuth samples per light and receiver
    float texel_size;
    uint albedo_map;    // 1: per-texel albedo buffer
    uint glossy;        // 1: the material has a Phong lobe
    float exponent;     // Phong exponent S
    vec4 albedo;        // constant albedo (rgb) when albedo_map == 0
    vec4 specular;      // Phong k_s (rgb)
    vec4 camera;        // the camera (glossy view vector), high f32 part
    vec4 camera_lo;     // … and the low part
};

// Push constants of the sphere blockers' visibility (glsl/visibility/blockers.comp.glsl,
// docs/blockers.md). 112 bytes.
struct hfgi_BlockerPush {
    uint width;         // full resolution (the heights)
    uint height;
    uint work_width;    // receiver grid
    uint work_height;
    uint sphere_count;  // sphere slots (hfgi.blockers.spheres holds 2 vec4 per slot)
    uint quad_count;    // nodes of the exponentiation's quadrature (hfgi.blockers.quad)
    float texel_size;
    float log_eps;      // ln ε (gi.blocker_epsilon)
    uint ratio;         // 1: ratio attenuation r/d (gi.blocker_ratio)
    uint env_offset;    // log mode: first float of the environment set's V in the visibility buffer
    float ol_step;      // spacing of the OL tables in ‖f̂‖
    uint triple_count;  // primal mode: entries of the SH triple-product table
    vec4 camera;        // log_brdf: the camera (Phong lobe's view vector), high f32 part
    vec4 camera_lo;     // … and the low part
    float log_phong[8]; // log_brdf: √(4π/(2l+1)) · ZH of the log-SH Phong lobe (HFGI_MAX_SH_ORDER bands)
};

// Push constants of the indirect scan (indirect.scan). 80 bytes.
struct hfgi_IndirectPush {
    uint work_width;      // receiver grid
    uint work_height;
    uint wrap;
    uint level_step;      // k_v
    uint level_bias;      // k_v * o_v
    float texel_size;
    uint stack_mode;      // 1: stack (heights and radiance), 0: true pyramids
    uint sample_count;    // azimuths m
    uint radiance_levels; // n_u, levels per channel of the radiance pyramid
    uint radiance_stack;  // 1: the radiance pyramid is a stack
    uint flags;           // HFGI_FLAG_* (hfgi_pyramid.glsl; docs/accuracy.md §4)
    uint scan_extent;     // near_steps | far_steps << 16, as in hfgi_VisibilityPush
    vec4 specular;        // Phong k_s (vector pyramid)
    uint sample_offset;   // first azimuth of this dispatch (frame::shared::azimuth_chunks)
    uint probes;          // gi.radial_probes
    uint radiance_planes; // radiance stack planes per channel (its finest levels; stack mode)
    float radiance_scale; // the pre-exposure of the f16 radiance stack and U (hfgi_store.glsl): read / it, store × it
};

// Push constants of radiance.gather. 48 bytes.
struct hfgi_GatherPush {
    uint width;          // level 0 of the radiance pyramid (the working grid when sub-sampled)
    uint height;
    uint channel_stride; // floats per channel in the radiance levels buffer
    uint vector;         // 1: channels 0-2 diffuse only, then 3 n² incident SH channels
    uint n2;
    uint glossy;         // 1: the shading buffer has the glossy planes (direct glossy: plane 4)
    uint src_width;      // the shading planes (the field)
    uint src_height;
    uint plane;          // the shading plane read: HFGI_PLANE_DIRECT, or HFGI_PLANE_TOTAL (later bounces, working grid)
    uint packed;         // 1: RGBE planes (hfgi_plane.glsl)
    uint pad1;
    uint pad2;
};

// Push constants of the view raster pass (glsl/view/raster.vert.glsl). 112 bytes.
struct hfgi_ViewPush {
    mat4 view_proj;     // eye-relative world → clip (Vulkan: y down, reversed depth 1 at near → 0 at far)
    uint width;         // height-field size (vertices per row)
    uint height;
    float texel_size;   // world units per texel
    uint packed;        // 1: RGBE shading planes (hfgi_plane.glsl)
    vec4 eye;           // eye position, high part (xyz)
    vec4 eye_lo;        // low part: eye = eye + eye_lo (an f64 position in two f32)
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

// Push constants of the ground-truth reference (glsl/reference/truth.comp.glsl). 128 bytes.
struct hfgi_TruthPush {
    uint width;
    uint height;
    uint wrap;
    uint azimuths;      // A, uniformly spaced
    float step;         // march step, texels (march = 1 only)
    float texel_size;
    uint sh_visibility; // 1: project to SH (V or U), 0: exact irradiance
    uint indirect;      // 1: blocked directions with the source radiance, 0: open directions
    uint row_offset;    // first row of this dispatch
    uint rows;          // rows in this dispatch
    uint azimuth_first; // azimuths [first, first + count) of `azimuths` (cap = 0) or samples
    uint azimuth_count; //   [first, first + count) of the cap buffer (cap = 1) in this dispatch
    uint march;         // 1: march at `step`, 0: exact intersection with the bilinear patches
    uint cap;           // 1: this dispatch integrates the key light cap_* (exact, direct);
                        // 2: the local light local_* (both variants, direct);
                        // 3: the sphere blockers, flattened samples (both variants, direct)
    uint accumulate;    // 1: add to the output, 0: overwrite it (a pass's first dispatch)
    uint local_nodes;   // local light, sphere: azimuth samples of a cap holding no pole (cap buffer [0, local_nodes))
    vec4 cap_dir;       // key light: unit direction (xyz), cos α (w)
    vec4 cap_radiance;  // key light: rgb radiance, sin α (w); local light: rgb radiance
    vec4 local_centre;  // local light: centre, high f32 part (xyz); radius (w)
    vec4 local_lo;      // local light: centre − high part (xyz), f64 split in two f32
};

#endif
