// Classification and empty-space-leaping structures for the ray caster (thesis §6.1.1, §6.2.1).
//
// Layout: samples data[(i*NY + j)*NZ + k]; cells (i, j, k) with 0 <= i < NX-1 etc. are
// numbered (i*(NY-1) + j)*(NZ-1) + k. Level 0 of the min-max octree holds per-cell value
// bounds; level L+1 node (a, b, c) covers the level-L nodes 2a..2a+1 x 2b..2b+1 x 2c..2c+1.
// All levels are stored one after the other; `levels` holds (offset, nx, ny, nz) per level.
//
// Skip code of a cell (uchar): SKIP_ACTIVE if the cell may hold the isosurface, else the
// highest octree level L whose node containing the cell is empty (a macro cube of 2^L cells).

#define SKIP_ACTIVE 255

__kernel void cell_minmax(__global const float *data, __global float *vmin,
                          __global float *vmax, int NX, int NY, int NZ)
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
    const int c = (i * cy + j) * cz + k;
    vmin[c] = lo;
    vmax[c] = hi;
}

__kernel void reduce_level(__global float *vmin, __global float *vmax,
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
                    const int s = src_off + (i * sy + j) * sz + k;
                    lo = fmin(lo, vmin[s]);
                    hi = fmax(hi, vmax[s]);
                }
            }
    const int d = dst_off + (a * dy + b) * dz + c;
    vmin[d] = lo;
    vmax[d] = hi;
}

__kernel void skip_codes(__global const float *vmin, __global const float *vmax,
                         __global const int4 *levels, int n_levels, float iso,
                         __global uchar *skip, __global int *active)
{
    const int k = get_global_id(0), j = get_global_id(1), i = get_global_id(2);
    const int4 l0 = levels[0];
    if (i >= l0.y || j >= l0.z || k >= l0.w) return;
    const int c = (i * l0.z + j) * l0.w + k;
    const bool act = vmin[c] <= iso && iso <= vmax[c];
    active[c] = act ? 1 : 0;
    if (act) {
        skip[c] = SKIP_ACTIVE;
        return;
    }
    // top-down: the first empty level is the largest macro cube (children of an empty node
    // are empty, so this is the thesis' skip index)
    for (int L = n_levels - 1; L >= 0; --L) {
        const int4 lv = levels[L];
        const int s = lv.x + (((i >> L) * lv.z + (j >> L)) * lv.w + (k >> L));
        if (iso < vmin[s] || iso > vmax[s]) {
            skip[c] = (uchar)L;
            return;
        }
    }
    skip[c] = 0;  // unreachable: level 0 is empty when the cell is not active
}

// ---- type-6 splines (cubes centred at the data points; padded samples, one ghost layer) ----
#ifdef MODEL_TYPE6

// Conservative value bounds of the spline on each cube: every B-coefficient is an affine
// combination sum w_q f_q (sum w_q = 1) of the 27 stencil values, so it lies in
// [min - N (max - min), max + N (max - min)] with N the largest negative weight mass.
__kernel void stencil_bounds(__global const float *pdata, int PY, int PZ,
                             int NX, int NY, int NZ, float negmass,
                             __global float *vmin, __global float *vmax)
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
    const int q = (i * NY + j) * NZ + k;
    vmin[q] = lo - w;
    vmax[q] = hi + w;
}

// Per candidate cube: all cube B-coefficients from the stencil, then the 24-bit tet code:
// bit t is set when the coefficients of tet t straddle the isovalue (convex hull property,
// thesis §6.1.1).
__kernel void tet_codes(__global const float *pdata, int PY, int PZ, int NY, int NZ,
                        __global const int *cubes, __constant const int *stencil,
                        __global const int *row_ptr, __global const int *cols,
                        __global const float *weights, __constant const int *tet_points,
                        float iso, __global uint *tetcode, __global int *n_relevant)
{
    const int a = get_global_id(0);
    const int cube = cubes[a];
    const int k = cube % NZ, j = (cube / NZ) % NY, i = cube / (NY * NZ);
    const int base = ((i + 1) * PY + (j + 1)) * PZ + (k + 1);
    float vals[27];
    for (int q = 0; q < 27; ++q) vals[q] = pdata[base + stencil[q]];
    float coef[NPOINTS];
    // the cube masks are sparse (about 12 of 27 weights per coefficient): CSR rows, kept in
    // global memory (cached) so that constant memory stays small on GPUs (64 KB, 8-9 args)
    for (int p = 0; p < NPOINTS; ++p) {
        float acc = 0.0f;
        for (int e = row_ptr[p]; e < row_ptr[p + 1]; ++e) acc += weights[e] * vals[cols[e]];
        coef[p] = acc;
    }
    uint code = 0u;
    for (int t = 0; t < 24; ++t) {
        float lo = INFINITY, hi = -INFINITY;
        for (int m = 0; m < NCOEF; ++m) {
            const float v = coef[tet_points[t * NCOEF + m]];
            lo = fmin(lo, v);
            hi = fmax(hi, v);
        }
        if (lo <= iso && iso <= hi) code |= 1u << t;
    }
    tetcode[cube] = code;
    n_relevant[a] = popcount(code);
}

#endif

// ---- activity pyramid: exact skip codes from per-cell activity (any model) ----

__kernel void activity_level0(__global const uint *code, __global uchar *act, int n)
{
    const int i = get_global_id(0);
    if (i < n) act[i] = code[i] != 0u ? 1 : 0;
}

__kernel void reduce_or(__global uchar *act, int src_off, int sx, int sy, int sz,
                        int dst_off, int dx, int dy, int dz)
{
    const int c = get_global_id(0), b = get_global_id(1), a = get_global_id(2);
    if (a >= dx || b >= dy || c >= dz) return;
    uchar any_ = 0;
    for (int da = 0; da < 2; ++da)
        for (int db = 0; db < 2; ++db)
            for (int dc = 0; dc < 2; ++dc) {
                const int i = 2 * a + da, j = 2 * b + db, k = 2 * c + dc;
                if (i < sx && j < sy && k < sz) any_ |= act[src_off + (i * sy + j) * sz + k];
            }
    act[dst_off + (a * dy + b) * dz + c] = any_;
}

__kernel void skip_from_activity(__global const uchar *act, __global const int4 *levels,
                                 int n_levels, __global uchar *skip)
{
    const int k = get_global_id(0), j = get_global_id(1), i = get_global_id(2);
    const int4 l0 = levels[0];
    if (i >= l0.y || j >= l0.z || k >= l0.w) return;
    const int c = (i * l0.z + j) * l0.w + k;
    if (act[c]) {
        skip[c] = SKIP_ACTIVE;
        return;
    }
    for (int L = n_levels - 1; L >= 0; --L) {
        const int4 lv = levels[L];
        if (!act[lv.x + (((i >> L) * lv.z + (j >> L)) * lv.w + (k >> L))]) {
            skip[c] = (uchar)L;
            return;
        }
    }
    skip[c] = 0;
}

// ---- truncated-octahedral spline Q_k: unit cells of the data grid, parity-class tables ----
#ifdef MODEL_TO

// Conservative bounds per cell from the union of the data its pieces use (offsets per parity
// class, relative to the cell corner in the padded array), widened by the negative mass.
__kernel void to_bounds(__global const float *pdata, int PY, int PZ, int CX, int CY, int CZ,
                        __constant const int *cls_start, __constant const int *cls_offsets,
                        float negmass, __global float *vmin, __global float *vmax)
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
    const int q = (i * CY + j) * CZ + k;
    vmin[q] = lo - w;
    vmax[q] = hi + w;
}

// Per candidate cell: B-coefficients of every (TO, tet) piece meeting it, and a bit set of the
// relevant ones (NWORDS x 32 bits; the thesis' tet code for the 144 tets of a TO). The data a
// cell's pieces read (the class union, at most NUNION values) are gathered once; the piece
// stencils (CSR per entry and coefficient) index into that private copy.
__kernel void to_codes(__global const float *pdata, int PY, int PZ, int CY, int CZ,
                       __global const int *cells, __constant const int *cls_start,
                       __constant const int *cls_offsets, __constant const int *ent_start,
                       __global const int *row_ptr, __global const ushort *cols,
                       __global const float *weights, float iso,
                       __global uint *anycode, __global int *slot, __global uint *bits,
                       __global int *n_relevant)
{
    const int a = get_global_id(0);
    const int cell = cells[a];
    const int k = cell % CZ, j = (cell / CZ) % CY, i = cell / (CY * CZ);
    const int cls = ((i & 1) << 2) | ((j & 1) << 1) | (k & 1);
    const int corner = ((i + GHOST) * PY + (j + GHOST)) * PZ + (k + GHOST);
    float vals[NUNION];
    const int u0 = cls_start[cls], nu = cls_start[cls + 1] - u0;
    for (int u = 0; u < nu; ++u) vals[u] = pdata[corner + cls_offsets[u0 + u]];
    uint words[NWORDS];
    for (int w = 0; w < NWORDS; ++w) words[w] = 0u;
    int count = 0;
    const int e0 = ent_start[cls];
    for (int e = e0; e < ent_start[cls + 1]; ++e) {
        float lo = INFINITY, hi = -INFINITY;
        for (int m = 0; m < NCOEF; ++m) {
            const int r = e * NCOEF + m;
            float acc = 0.0f;
            for (int q = row_ptr[r]; q < row_ptr[r + 1]; ++q) acc += weights[q] * vals[cols[q]];
            lo = fmin(lo, acc);
            hi = fmax(hi, acc);
        }
        if (lo <= iso && iso <= hi) {
            words[(e - e0) >> 5] |= 1u << ((e - e0) & 31);
            ++count;
        }
    }
    for (int w = 0; w < NWORDS; ++w) bits[a * NWORDS + w] = words[w];
    slot[cell] = a;
    anycode[cell] = count > 0 ? 1u : 0u;
    n_relevant[a] = count;
}

#endif
