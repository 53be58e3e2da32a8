// hfgi — texel addressing: periodic (wrap) or clamped to the edge.
#ifndef HFGI_ADDRESS_GLSL
#define HFGI_ADDRESS_GLSL

// Index p of a row of n texels, wrapped periodically or clamped. The periodic case avoids the
// integer `%`: lavapipe (llvmpipe) evaluates both sides of this branch on its SIMD lanes and
// x86 has no vector integer division, so `p % n` cost 8 scalar divisions per use even on
// fields without wrap — about a quarter of every scan (docs/performance.md). The float
// quotient is off by at most one for |p| < 2^24 (float(p) exact), which the two corrections
// undo: the result equals ((p % n) + n) % n.
int hfgi_address(int p, int n, bool wrap) {
    if (wrap) {
        int m = p - n * int(floor(float(p) / float(n)));
        m = m < 0 ? m + n : m;
        return m >= n ? m - n : m;
    }
    return clamp(p, 0, n - 1);
}
#endif
