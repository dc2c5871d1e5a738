// Isovalue-independent structures of the ray caster (thesis §6.1.1, §6.2.1), built once per
// data change, and the classification of every cell at once (RayCaster.classify_all).
// Specialised by -D options: MODEL_TYPE6 (cubes centred at the samples, padded samples with
// one ghost layer), MODEL_TO with GHOST (unit cells, parity-class tables), else trilinear;
// MODEL_CUSTOM with CELL_REACH (a plugin's family: cell (i, j, k) reads the samples
// i..i+CELL_REACH per axis, without a ghost offset); DATA_T the device type of the samples
// (uchar/short/ushort for integer data, else float); OFFSET64 64-bit sample offsets.
//
// Cells (i, j, k) of the traversal grid (CX x CY x CZ) are numbered (i*CY + j)*CZ + k; the
// samples are data[(i*SY + j)*SZ + k]. The min-max octree holds value bounds (lo, hi) as
// float2 from level 1 up: level 1 node (a, b, c) covers the cells 2a..2a+1 x 2b..2b+1 x
// 2c..2c+1, level L+1 the level-L nodes likewise. Per-cell bounds (level 0) are not stored
// (8 bytes per cell): where a cell's own bounds are needed they come from its data. All
// stored levels lie one after the other; `levels` holds (offset, nx, ny, nz) from level 1.
// The skip index of a cell for an isovalue follows from these bounds alone (raycast.cl,
// skip_level), so nothing here is redone when the isovalue changes.

#ifndef DATA_T
#define DATA_T float  // samples as Volume holds them (the host names a smaller exact type)
#endif
#ifndef offset_t
#ifdef OFFSET64
#define offset_t long
#else
#define offset_t int
#endif
#endif

// Minimum and maximum of the bound loops: PoCL calls fmin/fmax out of line (two thirds of
// the octree build). As fmin/fmax do, a NaN x (a missing sample) is ignored.
inline float min_acc(float acc, float x) { return x < acc ? x : acc; }
inline float max_acc(float acc, float x) { return x > acc ? x : acc; }

// the (lo, hi) vector of the sample type (DATA_T2: uchar2, short2, ..., float2)
#define PAIR_OF(t) t##2
#define PAIR(t) PAIR_OF(t)
#define DATA_T2 PAIR(DATA_T)

#ifdef MODEL_TO
// the TO bounds read the data offsets of the cell's parity class; brick_bounds reads the
// NODE_BLOCKS sample blocks (sample_blocks) that hold the data a level-1 node reads
// (node_blocks: offsets from block (a, b, c); splineviz/compute/raycast/to_tables.py
// node_union)
#define CLASS_ARGS , __constant const int *cls_start, __constant const int *cls_offsets
#define CLASS_PASS , cls_start, cls_offsets
#define NODE_ARGS , __global const DATA_T2 *blocks, int BX, int BY, int BZ, \
                  __constant const int *node_blocks
#elif defined(MODEL_TYPE6)
// type-6 brick_bounds reads the (min, max) of 2 x 2 x 2 blocks of samples (sample_blocks)
#define CLASS_ARGS
#define CLASS_PASS
#define NODE_ARGS , __global const DATA_T2 *blocks, int BX, int BY, int BZ
#else
#define CLASS_ARGS
#define CLASS_PASS
#define NODE_ARGS
#endif

// Conservative value bounds of the model on cell (i, j, k).
//   trilinear: the values lie between the min and max of the cell's 8 corners (exact).
//   type-6: every B-coefficient of the cube is an affine combination sum w_q f_q
//   (sum w_q = 1) of the 27 stencil values, so it lies in [min - N (max - min),
//   max + N (max - min)] with N = negmass, the largest negative weight mass.
//   TO: the same, over the union of the data the cell's (TO, tet) pieces use.
inline float2 cell_bounds(__global const DATA_T *data, int SY, int SZ, int i, int j, int k,
                          float negmass CLASS_ARGS)
{
    float lo = INFINITY, hi = -INFINITY;
#if defined(MODEL_TYPE6)
    for (int a = 0; a < 3; ++a)
        for (int b = 0; b < 3; ++b)
            for (int c = 0; c < 3; ++c) {
                const float v = data[(((offset_t)i + a) * SY + (j + b)) * SZ + (k + c)];
                lo = min_acc(lo, v);
                hi = max_acc(hi, v);
            }
#elif defined(MODEL_CUSTOM)
    for (int a = 0; a <= CELL_REACH; ++a)
        for (int b = 0; b <= CELL_REACH; ++b)
            for (int c = 0; c <= CELL_REACH; ++c) {
                const float v = data[(((offset_t)i + a) * SY + (j + b)) * SZ + (k + c)];
                lo = min_acc(lo, v);
                hi = max_acc(hi, v);
            }
#elif defined(MODEL_TO)
    const int cls = ((i & 1) << 2) | ((j & 1) << 1) | (k & 1);
    const offset_t base = (((offset_t)i + GHOST) * SY + (j + GHOST)) * SZ + (k + GHOST);
    for (int e = cls_start[cls]; e < cls_start[cls + 1]; ++e) {
        const float v = data[base + cls_offsets[e]];
        lo = min_acc(lo, v);
        hi = max_acc(hi, v);
    }
#else
    for (int a = 0; a < 2; ++a)
        for (int b = 0; b < 2; ++b)
            for (int c = 0; c < 2; ++c) {
                const float v = data[(((offset_t)i + a) * SY + (j + b)) * SZ + (k + c)];
                lo = min_acc(lo, v);
                hi = max_acc(hi, v);
            }
#endif
    const float w = negmass * (hi - lo);
    return (float2)(lo - w, hi + w);
}

// Level 1 of the octree: the bounds of the (up to) 8 cells of each node.
__kernel void brick_bounds(__global const DATA_T *data, int SY, int SZ, int CX, int CY, int CZ,
                           float negmass CLASS_ARGS NODE_ARGS, __global float2 *bounds)
{
    const int c = get_global_id(0), b = get_global_id(1), a = get_global_id(2);
    const int dx = (CX + 1) / 2, dy = (CY + 1) / 2, dz = (CZ + 1) / 2;
    if (a >= dx || b >= dy || c >= dz) return;
    float lo = INFINITY, hi = -INFINITY;
#ifdef MODEL_TO
    // the node's 8 cells read 416 values, 125 of them distinct, held by 39 sample blocks:
    // the blocks' range, widened as in cell_bounds, holds the union of the cells' bounds
    // from 39 loads (312 samples: 1.4x the candidate nodes of the cells' own bounds on the
    // benchmark's gyroid, the same frames; the octree of a new 256^3 time step took 2.5x
    // longer from the 125 values, longer still from the cells' 416). A node past the last
    // cell reads inside the padded samples still (its phantom cells reach GHOST layers at
    // most).
    const int base = (a * BY + b) * BZ + c;
    for (int u = 0; u < NODE_BLOCKS; ++u) {
        const DATA_T2 v = blocks[base + node_blocks[u]];
        lo = min_acc(lo, (float)v.x);
        hi = max_acc(hi, (float)v.y);
    }
    const float w = negmass * (hi - lo);
    lo -= w;
    hi += w;
#elif defined(MODEL_TYPE6)
    // the node's cubes read the padded samples 2a..min(2a + 1, CX - 1) + 2 per axis (a cube
    // i the samples i..i+2): the blocks a and a + 1, the last one cut at the samples' end
    // (sample_blocks) hold exactly these, so their range, widened as in cell_bounds, is the
    // box's from 8 loads instead of 64
    // (the second block per axis clamped to the last, as in sample_blocks)
    const int i1 = min(a + 1, BX - 1), j1 = min(b + 1, BY - 1), k1 = min(c + 1, BZ - 1);
    const int r00 = (a * BY + b) * BZ, r01 = (a * BY + j1) * BZ, r10 = (i1 * BY + b) * BZ,
              r11 = (i1 * BY + j1) * BZ;
    const DATA_T2 v[8] = {blocks[r00 + c], blocks[r00 + k1], blocks[r01 + c], blocks[r01 + k1],
                          blocks[r10 + c], blocks[r10 + k1], blocks[r11 + c], blocks[r11 + k1]};
    for (int m = 0; m < 8; ++m) {
        lo = min_acc(lo, (float)v[m].x);
        hi = max_acc(hi, (float)v[m].y);
    }
    const float w = negmass * (hi - lo);
    lo -= w;
    hi += w;
#else
    // the node's cells read one box of samples (a trilinear cell i the samples i..i+1): its
    // range, widened as in cell_bounds, holds the union of the cells' bounds (the same
    // bounds when negmass is 0), from far fewer loads
#if defined(MODEL_CUSTOM)
    const int reach = CELL_REACH;
#else
    const int reach = 1;
#endif
    for (int i = 2 * a; i <= min(2 * a + 1, CX - 1) + reach; ++i)
        for (int j = 2 * b; j <= min(2 * b + 1, CY - 1) + reach; ++j)
            for (int k = 2 * c; k <= min(2 * c + 1, CZ - 1) + reach; ++k) {
                const float v = data[((offset_t)i * SY + j) * SZ + k];
                lo = min_acc(lo, v);
                hi = max_acc(hi, v);
            }
    const float w = negmass * (hi - lo);
    lo -= w;
    hi += w;
#endif
    bounds[(a * dy + b) * dz + c] = (float2)(lo, hi);
}

#if defined(MODEL_TYPE6) || defined(MODEL_TO)
// (min, max) of the 2 x 2 x 2 blocks of the PX x PY x PZ (padded) samples: block (p, q, r)
// holds the samples 2p..2p+1 x 2q..2q+1 x 2r..2r+1 that exist; made once per data change for
// brick_bounds (a type-6 node's 64 samples are 8 blocks, a TO node's 125 lie in 39)
__kernel void sample_blocks(__global const DATA_T *data, int PX, int PY, int PZ,
                            __global DATA_T2 *blocks)
{
    const int r = get_global_id(0), q = get_global_id(1), p = get_global_id(2);
    const int BX = (PX + 1) / 2, BY = (PY + 1) / 2, BZ = (PZ + 1) / 2;
    if (p >= BX || q >= BY || r >= BZ) return;
    // the second sample per axis clamped to the last (a repeated sample changes no extreme):
    // a loop without bounds that depend on the block, which PoCL runs several times faster
    const int i1 = min(2 * p + 1, PX - 1), j1 = min(2 * q + 1, PY - 1),
              k1 = min(2 * r + 1, PZ - 1);
    const offset_t r00 = ((offset_t)(2 * p) * PY + 2 * q) * PZ, r01 = ((offset_t)(2 * p) * PY + j1) * PZ,
                   r10 = ((offset_t)i1 * PY + 2 * q) * PZ, r11 = ((offset_t)i1 * PY + j1) * PZ;
    const float v[8] = {data[r00 + 2 * r], data[r00 + k1], data[r01 + 2 * r], data[r01 + k1],
                        data[r10 + 2 * r], data[r10 + k1], data[r11 + 2 * r], data[r11 + k1]};
    float lo = v[0], hi = v[0];
    for (int m = 1; m < 8; ++m) {
        lo = min_acc(lo, v[m]);
        hi = max_acc(hi, v[m]);
    }
    // back in the samples' type, exactly: integer samples' extremes are integers (a block
    // holds one sample at least), float blocks of NaNs alone keep (inf, -inf)
    blocks[(p * BY + q) * BZ + r] = (DATA_T2)((DATA_T)lo, (DATA_T)hi);
}
#endif

__kernel void reduce_level(__global float2 *bounds,
                           int src_off, int sx, int sy, int sz,
                           int dst_off, int dx, int dy, int dz)
{
    const int c = get_global_id(0), b = get_global_id(1), a = get_global_id(2);
    if (a >= dx || b >= dy || c >= dz) return;
    // the second child per axis clamped to the last (as in sample_blocks)
    const int i1 = min(2 * a + 1, sx - 1), j1 = min(2 * b + 1, sy - 1),
              k1 = min(2 * c + 1, sz - 1);
    const int r00 = src_off + (2 * a * sy + 2 * b) * sz, r01 = src_off + (2 * a * sy + j1) * sz,
              r10 = src_off + (i1 * sy + 2 * b) * sz, r11 = src_off + (i1 * sy + j1) * sz;
    const float2 v[8] = {bounds[r00 + 2 * c], bounds[r00 + k1], bounds[r01 + 2 * c],
                         bounds[r01 + k1], bounds[r10 + 2 * c], bounds[r10 + k1],
                         bounds[r11 + 2 * c], bounds[r11 + k1]};
    float lo = INFINITY, hi = -INFINITY;
    for (int m = 0; m < 8; ++m) {
        lo = min_acc(lo, v[m].x);
        hi = max_acc(hi, v[m].y);
    }
    bounds[dst_off + (a * dy + b) * dz + c] = (float2)(lo, hi);
}

// Classification of every cell at once (RayCaster.classify_all): flag of the candidate
// cells, whose value bounds straddle the isovalue.
__kernel void candidates(__global const DATA_T *data, int SY, int SZ, int CX, int CY, int CZ,
                         float negmass CLASS_ARGS, float iso, __global int *flag)
{
    const int k = get_global_id(0), j = get_global_id(1), i = get_global_id(2);
    if (i >= CX || j >= CY || k >= CZ) return;
    const float2 v = cell_bounds(data, SY, SZ, i, j, k, negmass CLASS_PASS);
    flag[(i * CY + j) * CZ + k] = (v.x <= iso && iso <= v.y) ? 1 : 0;
}
