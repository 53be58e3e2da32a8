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

#endif
