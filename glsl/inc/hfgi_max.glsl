// hfgi — the max reduction of the level-0 heights (stage `pyramid.max`, docs/accuracy.md §4):
// level L has ceil(W/8^(L+1)) × ceil(H/8^(L+1)) cells; m_0[c] is the largest texel of the
// 8 × 8 block c, m_L[c] the largest of the 8 × 8 cells 8c … of level L − 1 (indices clamped),
// until one cell: the field's largest height, which the indirect scan's early stop reads.
// Values are relative to level 0's bias (hfgi_fetch).
// The includer declares `float hfgi_max[]`. Rust twin: reference::max::MaxLayout.
#ifndef HFGI_MAX_GLSL
#define HFGI_MAX_GLSL

const uint HFGI_MAX_LEVELS = 6u; // fields of up to 8^6 texels per axis
const uint HFGI_MAX_BLOCK = 8u;

uvec2 hfgi_max_size(uvec2 n0, uint level) {
    uint b = 1u << (3u * (level + 1u)); // 8^(level + 1)
    return (n0 + (b - 1u)) / b;
}

// Levels until the coarsest has 1 × 1 cells.
uint hfgi_max_count(uvec2 n0) {
    uint c = 1u;
    while (c < HFGI_MAX_LEVELS && any(greaterThan(hfgi_max_size(n0, c - 1u), uvec2(1u)))) ++c;
    return c;
}

// Offset (in floats) of m_level.
uint hfgi_max_offset(uvec2 n0, uint level) {
    uint off = 0u;
    for (uint l = 0u; l < level; ++l) {
        uvec2 s = hfgi_max_size(n0, l);
        off += s.x * s.y;
    }
    return off;
}

// The early stop of the scans (docs/accuracy.md §4, docs/performance.md §18, §34), with
// `bounded` (the pass reads the max pyramid), `gmax` its top and `bmin` the lowest base a
// sample's height is compared with: no position at step t or farther has a slope above
// (gmax − bmin)/(t·texel), so once that is ≤ `slope` (the horizon so far) nothing there can rise
// above it and the ray ends. Conservative: the horizon (and the casting set) is the same.
bool hfgi_nothing_beyond(bool bounded, float gmax, float bmin, float slope, float t, float texel) {
    return bounded && gmax - bmin <= slope * (t * texel);
}

#ifdef hfgi_max
// The field's largest level-0 height (relative to level 0's bias): the reduction's 1 × 1 top,
// read once per receiver by a scan that defines hfgi_max(i) as its buffer's value i.
float hfgi_max_top(uvec2 n0) {
    return hfgi_max(hfgi_max_offset(n0, hfgi_max_count(n0) - 1u));
}
#endif
#endif
