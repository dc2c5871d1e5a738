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
