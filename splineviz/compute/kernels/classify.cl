// Isovalue-independent structures of the ray caster (thesis §6.1.1, §6.2.1), built once per
// data change, and the classification of every cell at once (RayCaster.classify_all).
//
// Layout: samples data[(i*NY + j)*NZ + k]; cells (i, j, k) with 0 <= i < NX-1 etc. are
// numbered (i*(NY-1) + j)*(NZ-1) + k. Level 0 of the min-max octree holds per-cell value
// bounds (lo, hi) as float2; level L+1 node (a, b, c) covers the level-L nodes 2a..2a+1 x
// 2b..2b+1 x 2c..2c+1. All levels are stored one after the other; `levels` holds
// (offset, nx, ny, nz) per level. The skip index of a cell for an isovalue follows from these
// bounds alone (raycast.cl, skip_level), so nothing here is redone when the isovalue changes.

__kernel void cell_minmax(__global const float *data, __global float2 *bounds,
                          int NX, int NY, int NZ)
{
    // trilinear model: the values on a cell lie between the min and max of its 8 corners
    const int k = get_global_id(0), j = get_global_id(1), i = get_global_id(2);
    const int cx = NX - 1, cy = NY - 1, cz = NZ - 1;
    if (i >= cx || j >= cy || k >= cz) return;
    float lo = INFINITY, hi = -INFINITY;
    for (int di = 0; di < 2; ++di)
        for (int dj = 0; dj < 2; ++dj)
            for (int dk = 0; dk < 2; ++dk) {
                const float v = data[((i + di) * NY + (j + dj)) * NZ + (k + dk)];
                lo = fmin(lo, v);
                hi = fmax(hi, v);
            }
    bounds[(i * cy + j) * cz + k] = (float2)(lo, hi);
}

__kernel void reduce_level(__global float2 *bounds,
                           int src_off, int sx, int sy, int sz,
                           int dst_off, int dx, int dy, int dz)
{
    const int c = get_global_id(0), b = get_global_id(1), a = get_global_id(2);
    if (a >= dx || b >= dy || c >= dz) return;
    float lo = INFINITY, hi = -INFINITY;
    for (int da = 0; da < 2; ++da)
        for (int db = 0; db < 2; ++db)
            for (int dc = 0; dc < 2; ++dc) {
                const int i = 2 * a + da, j = 2 * b + db, k = 2 * c + dc;
                if (i < sx && j < sy && k < sz) {
                    const float2 b = bounds[src_off + (i * sy + j) * sz + k];
                    lo = fmin(lo, b.x);
                    hi = fmax(hi, b.y);
                }
            }
    bounds[dst_off + (a * dy + b) * dz + c] = (float2)(lo, hi);
}

// Classification of every cell at once (RayCaster.classify_all; the ray kernel does the same
// test lazily, cell by cell): flag of the cells whose value bounds straddle the isovalue.
__kernel void candidates(__global const float2 *bounds, int n, float iso, __global int *flag)
{
    const int c = get_global_id(0);
    if (c >= n) return;
    const float2 b = bounds[c];
    flag[c] = (b.x <= iso && iso <= b.y) ? 1 : 0;
}

// ---- type-6 splines (cubes centred at the data points; padded samples, one ghost layer) ----
#ifdef MODEL_TYPE6

// Conservative value bounds of the spline on each cube: every B-coefficient is an affine
// combination sum w_q f_q (sum w_q = 1) of the 27 stencil values, so it lies in
// [min - N (max - min), max + N (max - min)] with N the largest negative weight mass.
__kernel void stencil_bounds(__global const float *pdata, int PY, int PZ,
                             int NX, int NY, int NZ, float negmass,
                             __global float2 *bounds)
{
    const int k = get_global_id(0), j = get_global_id(1), i = get_global_id(2);
    if (i >= NX || j >= NY || k >= NZ) return;
    float lo = INFINITY, hi = -INFINITY;
    for (int a = 0; a < 3; ++a)
        for (int b = 0; b < 3; ++b)
            for (int c = 0; c < 3; ++c) {
                const float v = pdata[((i + a) * PY + (j + b)) * PZ + (k + c)];
                lo = fmin(lo, v);
                hi = fmax(hi, v);
            }
    const float w = negmass * (hi - lo);
    bounds[(i * NY + j) * NZ + k] = (float2)(lo - w, hi + w);
}

#endif

// ---- truncated-octahedral spline Q_k: unit cells of the data grid, parity-class tables ----
#ifdef MODEL_TO

// Conservative bounds per cell from the union of the data its pieces use (offsets per parity
// class, relative to the cell corner in the padded array), widened by the negative mass.
__kernel void to_bounds(__global const float *pdata, int PY, int PZ, int CX, int CY, int CZ,
                        __constant const int *cls_start, __constant const int *cls_offsets,
                        float negmass, __global float2 *bounds)
{
    const int k = get_global_id(0), j = get_global_id(1), i = get_global_id(2);
    if (i >= CX || j >= CY || k >= CZ) return;
    const int cls = ((i & 1) << 2) | ((j & 1) << 1) | (k & 1);
    const int base = ((i + GHOST) * PY + (j + GHOST)) * PZ + (k + GHOST);
    float lo = INFINITY, hi = -INFINITY;
    for (int e = cls_start[cls]; e < cls_start[cls + 1]; ++e) {
        const float v = pdata[base + cls_offsets[e]];
        lo = fmin(lo, v);
        hi = fmax(hi, v);
    }
    const float w = negmass * (hi - lo);
    bounds[(i * CY + j) * CZ + k] = (float2)(lo - w, hi + w);
}

#endif
