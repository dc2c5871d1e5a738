// Direct volume rendering (emission-absorption) of a spline model, one work-item per pixel
// (thesis §8: "full volume rendering" from the direct ray caster). Compiled after raycast.cl
// (prepended with the same -D options: MODEL_TRILINEAR or MODEL_TYPE6, DATA_T, shading), whose
// point evaluation pieces it reuses: the trilinear monomial form, and for type-6 splines the
// dense tet masks, barycentric rows and de Casteljau tables (value and exact B-form gradient
// of the tet that holds the sample).
//
// Per ray: the interval inside the data box and the kept side of every clip plane, cut at the
// pixel's stop parameter (an embedded isosurface hit or an opaque mesh); samples at
// t0 + (k + 1/2) dt; RGBA from the transfer-function table (TF_SIZE entries over [tf_lo,
// tf_lo + (TF_SIZE - 1) / tf_scale], linear between entries), opacity corrected for the step
// (1 - (1 - a)^(dt / unit)), or, pre-integrated, the segment from the previous sample to
// this one from a PREINT_SIZE^2 table (front value x back value; thin features between two
// samples count); optional headlight Phong on the normalised spline gradient;
// front-to-back compositing until the opacity reaches ERT_ALPHA; the stop colour composited
// behind. Blocks of BLOCK^3 voxels whose value range maps to zero opacity are leapt over along
// the sample lattice, so the samples taken are those of a march without skipping: per block the
// host gives the Chebyshev distance k to the nearest block that is not transparent (rebuilt
// when the transfer function changes), so the ray leaps to where it leaves the (2k - 1)^3
// blocks around it, many blocks at once in large empty regions. core/dvr_reference.py is the NumPy
// reference of the same rules.

#ifndef BLOCK
#define BLOCK 4
#endif

#ifdef MODEL_TYPE6
// Value and index-space gradient of the type-6 spline at p (relative to the centre of the cube
// whose stencil starts at base): the tet of the cube holding p from the slicing planes (points
// on shared faces pick either; the spline is continuous there). The tet's B-coefficients are
// kept in acc between calls while the samples stay in the same tet of the same cube
// (*last_base, *last_tet): consecutive samples along a ray mostly do.
inline float type6_value(__global const DATA_T *pdata, offset_t base,
                         __constant const int *stencil, __global const float8 *tet_weights,
                         __constant const float4 *bary, __constant const int *red, float3 p,
                         float3 *grad, offset_t *last_base, int *last_tet, float8 *acc)
{
    // the pyramid by the axis a of the largest |p_a| and its sign, the tet inside it by the
    // larger of the two other |p_b| and its sign (core/partitions/type6.py locate and the
    // numbering of its TET_LOOKUP: 8 a + 4 [p_a < 0] + 2 [b = a + 1 mod 3] + [p_b < 0])
    const float pc[3] = {p.x, p.y, p.z};
    const float3 m = fabs(p);
    const int a = (m.x >= m.y && m.x >= m.z) ? 0 : (m.y >= m.z ? 1 : 2);
    const int b1 = a == 2 ? 0 : a + 1, b2 = a == 0 ? 2 : a - 1;
    const bool first = fabs(pc[b1]) >= fabs(pc[b2]);
    const int b = first ? b1 : b2;
    const int best = 8 * a + 4 * (pc[a] < 0.0f) + 2 * first + (pc[b] < 0.0f);
    const float4 r0 = bary[4 * best], r1 = bary[4 * best + 1], r2 = bary[4 * best + 2],
                 r3 = bary[4 * best + 3];
    const float4 lam = (float4)(r0.x * p.x + r0.y * p.y + r0.z * p.z + r0.w,
                                r1.x * p.x + r1.y * p.y + r1.z * p.z + r1.w,
                                r2.x * p.x + r2.y * p.y + r2.z * p.z + r2.w,
                                r3.x * p.x + r3.y * p.y + r3.z * p.z + r3.w);
    if (base != *last_base || best != *last_tet) {
        for (int h = 0; h < NCHUNK; ++h) acc[h] = (float8)(0.0f);
        __global const float8 *wt = tet_weights + best * 27 * NCHUNK;
        for (int q = 0; q < 27; ++q) {
            const float v = pdata[base + stencil[q]];
            for (int h = 0; h < NCHUNK; ++h) acc[h] += wt[q * NCHUNK + h] * v;
        }
        *last_base = base;
        *last_tet = best;
    }
    const float *c = (const float *)acc;
    const float4 e = linear_part(c, red, lam);
    *grad = DEGREE * (e.x * r0.xyz + e.y * r1.xyz + e.z * r2.xyz + e.w * r3.xyz);
    return e.x * lam.x + e.y * lam.y + e.z * lam.z + e.w * lam.w;
}
#endif

// v, g: the model's value and index-space gradient at the index-space point u (in the box)
// (the piece of the last sample is kept: eval_cell / eval_f, eval_base / eval_tet / eval_acc)
#ifdef MODEL_TRILINEAR
#define MODEL_EVAL(u, v, g) do { \
        const int3 cell_ = clamp(convert_int3_rtn(u), (int3)(0), \
                                 (int3)(NX - 2, NY - 2, NZ - 2)); \
        if (cell_.x != eval_cell.x || cell_.y != eval_cell.y || cell_.z != eval_cell.z) { \
            eval_f = trilinear_coeffs(data, cell_, SY, SZ); \
            eval_cell = cell_; \
        } \
        const float3 q_ = (u) - convert_float3(cell_); \
        (v) = tri_value(&eval_f, q_); \
        (g) = tri_gradient(&eval_f, q_); \
    } while (0)
#else
#define MODEL_EVAL(u, v, g) do { \
        const int3 cube_ = clamp(convert_int3_rte(u), (int3)(0), \
                                 (int3)(NX - 1, NY - 1, NZ - 1)); \
        const offset_t base_ = (((offset_t)cube_.x + 1) * SY + (cube_.y + 1)) * SZ \
                               + (cube_.z + 1); \
        (v) = type6_value(data, base_, stencil, tet_weights, bary, red, \
                          (u) - convert_float3(cube_), &(g), &eval_base, &eval_tet, \
                          eval_acc); \
    } while (0)
#endif

__kernel void dvr(__global const DATA_T *data,   // device samples of the ray caster
                  int NX, int NY, int NZ,        // samples (box [0, n-1] in index space)
                  int SY, int SZ,                // strides of `data`
#ifdef MODEL_TYPE6
                  __constant const int *stencil, __global const float8 *tet_weights,
                  __constant const float4 *bary, __constant const int *red,
#endif
                  __global const uchar *leap,    // per block: Chebyshev distance to an opaque one
                  int BX, int BYB, int BZB,      // blocks per axis
                  __global const float4 *tf, float tf_lo, float tf_scale,
                  int preint,                    // 1: pre-integrated segments (`pre`)
                  __global const float4 *pre, float pre_scale,
                  float dt, float alpha_exp,     // world step; dt / unit length
                  int shade,
                  float3 eye_u, float3 dop, float3 right_s, float3 up_s, float3 inv_spacing,
                  __global const float4 *planes, int n_planes,  // index space: n.u + w >= 0
                  float depth_a, float depth_b,  // window depth = a - b / z_eye
                  __global const float *stop_t,  // per pixel: the ray ends there (INFINITY)
                  __global const float4 *stop_rgba,  // ... with this colour behind
                  __global const float *stop_depth,  // ... at this window depth
                  float3 bg,
                  __global float4 *rgba_out,     // accumulated (premultiplied rgb, alpha)
                  __global float *depth_out,
                  __global uchar4 *color_out,    // composited over bg, opaque
                  int W, int H)
{
    const int col = get_global_id(0), row = get_global_id(1);
    if (col >= W || row >= H) return;
    const int pix = row * W + col;

    const float x = 2.0f * (col + 0.5f) / W - 1.0f;
    const float y = 1.0f - 2.0f * (row + 0.5f) / H;
    const float3 dw = normalize(dop + x * right_s + y * up_s);
    const float3 d = dw * inv_spacing;
    const float3 inv_d = 1.0f / d;

    const float3 hiB = (float3)(NX - 1, NY - 1, NZ - 1);
    float3 ta = (0.0f - eye_u) * inv_d, tb = (hiB - eye_u) * inv_d;
    float3 tn = fmin(ta, tb), tf_ = fmax(ta, tb);
    if (d.x == 0.0f) { tn.x = (eye_u.x >= 0.0f && eye_u.x <= hiB.x) ? -INFINITY : INFINITY; tf_.x = -tn.x; }
    if (d.y == 0.0f) { tn.y = (eye_u.y >= 0.0f && eye_u.y <= hiB.y) ? -INFINITY : INFINITY; tf_.y = -tn.y; }
    if (d.z == 0.0f) { tn.z = (eye_u.z >= 0.0f && eye_u.z <= hiB.z) ? -INFINITY : INFINITY; tf_.z = -tn.z; }
    float t0 = fmax(0.0f, fmax(tn.x, fmax(tn.y, tn.z)));
    float t1 = fmin(tf_.x, fmin(tf_.y, tf_.z));
    for (int p = 0; p < n_planes; ++p) {
        const float4 pl = planes[p];
        const float a0 = dot(pl.xyz, eye_u) + pl.w;
        const float b = dot(pl.xyz, d);
        if (b > 0.0f) t0 = fmax(t0, -a0 / b);
        else if (b < 0.0f) t1 = fmin(t1, -a0 / b);
        else if (a0 < 0.0f) t1 = -INFINITY;
    }
    const float ts = stop_t[pix];
    t1 = fmin(t1, ts);

    float3 acc = (float3)(0.0f);
    float A = 0.0f;
    float depth = 1.0f;
    bool has_depth = false;
    const float dz = dot(dw, dop);
#ifdef MODEL_TRILINEAR
    int3 eval_cell = (int3)(-1);
    Trilinear eval_f;
#else
    offset_t eval_base = -1;
    int eval_tet = -1;
    float8 eval_acc[NCHUNK];
#endif
    if (t0 < t1) {
        const int n = (int)ceil((t1 - t0) / dt - 0.5f);
        float v_prev = 0.0f;
        bool have_prev = false, leapt = false;
        for (int k = 0; k < n; ++k) {
            const float t = t0 + ((float)k + 0.5f) * dt;
            const float3 u = clamp(eye_u + t * d, (float3)(0.0f), hiB);
            const int3 blk = min(convert_int3_rtn(u) / BLOCK, (int3)(BX - 1, BYB - 1, BZB - 1));
            int kk = k;  // the last sample inside an empty block holding this one
            const int reach = leapt ? 0 : leap[(blk.x * BYB + blk.y) * BZB + blk.z];
            if (reach > 0) {
                const int3 lo = (blk - (reach - 1)) * BLOCK, hi = (blk + reach) * BLOCK;
                const float3 te = exit_params(eye_u, d, inv_d, lo, hi);
                const float t_exit = fmin(te.x, fmin(te.y, te.z));
                kk = max(k, min((int)floor((t_exit - t0) / dt - 0.5f), n - 1));
                if (!preint) {
                    k = kk;  // the loop steps past it
                    continue;
                }
            }
            leapt = false;
            float3 g;
            float v;
            MODEL_EVAL(u, v, g);
            float3 rgb;
            float a;
            if (preint) {
                // the segment from the previous sample (evaluated again after a leap)
                if (!have_prev) {
                    float3 g_prev;
                    const float3 up = clamp(eye_u + (t - dt) * d, (float3)(0.0f), hiB);
                    MODEL_EVAL(up, v_prev, g_prev);
                }
                const float fi = clamp((v_prev - tf_lo) * pre_scale, 0.0f,
                                       (float)(PREINT_SIZE - 1));
                const float fj = clamp((v - tf_lo) * pre_scale, 0.0f, (float)(PREINT_SIZE - 1));
                const int i = min((int)fi, PREINT_SIZE - 2), j = min((int)fj, PREINT_SIZE - 2);
                const float wi = fi - (float)i, wj = fj - (float)j;
                __global const float4 *r0 = pre + i * PREINT_SIZE, *r1 = r0 + PREINT_SIZE;
                const float4 c = (r0[j] * (1.0f - wj) + r0[j + 1] * wj) * (1.0f - wi)
                                 + (r1[j] * (1.0f - wj) + r1[j + 1] * wj) * wi;
                v_prev = v;
                have_prev = true;
                if (kk > k + 1) {
                    // the samples up to kk lie in a block the transfer function leaves
                    // transparent: leap to kk, whose segment is taken from kk - 1
                    k = kk - 1;
                    have_prev = false;
                    leapt = true;
                }
                if (c.w <= 0.0f) continue;
                a = c.w;
                rgb = c.xyz;  // premultiplied by the segment's opacity
                if (shade) {
                    const float3 gw = g * inv_spacing;
                    const float gl = length(gw);
                    const float cs = gl > 0.0f ? fabs(dot(gw, dw)) / gl : 1.0f;
                    rgb = fmin(rgb * (AMBIENT + DIFFUSE * cs) + SPECULAR * pow(cs, SHININESS) * a,
                               a);
                }
            } else {
                const float fx = clamp((v - tf_lo) * tf_scale, 0.0f, (float)(TF_SIZE - 1));
                const int i = min((int)fx, TF_SIZE - 2);
                const float fr = fx - (float)i;
                const float4 c = tf[i] * (1.0f - fr) + tf[i + 1] * fr;
                if (c.w <= 0.0f) continue;
                a = 1.0f - pow(1.0f - fmin(c.w, 1.0f), alpha_exp);
                rgb = c.xyz;
                if (shade) {
                    const float3 gw = g * inv_spacing;
                    const float gl = length(gw);
                    const float cs = gl > 0.0f ? fabs(dot(gw, dw)) / gl : 1.0f;
                    rgb = clamp(rgb * (AMBIENT + DIFFUSE * cs) + SPECULAR * pow(cs, SHININESS),
                                0.0f, 1.0f);
                }
                rgb *= a;
            }
            acc += (1.0f - A) * rgb;
            A += (1.0f - A) * a;
            if (!has_depth && A >= DEPTH_ALPHA) {
                depth = clamp(depth_a - depth_b / (t * dz), 0.0f, 1.0f);
                has_depth = true;
            }
            if (A >= ERT_ALPHA) break;
        }
    }
    if (A < ERT_ALPHA && isfinite(ts)) {
        const float4 s = stop_rgba[pix];
        acc += (1.0f - A) * s.w * s.xyz;
        A += (1.0f - A) * s.w;
        if (!has_depth) depth = stop_depth[pix];
    }
    rgba_out[pix] = (float4)(acc, A);
    depth_out[pix] = depth;
    const float3 out = clamp(acc + (1.0f - A) * bg, 0.0f, 1.0f);
    const float3 c255 = rint(out * 255.0f);
    color_out[pix] = (uchar4)((uchar)c255.x, (uchar)c255.y, (uchar)c255.z, 255);
}
