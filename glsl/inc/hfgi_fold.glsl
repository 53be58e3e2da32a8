// hfgi — the folded wedge matrices A_j as the scans read them (frame::shared::gpu_fold;
// docs/performance.md §22). Needs the specialization constants HFGI_N (SH order n), HFGI_NE
// (values per azimuth) and HFGI_FOLD_SIZE (vec4 texels per azimuth) declared before the include.
// Legendre basis (HFGI_NE = 2n + 1): row (l, m) of A_j is non-zero only on the Fourier moments
// of math::elevation::fold_support — g_l|m| = cos^{|m|+1}ω · P_l^{(|m|)}(sin ω) has degree l + 1
// and the parity of l − |m|, so the cosines (value k, the width at k = 0) or the sines (value
// n + k) of orders l + 1, l − 1, … —, and the host stores only those, row after row, each
// azimuth's block padded to whole vec4s. NLP basis (HFGI_NE = n): every row whole, each padded
// to HFGI_NQ vec4s.
#ifndef HFGI_FOLD_GLSL
#define HFGI_FOLD_GLSL

const bool hfgi_fold_sparse = HFGI_NE != HFGI_N;
const int HFGI_NQ = (HFGI_NE + 3) / 4; // vec4s per row of a dense fold

// Whether row (l, m) holds the cosines (else the sines).
bool hfgi_fold_even(int l, int m) {
    return ((l - abs(m)) & 1) == 0;
}

// Entries of row (l, m) in a sparse fold.
int hfgi_fold_entries(int l, int m) {
    return hfgi_fold_even(l, m) ? (l + 1) / 2 + 1 : l / 2 + 1;
}

// The value of the azimuth's moments that entry s of row (l, m) multiplies (orders l + 1,
// l − 1, …: math::elevation::fold_support's order).
int hfgi_fold_moment(int l, int m, int s) {
    int k = l + 1 - 2 * s;
    return hfgi_fold_even(l, m) ? k : HFGI_N + k;
}

// vec4 texels per azimuth: HFGI_FOLD_SIZE, a specialization constant the including shader
// declares (frame::shared::fold_texels; a loop here, evaluated per azimuth, cost lavapipe more
// than the fold it serves).

// acc[k] += (A_j u)_k for the rows k < rows (eq. 19–21 folded): `u` the azimuth's values (type
// T: float or vec3), A_j's texels from `base` of the R32G32B32A32 view `tex`. The sparse fold's
// loops have constant bounds after specialization and are unrolled: every entry's texel,
// component and moment are constants (the four entries of a texel share one fetch).
#define HFGI_FOLD(T, tex, base, u, acc, rows)                                                              \
    if (hfgi_fold_sparse) {                                                                                \
        int hfgi_at = 0;                                                                                   \
        [[unroll]] for (int hfgi_k = 0; hfgi_k < (rows); ++hfgi_k) {                                       \
            int hfgi_l = int(sqrt(float(hfgi_k) + 0.5)), hfgi_m = hfgi_k - hfgi_l * (hfgi_l + 1);           \
            T hfgi_s = T(0.0);                                                                             \
            [[unroll]] for (int hfgi_e = 0; hfgi_e < HFGI_N / 2 + 1; ++hfgi_e) {                            \
                if (hfgi_e < hfgi_fold_entries(hfgi_l, hfgi_m)) {                                          \
                    vec4 hfgi_a = uintBitsToFloat(texelFetch(tex, int(base) + hfgi_at / 4));                \
                    hfgi_s += hfgi_a[hfgi_at % 4] * u[hfgi_fold_moment(hfgi_l, hfgi_m, hfgi_e)];             \
                    ++hfgi_at;                                                                             \
                }                                                                                          \
            }                                                                                              \
            acc[hfgi_k] += hfgi_s;                                                                         \
        }                                                                                                  \
    } else {                                                                                               \
        for (int hfgi_k = 0; hfgi_k < (rows); ++hfgi_k) {                                                  \
            T hfgi_s = T(0.0);                                                                             \
            for (int hfgi_q = 0; hfgi_q < HFGI_NQ; ++hfgi_q) {                                             \
                vec4 hfgi_a = uintBitsToFloat(texelFetch(tex, int(base) + hfgi_k * HFGI_NQ + hfgi_q));      \
                for (int hfgi_c = 0; hfgi_c < 4; ++hfgi_c) {                                               \
                    if (4 * hfgi_q + hfgi_c < HFGI_NE) hfgi_s += hfgi_a[hfgi_c] * u[4 * hfgi_q + hfgi_c];   \
                }                                                                                          \
            }                                                                                              \
            acc[hfgi_k] += hfgi_s;                                                                         \
        }                                                                                                  \
    }

#endif
