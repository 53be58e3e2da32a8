// hfgi — real SH evaluation for any order HFGI_N (CONVENTIONS: orthonormal, no Condon–Shortley
// phase, index k = l(l+1)+m). The includer declares the spec constant HFGI_N and a buffer
// holding `float hfgi_klm[HFGI_MAX_SH_ORDER²]`: K_l^|m| (times √2 for m ≠ 0) at index l(l+1)+m.
#ifndef HFGI_SH_GLSL
#define HFGI_SH_GLSL

// The result array (private to each invocation).
float hfgi_y[HFGI_N * HFGI_N];

// hfgi_y[k] = y_k(d) for k < n², d a unit vector. Uses Q_l^m = P_l^m / sin^m θ (a polynomial in
// z, recurrence (l−m) Q_l^m = (2l−1) z Q_{l−1}^m − (l+m−1) Q_{l−2}^m) and
// (x + iy)^m = sin^m θ · (cos mφ + i sin mφ).
void hfgi_sh_eval(vec3 d) {
    float cm = 1.0;  // Re (x+iy)^m
    float sm = 0.0;  // Im (x+iy)^m
    float qmm = 1.0; // Q_m^m = (2m−1)!!
    for (int m = 0; m < HFGI_N; ++m) {
        float qa = qmm; // Q_{l−1}^m
        float qb = 0.0; // Q_{l−2}^m
        for (int l = m; l < HFGI_N; ++l) {
            float q = qmm;
            if (l > m) {
                q = (float(2 * l - 1) * d.z * qa - float(l + m - 1) * qb) / float(l - m);
                qb = qa;
                qa = q;
            }
            int c = l * (l + 1);
            if (m == 0) {
                hfgi_y[c] = hfgi_klm[c] * q;
            } else {
                hfgi_y[c + m] = hfgi_klm[c + m] * q * cm;
                hfgi_y[c - m] = hfgi_klm[c + m] * q * sm;
            }
        }
        float cn = cm * d.x - sm * d.y;
        sm = cm * d.y + sm * d.x;
        cm = cn;
        qmm *= float(2 * m + 1);
    }
}

#endif
