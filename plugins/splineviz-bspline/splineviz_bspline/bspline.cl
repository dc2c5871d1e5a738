// The tricubic B-spline kernel family of the splineviz-bspline plugin: the first root of the
// C2 tricubic B-spline interpolant along a ray in one unit cell, prepended to splineviz's
// raycast.cl (MODEL_CUSTOM, see splineviz.compute.raycast.CustomKernelFamily).
//
// data holds the spline's coefficients with one mirrored layer (the float32 device samples of
// TricubicBSplineFamily); data[base] is coefficient (i-1, j-1, k-1) of the cell (i, j, k), and
// the cell reads the 4 x 4 x 4 coefficients base + (a, b, c), a, b, c = 0..3 (CELL_REACH 3).
// Their min/max bound the spline on the cell (the B-spline weights are >= 0 and sum to 1);
// the ray caster's octree holds the much tighter range of the cell's Bernstein coefficients
// (bounds.cl, TricubicBSplineFamily.allocate), so the cells this function sees are few.
//
// Along the ray p + r d in the cell each axis' weights are cubics in r, so s - iso is a
// polynomial of degree 9. Its Bernstein coefficients on [0, len] come from the blossoms of
// the weights (degree 3 per axis) multiplied in scaled Bernstein form (products of scaled
// Bernstein coefficients are convolutions); the first root is isolated by subdividing the
// Bernstein polygon (a piece whose polygon keeps one sign has no root; one sign change means
// exactly one root, then bisected), so no root is missed, however thin the feature.

#define BS_DEGREE 9
// levels of interval halving before a piece that still straddles iso counts as a touching
// root (the Bernstein polygon is then within ~1e-8 of the polynomial, relative)
#define BS_MAX_DEPTH 16
// bisection steps of an isolated root: float resolution of the cell's segment
#define BS_BISECT 24

// Power coefficients (1, t, t^2, t^3) of the uniform cubic B-spline weights of the
// coefficient offsets -1, 0, 1, 2 on t in [0, 1].
__constant float bs_power[4][4] = {
    {1.0f / 6.0f, -0.5f, 0.5f, -1.0f / 6.0f},
    {4.0f / 6.0f, 0.0f, -1.0f, 0.5f},
    {1.0f / 6.0f, 0.5f, 0.5f, -0.5f},
    {0.0f, 0.0f, 0.0f, 1.0f / 6.0f},
};

// the scaled Bernstein coefficients of a sextic are binomial(6, i) times its coefficients
// (the eighth component is unused: 0)
#define BS_UNSCALE6 ((float8)(1.0f, 1.0f / 6.0f, 1.0f / 15.0f, 1.0f / 20.0f, 1.0f / 15.0f, \
                              1.0f / 6.0f, 1.0f, 0.0f))

// binomial(9, k)
__constant float bs_binom9[10] = {1.0f, 9.0f, 36.0f, 84.0f, 126.0f, 126.0f, 84.0f, 36.0f,
                                  9.0f, 1.0f};

// Scaled Bernstein coefficients (binomial(3, i) times the Bernstein coefficients, i = 0..3 in
// the components) on u in [0, 1] of the 4 weights along t = t0 + u (t1 - t0): the blossom
// values w[t0^(3-i), t1^i] of w(t) = a + b t + c t^2 + e t^3, w[x,y,z] = a + b (x+y+z)/3
// + c (xy+xz+yz)/3 + e xyz.
inline void bs_axis(float t0, float t1, float4 *w)
{
    const float4 s1 = (float4)(t0, (2.0f * t0 + t1) / 3.0f, (t0 + 2.0f * t1) / 3.0f, t1);
    const float4 s2 = (float4)(t0 * t0, (t0 * t0 + 2.0f * t0 * t1) / 3.0f,
                               (2.0f * t0 * t1 + t1 * t1) / 3.0f, t1 * t1);
    const float4 s3 = (float4)(t0 * t0 * t0, t0 * t0 * t1, t0 * t1 * t1, t1 * t1 * t1);
    const float4 scale = (float4)(1.0f, 3.0f, 3.0f, 1.0f);
    for (int m = 0; m < 4; ++m)
        w[m] = scale * (bs_power[m][0] + bs_power[m][1] * s1 + bs_power[m][2] * s2
                        + bs_power[m][3] * s3);
}

// Weights and their first and second derivatives of the offsets -1..2 at t.
inline void bs_weights(float t, float *w, float *dw, float *d2w)
{
    const float s = 1.0f - t, t2 = t * t;
    w[0] = s * s * s / 6.0f;
    w[1] = (3.0f * t2 * t - 6.0f * t2 + 4.0f) / 6.0f;
    w[2] = (-3.0f * t2 * t + 3.0f * t2 + 3.0f * t + 1.0f) / 6.0f;
    w[3] = t2 * t / 6.0f;
    dw[0] = -0.5f * s * s;
    dw[1] = 0.5f * (3.0f * t2 - 4.0f * t);
    dw[2] = 0.5f * (-3.0f * t2 + 2.0f * t + 1.0f);
    dw[3] = 0.5f * t2;
    d2w[0] = s;
    d2w[1] = 3.0f * t - 2.0f;
    d2w[2] = 1.0f - 3.0f * t;
    d2w[3] = t;
}

// The sign of the Bernstein polynomial of degree 9 with scaled coefficients a (binomial(9, i)
// times its Bernstein coefficients) at u in (0, 1): sum a_i u^i (1-u)^(9-i) is (1-u)^9 times a
// polynomial in u / (1-u), or u^9 times one in (1-u) / u, evaluated by Horner in whichever
// ratio is <= 1. Its rounding error is bounded by that of de Casteljau (both are a few ulps of
// sum |a_i| u^i (1-u)^(9-i)) at a fifth of the work, and the positive power needs no computing.
inline float bs_sign_at(const float *a, float u)
{
    float h;
    if (u <= 0.5f) {
        const float t = u / (1.0f - u);
        h = a[BS_DEGREE];
        for (int i = BS_DEGREE - 1; i >= 0; --i) h = h * t + a[i];
    } else {
        const float t = (1.0f - u) / u;
        h = a[0];
        for (int i = 1; i <= BS_DEGREE; ++i) h = h * t + a[i];
    }
    return h;
}

// The Bernstein coefficients of b on [u0, u1] of [0, 1] (two de Casteljau subdivisions, each
// a convex combination: stable).
inline void bs_piece(const float *b, float u0, float u1, float *out)
{
    // the part [u0, 1]: right[j] is the last entry of row n - j of the triangle at u0
    float row[BS_DEGREE + 1], right[BS_DEGREE + 1];
    for (int i = 0; i <= BS_DEGREE; ++i) row[i] = b[i];
    right[BS_DEGREE] = row[BS_DEGREE];
    for (int r = 1; r <= BS_DEGREE; ++r) {
        for (int i = 0; i <= BS_DEGREE - r; ++i) row[i] = row[i] + u0 * (row[i + 1] - row[i]);
        right[BS_DEGREE - r] = row[BS_DEGREE - r];
    }
    // its part [0, v], v = (u1 - u0) / (1 - u0): out[r] is the first entry of row r
    const float v = u0 < 1.0f ? (u1 - u0) / (1.0f - u0) : 0.0f;
    out[0] = right[0];
    for (int r = 1; r <= BS_DEGREE; ++r) {
        for (int i = 0; i <= BS_DEGREE - r; ++i)
            right[i] = right[i] + v * (right[i + 1] - right[i]);
        out[r] = right[0];
    }
}

// Sign changes of the Bernstein polygon b (zeros skipped); 2 stands for "2 or more".
inline int bs_sign_changes(const float *b)
{
    int n = 0, last = 0;
    for (int i = 0; i <= BS_DEGREE; ++i) {
        const int sg = b[i] > 0.0f ? 1 : (b[i] < 0.0f ? -1 : 0);
        if (sg != 0) {
            if (last != 0 && sg != last && ++n >= 2) return 2;
            last = sg;
        }
    }
    return n;
}

// The first root in [0, 1] of the Bernstein polynomial b of degree 9; -1 if none. The
// pieces [k 2^-d, (k+1) 2^-d] are visited left to right, depth first, without a stack: a
// piece whose polygon has no sign change is skipped (no root), one with a single change and
// endpoints of opposite signs holds exactly one root (bisected), any other is halved.
inline float bs_first_root(const float *b)
{
    int d = 0, k = 0;
    float c[BS_DEGREE + 1];
    while (true) {
        const float scale = 1.0f / (float)(1 << d);
        const float u0 = k * scale, u1 = (k + 1) * scale;
        if (d == 0) {
            for (int i = 0; i <= BS_DEGREE; ++i) c[i] = b[i];
        } else {
            bs_piece(b, u0, u1, c);
        }
        if (c[0] == 0.0f) return u0;
        const int v = bs_sign_changes(c);
        const bool ends = (c[0] < 0.0f) != (c[BS_DEGREE] < 0.0f) && c[BS_DEGREE] != 0.0f;
        if (ends && (v == 1 || d == BS_MAX_DEPTH)) {
            // bisection on the piece's own coefficients (float resolution of [0, 1])
            float lo = 0.0f, hi = 1.0f;
            const bool neg = c[0] < 0.0f;
            float a[BS_DEGREE + 1];
            for (int i = 0; i <= BS_DEGREE; ++i) a[i] = c[i] * bs_binom9[i];
            for (int it = 0; it < BS_BISECT - d; ++it) {
                const float m = 0.5f * (lo + hi);
                const float fm = bs_sign_at(a, m);
                if (fm == 0.0f) { lo = hi = m; break; }
                if ((fm < 0.0f) == neg) lo = m; else hi = m;
            }
            return u0 + 0.5f * (lo + hi) * (u1 - u0);
        }
        if (v >= 1 && d == BS_MAX_DEPTH) {
            // the polygon still straddles iso on a piece of 2^-16: a touching (double) root
            if (c[BS_DEGREE] == 0.0f) return u1;
            return 0.5f * (u0 + u1);
        }
        if (v >= 1) {
            ++d;
            k <<= 1;
            continue;
        }
        // no root here: the next piece to the right, climbing from right children
        while (k & 1) {
            k >>= 1;
            --d;
        }
        if (d == 0) return -1.0f;
        ++k;
    }
}

// The first root r in [0, len] of s(cell + p + r d) = iso (s: the tricubic B-spline on the
// cell whose first coefficient is data[base]); -1 if none. *grad gets the index-space gradient
// at the root and, when want_hess, hess[0..5] the Hessian (xx, yy, zz, xy, xz, yz).
float custom_cell_root(__global const DATA_T *data, offset_t base, int SY, int SZ,
                       float3 p, float3 d, float len, float iso, float3 *grad,
                       int want_hess, float *hess)
{
    const int sx = SY * SZ;
    // the restriction to the segment in scaled Bernstein form, axis by axis (z, y, x):
    // products of scaled Bernstein forms are convolutions of their coefficient vectors
    float4 wx[4], wy[4], wz[4];
    bs_axis(p.x, p.x + len * d.x, wx);
    bs_axis(p.y, p.y + len * d.y, wy);
    bs_axis(p.z, p.z + len * d.z, wz);
    // g[a][b]: the coefficient row (a, b, .) along z restricted to the segment
    float4 g[4][4];
    for (int a = 0; a < 4; ++a)
        for (int b = 0; b < 4; ++b) {
            const offset_t row = base + a * sx + b * SZ;
            g[a][b] = (float)data[row] * wz[0] + (float)data[row + 1] * wz[1]
                      + (float)data[row + 2] * wz[2] + (float)data[row + 3] * wz[3];
        }
    // h[a]: the x-slice a restricted to the segment (degree 6 in scaled Bernstein form, 7 of
    // the 8 components used). f is a convex combination of them (the x weights are >= 0 and
    // sum to 1), so the range of their Bernstein coefficients bounds f on the segment: a
    // rejection before the degree-9 product (comparisons, not fmin/fmax: PoCL calls those out
    // of line)
    float8 h[4];
    float8 hlo = (float8)(INFINITY), hhi = (float8)(-INFINITY);
    for (int a = 0; a < 4; ++a) {
        h[a] = (float8)(0.0f);
        for (int b = 0; b < 4; ++b) {
            const float4 ga = g[a][b];
            const float4 w = wy[b];
            h[a] += ga.s0 * (float8)(w, 0.0f, 0.0f, 0.0f, 0.0f)
                    + ga.s1 * (float8)(0.0f, w, 0.0f, 0.0f, 0.0f)
                    + ga.s2 * (float8)(0.0f, 0.0f, w, 0.0f, 0.0f)
                    + ga.s3 * (float8)(0.0f, 0.0f, 0.0f, w, 0.0f);
        }
        const float8 u = h[a] * BS_UNSCALE6;
        hlo = select(hlo, u, u < hlo);
        hhi = select(hhi, u, u > hhi);
    }
    if (!((hlo.s0 <= iso || hlo.s1 <= iso || hlo.s2 <= iso || hlo.s3 <= iso
           || hlo.s4 <= iso || hlo.s5 <= iso || hlo.s6 <= iso)
          && (hhi.s0 >= iso || hhi.s1 >= iso || hhi.s2 >= iso || hhi.s3 >= iso
              || hhi.s4 >= iso || hhi.s5 >= iso || hhi.s6 >= iso)))
        return -1.0f;
    float16 acc = (float16)(0.0f);
    for (int a = 0; a < 4; ++a) {
        const float8 ha = h[a];
        const float4 w = wx[a];
        const float4 z4 = (float4)(0.0f);
        acc += ha.s0 * (float16)(w, z4, z4, z4)
               + ha.s1 * (float16)(0.0f, w, z4, z4, z4.s012)
               + ha.s2 * (float16)(0.0f, 0.0f, w, z4, z4, z4.s01)
               + ha.s3 * (float16)(0.0f, 0.0f, 0.0f, w, z4, z4, z4.s0)
               + ha.s4 * (float16)(z4, w, z4, z4)
               + ha.s5 * (float16)(z4, 0.0f, w, z4, z4.s012)
               + ha.s6 * (float16)(z4, 0.0f, 0.0f, w, z4, z4.s01);
    }
    float f[BS_DEGREE + 1] = {acc.s0, acc.s1, acc.s2, acc.s3, acc.s4,
                              acc.s5, acc.s6, acc.s7, acc.s8, acc.s9};
    bool below = false, above = false;
    for (int k = 0; k <= BS_DEGREE; ++k) {
        f[k] = f[k] / bs_binom9[k] - iso;
        below |= f[k] <= 0.0f;
        above |= f[k] >= 0.0f;
    }
    if (!(below && above)) return -1.0f;
    const float u = bs_first_root(f);
    if (u < 0.0f) return -1.0f;
    const float r = u * len;
    // gradient and Hessian at the root from the weights' derivatives
    const float3 q = p + r * d;
    float w[3][4], dw[3][4], d2w[3][4];
    bs_weights(q.x, w[0], dw[0], d2w[0]);
    bs_weights(q.y, w[1], dw[1], d2w[1]);
    bs_weights(q.z, w[2], dw[2], d2w[2]);
    float fx = 0.0f, fy = 0.0f, fz = 0.0f;
    float fxx = 0.0f, fyy = 0.0f, fzz = 0.0f, fxy = 0.0f, fxz = 0.0f, fyz = 0.0f;
    for (int a = 0; a < 4; ++a) {
        // derivatives along y and z of the x-slice a: (value, y, z, yy, yz, zz)
        float v00 = 0.0f, v10 = 0.0f, v01 = 0.0f, v20 = 0.0f, v11 = 0.0f, v02 = 0.0f;
        for (int b = 0; b < 4; ++b) {
            float z0 = 0.0f, z1 = 0.0f, z2 = 0.0f;
            for (int e = 0; e < 4; ++e) {
                const float v = (float)data[base + a * sx + b * SZ + e];
                z0 += v * w[2][e];
                z1 += v * dw[2][e];
                z2 += v * d2w[2][e];
            }
            v00 += z0 * w[1][b];
            v10 += z0 * dw[1][b];
            v01 += z1 * w[1][b];
            v20 += z0 * d2w[1][b];
            v11 += z1 * dw[1][b];
            v02 += z2 * w[1][b];
        }
        fx += v00 * dw[0][a];
        fy += v10 * w[0][a];
        fz += v01 * w[0][a];
        fxx += v00 * d2w[0][a];
        fyy += v20 * w[0][a];
        fzz += v02 * w[0][a];
        fxy += v10 * dw[0][a];
        fxz += v01 * dw[0][a];
        fyz += v11 * w[0][a];
    }
    *grad = (float3)(fx, fy, fz);
    if (want_hess) {
        hess[0] = fxx; hess[1] = fyy; hess[2] = fzz;
        hess[3] = fxy; hess[4] = fxz; hess[5] = fyz;
    }
    return r;
}
