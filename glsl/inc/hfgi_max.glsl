// hfgi — the max pyramid of the level-0 heights (stage `pyramid.max`, docs/accuracy.md §4): a
// conservative bound of the bilinear level-0 surface over any box, one read per box.
//
// Level L has ceil(W/2^L) × ceil(H/2^L) cells; level-0 cell c covers the level-0 positions
// [c, c+1] (per axis, texel centres at integers), level-L cell c the positions [c·2^L, (c+1)·2^L].
// The buffer holds two arrays of levels, L = 0 .. count−1 (until 1×1):
//   m_L[c]  = the largest texel whose bilinear cells touch cell c: m_0[c] = max h[c .. c+1],
//             m_L[c] = max m_{L−1}[2c .. 2c+1] (indices clamped to the level);
//   ov_L[c] = max(m_L[c], m_L[c+1]) (clamped): positions [c·2^L, (c+2)·2^L] in one read.
// A box of extent ≤ 2^L whose lower corner lies in cell c is inside ov_L[c]'s region, and the
// bilinear surface over it (a convex combination of the texels around it) is ≤ ov_L[c].
// Values are relative to level 0's bias (hfgi_fetch). No wrap: the scan does not use the bound
// on periodic fields (the planner leaves the stage out).
// The includer declares `float hfgi_max[]`. Rust twin: frame::pyramid_max::MaxLayout.
#ifndef HFGI_MAX_GLSL
#define HFGI_MAX_GLSL

const uint HFGI_MAX_LEVELS = 17u; // fields of up to 65536 texels per axis

uvec2 hfgi_max_size(uvec2 n0, uint level) {
    return (n0 + ((1u << level) - 1u)) >> level;
}

// Levels until the coarsest has 1 × 1 cells.
uint hfgi_max_count(uvec2 n0) {
    uint c = 1u;
    while (c < HFGI_MAX_LEVELS && any(greaterThan(hfgi_max_size(n0, c - 1u), uvec2(1u)))) ++c;
    return c;
}

// Offset (in floats) of m_level; the ov levels follow all m levels (`overlap`).
uint hfgi_max_offset(uvec2 n0, uint level, bool overlap) {
    uint count = hfgi_max_count(n0);
    uint off = 0u, total = 0u;
    for (uint l = 0u; l < count; ++l) {
        uvec2 s = hfgi_max_size(n0, l);
        if (l == level) off = total;
        total += s.x * s.y;
    }
    return off + (overlap ? total : 0u);
}
#endif
