// hfgi — which receiver an invocation of a scanning pass computes (docs/performance.md §18).
#ifndef HFGI_RECEIVER_GLSL
#define HFGI_RECEIVER_GLSL
#if HFGI_WORKGROUP != 8
#error "hfgi_receiver assumes 8 × 8 workgroups"
#endif

// The receiver (working-grid cell) of this invocation of a 2D dispatch of 8 × 8 workgroups.
// Each 8 consecutive invocations — lavapipe's SIMD lanes, which run in lock-step, and a quarter
// of a GPU warp — take a 4 × 2 block of the workgroup's tile instead of a row of 8: receivers
// closer together walk their rays more alike, so fewer lanes idle. A permutation of the tile:
// every cell is one invocation's, and the caller's bounds test is unchanged.
uvec2 hfgi_receiver() {
    uint li = gl_LocalInvocationIndex, group = li >> 3u, lane = li & 7u;
    uvec2 cell = uvec2((group & 1u) * 4u + (lane & 3u), (group >> 1u) * 2u + (lane >> 2u));
    return gl_WorkGroupID.xy * 8u + cell;
}
#endif
