// Value bounds of the tricubic B-spline on its unit cells from their Bernstein form (see
// splineviz_bspline/bounds.py): the B-spline coefficients of a cell are converted to its
// 4 x 4 x 4 Bernstein coefficients axis by axis (every Bernstein coefficient a convex
// combination of B-spline ones), whose range holds the spline on the cell.

// Bernstein coefficients (rows) of the cubic B-spline weights of offsets -1..2 (columns)
__constant float bb_matrix[4][4] = {
    {1.0f / 6.0f, 4.0f / 6.0f, 1.0f / 6.0f, 0.0f},
    {0.0f, 4.0f / 6.0f, 2.0f / 6.0f, 0.0f},
    {0.0f, 2.0f / 6.0f, 4.0f / 6.0f, 0.0f},
    {0.0f, 1.0f / 6.0f, 4.0f / 6.0f, 1.0f / 6.0f},
};

// One work item per sample (i, j, k) of the SX x SY x SZ coefficients: table[2 s], table[2 s
// + 1] (s = (i SY + j) SZ + k) get the bounds of the cell whose first coefficient is (i, j, k),
// widened by slack times the largest |coefficient| it reads (the float32 rounding of this
// conversion and of the ray kernel's restriction); (-inf, inf) where no cell starts, NaN for a
// cell that reads a NaN.
__kernel void bspline_cell_bounds(__global const float *data, int SX, int SY, int SZ,
                                  float slack, __global float *table)
{
    const int k = get_global_id(0), j = get_global_id(1), i = get_global_id(2);
    if (i >= SX || j >= SY || k >= SZ) return;
    const long s = ((long)i * SY + j) * SZ + k;
    if (i + 3 >= SX || j + 3 >= SY || k + 3 >= SZ) {
        table[2 * s] = -INFINITY;
        table[2 * s + 1] = INFINITY;
        return;
    }
    // z, then y: yz[a][l][m] = sum_b,c M[l][b] M[m][c] data(i + a, j + b, k + c)
    float yz[4][4][4];
    float amax = 0.0f;
    bool nan = false;
    for (int a = 0; a < 4; ++a) {
        float z[4][4];
        for (int b = 0; b < 4; ++b) {
            const long row = ((long)(i + a) * SY + (j + b)) * SZ + k;
            float c[4];
            for (int e = 0; e < 4; ++e) {
                c[e] = data[row + e];
                nan |= isnan(c[e]);
                const float v = fabs(c[e]);
                amax = v > amax ? v : amax;
            }
            for (int m = 0; m < 4; ++m)
                z[b][m] = bb_matrix[m][0] * c[0] + bb_matrix[m][1] * c[1]
                          + bb_matrix[m][2] * c[2] + bb_matrix[m][3] * c[3];
        }
        for (int l = 0; l < 4; ++l)
            for (int m = 0; m < 4; ++m)
                yz[a][l][m] = bb_matrix[l][0] * z[0][m] + bb_matrix[l][1] * z[1][m]
                              + bb_matrix[l][2] * z[2][m] + bb_matrix[l][3] * z[3][m];
    }
    float lo = INFINITY, hi = -INFINITY;
    for (int r = 0; r < 4; ++r)
        for (int l = 0; l < 4; ++l)
            for (int m = 0; m < 4; ++m) {
                const float v = bb_matrix[r][0] * yz[0][l][m] + bb_matrix[r][1] * yz[1][l][m]
                                + bb_matrix[r][2] * yz[2][l][m] + bb_matrix[r][3] * yz[3][l][m];
                lo = v < lo ? v : lo;
                hi = v > hi ? v : hi;
            }
    table[2 * s] = nan ? NAN : lo - slack * amax;
    table[2 * s + 1] = nan ? NAN : hi + slack * amax;
}

// Level 1 of the min-max octree (nodes of 2 x 2 x 2 cells, dx x dy x dz of them) from the
// CX x CY x CZ cells' bounds in table; NaN bounds are ignored, as in classify.cl.
__kernel void bspline_node_bounds(__global const float *table, int SY, int SZ,
                                  int CX, int CY, int CZ, __global float2 *nodes)
{
    const int c = get_global_id(0), b = get_global_id(1), a = get_global_id(2);
    const int dx = (CX + 1) / 2, dy = (CY + 1) / 2, dz = (CZ + 1) / 2;
    if (a >= dx || b >= dy || c >= dz) return;
    float lo = INFINITY, hi = -INFINITY;
    for (int i = 2 * a; i < min(2 * a + 2, CX); ++i)
        for (int j = 2 * b; j < min(2 * b + 2, CY); ++j)
            for (int k = 2 * c; k < min(2 * c + 2, CZ); ++k) {
                const long s = ((long)i * SY + j) * SZ + k;
                const float l = table[2 * s], h = table[2 * s + 1];
                lo = l < lo ? l : lo;
                hi = h > hi ? h : hi;
            }
    nodes[((long)a * dy + b) * dz + c] = (float2)(lo, hi);
}
