// Image-based ray casting of spline isosurfaces (thesis §6.2, Listing 6.2), one work-item per
// pixel. Specialised by -D options:
//   MODEL_TRILINEAR      the trilinear model: exact cubic along the ray in each cell
//   MODEL_TO, GHOST      the truncated-octahedral spline Q_k (DEGREE 2): unit cells of the
//   NUNION, NWORDS       grid with per-parity-class (TO, tet) tables and per-cell bit sets of
//                        the relevant pieces
//   MODEL_TYPE6, DEGREE  type-6 splines (2: super-quadratic, 3: cubic C1): B-coefficients of
//                        the relevant tets from the 27-point data stencil, blossoms of the
//                        ray segment, first root in the tet (thesis §6.1.2, §6.2.2); tet
//                        codes from the cube coefficients (type6_points_code, prepended)
//   AMBIENT, DIFFUSE, SPECULAR, SHININESS, FRONT_R.., BACK_R.., BG_R..   Phong headlight
//   SKIP_ACTIVE          skip code of a candidate cell (skip_codes)
//   MODEL_CUSTOM         a kernel family brought by a plugin (CustomKernelFamily): its source,
//   GHOST, CELL_REACH    prepended, defines custom_cell_root, the first root in a unit cell
//   DATA_T               device type of the samples (uchar/short/ushort: integer data kept
//                        in a small type, converted to float when read; else float)
//   OFFSET64             64-bit sample offsets (offset_t is long): volumes past 2^31 device
//                        samples; without it int, whose arithmetic is cheaper
//   BRICKS               the ray kernel of a brick of a bigger volume (below); without it,
//                        the kernel of a single cast, which ignores cell_lo/hi/off
//
// Nothing here needs a pass over the volume per isovalue (thesis §6.2.3 "only the work the
// picture needs"): the skip index of a cell comes from the isovalue-independent min-max octree
// of classify.cl when a ray reaches the cell, and the tet code of a type-6 cube (§6.1.1; TO:
// the cell's bit set of relevant pieces) is computed by the first ray that reaches it and
// cached per brick of 2^3 cells, stamped with the epoch of the isovalue (an isovalue change
// bumps the epoch, which invalidates every cached code at once).
//
// Rays live in index space (sample data[i,j,k] at (i,j,k)); the ray parameter t is in world
// units: u(t) = eye_u + t * d_u with d_u = d_world / spacing. For precision, traversal uses
// s = t - t0 measured from the entry point into the (box ∩ clip planes) interval.
//
// Bricks (sort-last rendering of a bigger volume, splineviz.compute.bricked): index space,
// data box, clip planes and pixels are always those of the whole volume and frame. A brick's
// samples are a part of the whole volume's: cell c of the whole grid reads the brick's
// samples and octree at c - cell_off, and the traversal keeps to the brick's own cells
// [cell_lo, cell_hi). So every float a brick's ray computes (entry point, cell boundary
// parameters, the restriction to the ray in each cell, its roots) is the one the ray of a
// single cast of the whole volume computes in the same cell: the bricks' first hits are the
// single cast's, bit for bit. A single cast is the brick of all cells at offset 0; it is
// compiled without BRICKS, so that its loop carries none of the offsets and clamps (they
// cost it 3-8 % on PoCL).
#ifdef BRICKS
#define LOCAL_CELL(c) ((c) - cell_off)
#define FIRST_CELL cell_lo
#define END_CELL cell_hi
#else
#define LOCAL_CELL(c) (c)
#define FIRST_CELL ((int3)(0))
#define END_CELL grid_cells
#endif

#ifndef DATA_T
#define DATA_T float  // samples as Volume holds them (the host names a smaller exact type)
#endif
// offset of a sample in `data` (a plugin's prelude, read before this file, may define it)
#ifndef offset_t
#ifdef OFFSET64
#define offset_t long
#else
#define offset_t int
#endif
#endif
#define BISECT_STEPS 40
// Minimum and maximum for the per-cell and per-point loops: PoCL calls fmin/fmax out of
// line, and those calls were a seventh of a to-quadratic frame. As fmin/fmax do, a NaN x is
// ignored (the accumulator acc never is NaN where they are used).
inline float min_acc(float acc, float x) { return x < acc ? x : acc; }
inline float max_acc(float acc, float x) { return x > acc ? x : acc; }
// low 24 bits of a cache entry (the top 8 bits hold the epoch of its isovalue)
#define CODE_MASK 0xFFFFFFu
// a cache slot claimed by a ray that is allocating its pool entry
#define ENTRY_BUSY CODE_MASK

// Monomial coefficients of the trilinear interpolant on [0,1]^3:
// f = a + bx x + by y + bz z + bxy xy + bxz xz + byz yz + bxyz xyz
typedef struct {
    float a, bx, by, bz, bxy, bxz, byz, bxyz;
} Trilinear;

inline Trilinear trilinear_coeffs(__global const DATA_T *data, int3 cell, int SY, int SZ)
{
    const offset_t base = ((offset_t)cell.x * SY + cell.y) * SZ + cell.z;
    const int sx = SY * SZ, sy = SZ;
    const float c000 = data[base], c001 = data[base + 1];
    const float c010 = data[base + sy], c011 = data[base + sy + 1];
    const float c100 = data[base + sx], c101 = data[base + sx + 1];
    const float c110 = data[base + sx + sy], c111 = data[base + sx + sy + 1];
    Trilinear t;
    t.a = c000;
    t.bx = c100 - c000;
    t.by = c010 - c000;
    t.bz = c001 - c000;
    t.bxy = c110 - c100 - c010 + c000;
    t.bxz = c101 - c100 - c001 + c000;
    t.byz = c011 - c010 - c001 + c000;
    t.bxyz = c111 - c110 - c101 - c011 + c100 + c010 + c001 - c000;
    return t;
}

inline float tri_value(const Trilinear *f, float3 p)
{
    return f->a + f->bx * p.x + f->by * p.y + f->bz * p.z + f->bxy * p.x * p.y
           + f->bxz * p.x * p.z + f->byz * p.y * p.z + f->bxyz * p.x * p.y * p.z;
}

inline float3 tri_gradient(const Trilinear *f, float3 p)
{
    return (float3)(f->bx + f->bxy * p.y + f->bxz * p.z + f->bxyz * p.y * p.z,
                    f->by + f->bxy * p.x + f->byz * p.z + f->bxyz * p.x * p.z,
                    f->bz + f->bxz * p.x + f->byz * p.y + f->bxyz * p.x * p.y);
}

inline float cubic(float4 k, float s) { return k.x + s * (k.y + s * (k.z + s * k.w)); }

// Restriction of f - iso to the ray p + s d: k.x + k.y s + k.z s^2 + k.w s^3 (exact).
inline float4 tri_ray_cubic(const Trilinear *f, float3 p, float3 d, float iso)
{
    const float3 g = tri_gradient(f, p);
    float4 k;
    k.x = tri_value(f, p) - iso;
    k.y = dot(g, d);
    k.z = f->bxy * d.x * d.y + f->bxz * d.x * d.z + f->byz * d.y * d.z
          + f->bxyz * (d.x * d.y * p.z + d.x * p.y * d.z + p.x * d.y * d.z);
    k.w = f->bxyz * d.x * d.y * d.z;
    return k;
}

// Roots of a + b s + c s^2 = 0 (numerically stable form); returns the number found.
inline int quadratic_roots(float a, float b, float c, float *r0, float *r1)
{
    if (c == 0.0f) {
        if (b == 0.0f) return 0;
        *r0 = -a / b;
        return 1;
    }
    const float disc = b * b - 4.0f * a * c;
    if (disc < 0.0f) return 0;
    const float q = -0.5f * (b + copysign(sqrt(disc), b));
    if (q == 0.0f) {  // b == 0 and a == 0: double root at 0
        *r0 = 0.0f;
        return 1;
    }
    float x0 = q / c, x1 = a / q;
    *r0 = min_acc(x0, x1);
    *r1 = max_acc(x0, x1);
    return 2;
}

// First root of the cubic k in [0, len]; -1 if none. The cubic is split at its critical
// points into monotone pieces, so a sign test on each piece cannot miss a root.
inline float first_cubic_root(float4 k, float len)
{
    float br[4];
    int n = 0;
    br[n++] = 0.0f;
    float r0, r1;
    const int nr = quadratic_roots(k.y, 2.0f * k.z, 3.0f * k.w, &r0, &r1);
    if (nr >= 1 && r0 > 0.0f && r0 < len) br[n++] = r0;
    if (nr == 2 && r1 > 0.0f && r1 < len && r1 != r0) br[n++] = r1;
    br[n++] = len;
    float a = br[0];
    float ga = cubic(k, a);
    for (int p = 1; p < n; ++p) {
        if (ga == 0.0f) return a;
        const float b = br[p];
        const float gb = cubic(k, b);
        if ((ga < 0.0f) != (gb < 0.0f)) {
            // bisection to float resolution, then one Newton step kept inside the bracket
            float lo = a, hi = b;
            const bool neg = ga < 0.0f;
            for (int it = 0; it < BISECT_STEPS && hi - lo > 0.0f; ++it) {
                const float m = 0.5f * (lo + hi);
                if (m <= lo || m >= hi) break;
                const float gm = cubic(k, m);
                if (gm == 0.0f) return m;
                if ((gm < 0.0f) == neg) lo = m; else hi = m;
            }
            float s = 0.5f * (lo + hi);
            const float dg = k.y + s * (2.0f * k.z + 3.0f * k.w * s);
            if (dg != 0.0f) {
                const float sn = s - cubic(k, s) / dg;
                if (sn >= lo && sn <= hi) s = sn;
            }
            return s;
        }
        a = b;
        ga = gb;
    }
    if (ga == 0.0f) return a;
    return -1.0f;
}


#if defined(MODEL_TYPE6) || defined(MODEL_TO)
#define NCOEF ((DEGREE + 1) * (DEGREE + 2) * (DEGREE + 3) / 6)
#define NCHUNK ((NCOEF + 7) / 8)  // float8s of a dense tet mask row
#if DEGREE == 3
#define NRED (10 + 4 + 1)
#else
#define NRED (4 + 1)
#endif

// One de Casteljau step (thesis §3.4.1) from degree k to k-1 with the barycentric argument
// lam; red[a*4 + m] is the position of alpha + e_m among the degree-k indices.
inline void decasteljau(const float *in, float *out, int n_out, __constant const int *red,
                        float4 lam)
{
    for (int a = 0; a < n_out; ++a)
        out[a] = lam.x * in[red[4 * a]] + lam.y * in[red[4 * a + 1]]
                 + lam.z * in[red[4 * a + 2]] + lam.w * in[red[4 * a + 3]];
}

// The DEGREE-1 fold de Casteljau at lam: the 4 linear coefficients whose combination with the
// barycentric gradients gives the gradient (thesis §3.4.2).
inline float4 linear_part(const float *c, __constant const int *red, float4 lam)
{
    float t1[10], t2[4];
#if DEGREE == 3
    decasteljau(c, t1, 10, red, lam);
    decasteljau(t1, t2, 4, red + 40, lam);
#else
    for (int i = 0; i < 10; ++i) t1[i] = c[i];
    decasteljau(t1, t2, 4, red, lam);
#endif
    return (float4)(t2[0], t2[1], t2[2], t2[3]);
}
#endif

inline float3 exit_params(float3 ue, float3 d, float3 inv_d, int3 lo, int3 hi)
{
    // parameters where the ray leaves the box [lo, hi] through the plane chosen by the
    // Heaviside of each direction component (thesis §6.2.1)
    const float3 bound = (float3)(d.x >= 0.0f ? (float)hi.x : (float)lo.x,
                                  d.y >= 0.0f ? (float)hi.y : (float)lo.y,
                                  d.z >= 0.0f ? (float)hi.z : (float)lo.z);
    float3 t = (bound - ue) * inv_d;
    // axis-parallel rays never leave through that axis
    t.x = d.x == 0.0f ? INFINITY : t.x;
    t.y = d.y == 0.0f ? INFINITY : t.y;
    t.z = d.z == 0.0f ? INFINITY : t.z;
    return t;
}

inline int argmin3(float3 t) { return (t.x <= t.y && t.x <= t.z) ? 0 : (t.y <= t.z ? 1 : 2); }

// Where a ray whose traversal starts outside the cells [lo, hi) of a brick enters them: the
// parameter *s (from the entry point we, cell coordinates) of the crossing with the box of
// those cells, computed as the whole grid's traversal computes cell boundaries ((plane - we)
// / d), and the cell there; false when the ray misses them before `send`.
#ifdef BRICKS
inline bool enter_cells(float3 we, float3 d, float3 inv_d, int3 lo, int3 hi, float send,
                        float *s, int3 *cell)
{
    const float3 flo = convert_float3(lo), fhi = convert_float3(hi);
    const float3 ta = (flo - we) * inv_d, tb = (fhi - we) * inv_d;
    float3 tn = fmin(ta, tb), tf = fmax(ta, tb);
    // axis-parallel rays: inside the slab or never
    if (d.x == 0.0f) { tn.x = (we.x >= flo.x && we.x <= fhi.x) ? -INFINITY : INFINITY; tf.x = -tn.x; }
    if (d.y == 0.0f) { tn.y = (we.y >= flo.y && we.y <= fhi.y) ? -INFINITY : INFINITY; tf.y = -tn.y; }
    if (d.z == 0.0f) { tn.z = (we.z >= flo.z && we.z <= fhi.z) ? -INFINITY : INFINITY; tf.z = -tn.z; }
    const float s0 = fmax(0.0f, fmax(tn.x, fmax(tn.y, tn.z)));
    const float s1 = fmin(send, fmin(tf.x, fmin(tf.y, tf.z)));
    if (!(s0 < s1)) return false;
    int3 c = clamp(convert_int3_rtn(we + s0 * d), lo, hi - 1);
    // the axis of the face it enters through from integers, not from the rounded point
    if (tn.x >= tn.y && tn.x >= tn.z) c.x = d.x > 0.0f ? lo.x : hi.x - 1;
    else if (tn.y >= tn.z) c.y = d.y > 0.0f ? lo.y : hi.y - 1;
    else c.z = d.z > 0.0f ? lo.z : hi.z - 1;
    *s = s0;
    *cell = c;
    return true;
}
#endif

// Skip index of `cell` at isovalue iso (thesis §6.2.1): -1 when the bounds of its level-1
// node (2^3 cells) straddle iso (the cell is a candidate; its own bounds are not stored, the
// cell's classification decides), else the highest level L whose octree node holding the cell
// has bounds that exclude iso (an empty macro cube of 2^L cells). A node's bounds contain
// those of its children (reduce_level), so the levels whose node excludes iso are 1..L: the
// walk goes down from the top and stops at the first node that excludes iso. Top down, not
// bottom up: the upper levels are small and stay in the caches, while level 1 (8 bytes per
// 2^3 cells, 17 MB at 256^3) is read only for the cells next to the surface; read first for
// every step of every ray, its cache misses were two fifths of the ray kernel's own time.
// levels[l - 1] is level l.
inline int skip_level(__global const float2 *bounds, __constant const int4 *levels,
                      int n_levels, int3 cell, float iso)
{
    for (int l = n_levels; l >= 1; --l) {
        const int4 lv = levels[l - 1];
        const float2 b = bounds[lv.x + (((cell.x >> l) * lv.z + (cell.y >> l)) * lv.w
                                        + (cell.z >> l))];
        if (!(b.x <= iso && iso <= b.y)) return l;
    }
    return -1;
}

// Skip codes of all CX x CY x CZ cells (SKIP_ACTIVE or the macro level), for inspection and
// tests: the same skip_level the ray kernel evaluates on the fly.
__kernel void skip_codes(__global const float2 *bounds, __constant const int4 *levels,
                         int n_levels, int CX, int CY, int CZ, float iso, __global uchar *skip)
{
    const int k = get_global_id(0), j = get_global_id(1), i = get_global_id(2);
    if (i >= CX || j >= CY || k >= CZ) return;
    const int L = skip_level(bounds, levels, n_levels, (int3)(i, j, k), iso);
    skip[(i * CY + j) * CZ + k] = L < 0 ? SKIP_ACTIVE : (uchar)L;
}

#if defined(MODEL_TYPE6) || defined(MODEL_TO)
// The part [*lo, *hi] of the segment p0 + s d, s in [0, hi], inside the tetrahedron with
// barycentric rows r0..r3 (its four plane equations, thesis §6.2.2); false if empty.
// l and av receive the barycentric coordinates at s = 0 and their change per unit s.
inline bool tet_interval(float4 r0, float4 r1, float4 r2, float4 r3, float3 p0, float3 d,
                         float *lo_out, float *hi_io, float4 *l_out, float4 *av_out)
{
    // the rows' dot products written out: PoCL calls dot out of line
    const float4 l = (float4)(r0.x * p0.x + r0.y * p0.y + r0.z * p0.z + r0.w,
                              r1.x * p0.x + r1.y * p0.y + r1.z * p0.z + r1.w,
                              r2.x * p0.x + r2.y * p0.y + r2.z * p0.z + r2.w,
                              r3.x * p0.x + r3.y * p0.y + r3.z * p0.z + r3.w);
    const float4 av = (float4)(r0.x * d.x + r0.y * d.y + r0.z * d.z,
                               r1.x * d.x + r1.y * d.y + r1.z * d.z,
                               r2.x * d.x + r2.y * d.y + r2.z * d.z,
                               r3.x * d.x + r3.y * d.y + r3.z * d.z);
    float lo = 0.0f, hi = *hi_io;
    const float lv[4] = {l.x, l.y, l.z, l.w}, avv[4] = {av.x, av.y, av.z, av.w};
    for (int m = 0; m < 4; ++m) {
        // a tiny slack keeps rays on shared faces from falling between two tets
        const float lm = lv[m] + TET_SLACK;
        if (avv[m] > 0.0f) lo = max_acc(lo, -lm / avv[m]);
        else if (avv[m] < 0.0f) hi = min_acc(hi, -lm / avv[m]);
        else if (lm < 0.0f) return false;
    }
    *lo_out = lo;
    *hi_io = hi;
    *l_out = l;
    *av_out = av;
    return lo <= hi;
}

// Index-space Hessian of the polynomial with B-coefficients c at lam (xx, yy, zz, xy, xz, yz):
// the DEGREE-2 fold de Casteljau leaves the quadratic coefficients q_{e_m + e_n}, and
// D^2 p = DEGREE (DEGREE - 1) sum_{m,n} q_{e_m + e_n} grad(lam_m) grad(lam_n)^T (thesis
// §3.4.2, one order further; colour by curvature, Kindlmann et al. 2003).
inline void tet_hessian(const float *c, __constant const int *red, float4 lam, float4 r0,
                        float4 r1, float4 r2, float4 r3, float *hess)
{
#if DEGREE == 3
    float q[10];
    decasteljau(c, q, 10, red, lam);
    __constant const int *red2 = red + 40;  // degree 2 -> 1 table: position of e_m + e_n
#else
    const float *q = c;
    __constant const int *red2 = red;
#endif
    const float3 r[4] = {r0.xyz, r1.xyz, r2.xyz, r3.xyz};
    float3 hx = (float3)(0.0f), hy = (float3)(0.0f), hz = (float3)(0.0f);
    for (int m = 0; m < 4; ++m) {
        float3 a = (float3)(0.0f);
        for (int n = 0; n < 4; ++n) a += q[red2[4 * m + n]] * r[n];
        hx += r[m].x * a;
        hy += r[m].y * a;
        hz += r[m].z * a;
    }
    const float f = (float)(DEGREE * (DEGREE - 1));
    hess[0] = f * hx.x; hess[1] = f * hy.y; hess[2] = f * hz.z;
    hess[3] = f * hx.y; hess[4] = f * hx.z; hess[5] = f * hy.z;
}

// First root of the polynomial with B-coefficients c (already minus iso) on [lo, hi] of the
// ray, from the blossoms of the segment (thesis §6.1.2); -1 if none; *grad at the root, and
// the Hessian there in hess[6] when want_hess.
inline float tet_segment_root(const float *c, __constant const int *red, float4 r0, float4 r1,
                              float4 r2, float4 r3, float4 l, float4 av, float lo, float hi,
                              float3 *grad, int want_hess, float *hess)
{
    const float4 lam0 = l + lo * av, lam1 = l + hi * av;
    // the blossoms b(lam0^(DEGREE - j), lam1^j) (thesis §3.4.3): segment_blossoms, generated
    // by splineviz/compute/raycast/segment_program.py and prepended to this file
    const float4 b = segment_blossoms(c, lam0, lam1);
    float4 k;
#if DEGREE == 3
    k = (float4)(b.x, 3.0f * (b.y - b.x), 3.0f * (b.z - 2.0f * b.y + b.x),
                 b.w - 3.0f * b.z + 3.0f * b.y - b.x);
#else
    k = (float4)(b.x, 2.0f * (b.y - b.x), b.z - 2.0f * b.y + b.x, 0.0f);
#endif
    const float u = first_cubic_root(k, 1.0f);
    if (u < 0.0f) return -1.0f;
    const float sh = lo + u * (hi - lo);
    const float4 e = linear_part(c, red, l + sh * av);
    // grad p = DEGREE * sum_m e_m grad(lam_m)
    *grad = DEGREE * (e.x * r0.xyz + e.y * r1.xyz + e.z * r2.xyz + e.w * r3.xyz);
    if (want_hess) tet_hessian(c, red, l + sh * av, r0, r1, r2, r3, hess);
    return sh;
}
#endif

#if defined(MODEL_TYPE6) || defined(MODEL_TO)
// ---- the classification cache (visible-first classification, thesis §6.1.1, §6.2.3) ----
// Per level-1 node of the octree (a brick of 2^3 cells) one slot: (epoch << 24) | pool
// entry; a slot of an older epoch (another isovalue) is invalid. A pool entry holds
// CELL_WORDS words for each of the brick's 8 cells: type-6: VALID | the 24-bit tet code;
// TO: the NWORDS words of the relevance bit set, then a word that is 1 once they are written.
// Only the bricks the rays reach take pool entries.
#ifdef MODEL_TYPE6
#define CELL_WORDS 1
#else
#define CELL_WORDS (NWORDS + 1)
#endif
#define VALID 0x80000000u

// Pool entry of the brick holding `cell` at this epoch, allocated (zeroed) and published by
// the first ray that needs it; -1 when the pool is full or another ray is allocating it (the
// caller then works uncached; counts[2], the entries asked for, tells the host to grow the
// pool). The slot is claimed (ENTRY_BUSY) before the entry is allocated: allocating first,
// the rays that met a new brick at once took an entry each and all but one were lost (on an
// H200, 8557 entries for 1421 cells).
inline int brick_entry(__global uint *slots, __global uint *pool, int pool_cap, uint epoch,
                       int3 cell, int BY, int BZ, __global int *counts)
{
    const int b = ((cell.x >> 1) * BY + (cell.y >> 1)) * BZ + (cell.z >> 1);
    // volatile loads of the cache: another work-group may have published the brick since,
    // and a GPU's non-coherent L1 could still hold the line from before (seen on an H200:
    // one ray in ~7000 read an entry's stale words and missed its first root)
    const uint e = ((volatile __global const uint *)slots)[b];
    if ((e >> 24) == epoch) {
        if ((e & CODE_MASK) == ENTRY_BUSY) return -1;
        read_mem_fence(CLK_GLOBAL_MEM_FENCE);  // the slot before its entry's words
        return (int)(e & CODE_MASK);
    }
    const uint busy = (epoch << 24) | ENTRY_BUSY;
    const uint old = atomic_cmpxchg((volatile __global uint *)&slots[b], e, busy);
    if (old != e) {
        // another ray claimed the brick first
        if ((old >> 24) != epoch || (old & CODE_MASK) == ENTRY_BUSY) return -1;
        read_mem_fence(CLK_GLOBAL_MEM_FENCE);
        return (int)(old & CODE_MASK);
    }
    const int a = atomic_inc(&counts[2]);
    if (a >= pool_cap) {
        atomic_xchg((volatile __global uint *)&slots[b], e);  // a later frame takes it
        return -1;
    }
    for (int w = 0; w < 8 * CELL_WORDS; ++w) pool[a * 8 * CELL_WORDS + w] = 0u;
    mem_fence(CLK_GLOBAL_MEM_FENCE);  // the zeroed entry before its slot
    atomic_xchg((volatile __global uint *)&slots[b], (epoch << 24) | (uint)a);
    return a;
}

// First word of `cell`'s part of pool entry a.
inline int cell_word(int a, int3 cell)
{
    return (a * 8 + (((cell.x & 1) << 2) | ((cell.y & 1) << 1) | (cell.z & 1))) * CELL_WORDS;
}
#endif

#ifdef MODEL_TYPE6
// First root of the type-6 spline - iso on the ray segment p0 + s d, s in [0, len], inside the
// cube centred at the origin of p; only the tets whose bit is set in `code` are tested.
// Each tet's part of the segment comes from its four barycentric plane equations (§6.2.2).
inline float type6_cube_root(__global const DATA_T *pdata, offset_t base,
                             __constant const int *stencil, __global const float8 *tet_weights,
                             __constant const float4 *bary, __constant const int *red,
                             uint code, float3 p0, float3 d, float len, float iso,
                             float3 *grad, int want_hess, float *hess)
{
    float vals[27];
    for (int q = 0; q < 27; ++q) vals[q] = pdata[base + stencil[q]];
    float best = -1.0f;
    for (int t = 0; t < 24; ++t) {
        if (!(code & (1u << t))) continue;
        const float4 r0 = bary[4 * t], r1 = bary[4 * t + 1], r2 = bary[4 * t + 2],
                     r3 = bary[4 * t + 3];
        float lo, hi = best >= 0.0f ? best : len;
        float4 l, av;
        if (!tet_interval(r0, r1, r2, r3, p0, d, &lo, &hi, &l, &av)) continue;
        // the dense tet mask: each stencil value feeds the NCOEF coefficients' independent
        // sums, NCHUNK float8s at a time (sparse rows made one serial chain per coefficient)
        // (three named float8s, not an array: the array's address, taken to read its floats,
        // kept the sums in memory, one store and reload per multiply-add, two fifths of this
        // function's time on PoCL; the same sums in the same order)
        __global const float8 *wt = tet_weights + t * 27 * NCHUNK;
        float8 a0 = (float8)(0.0f), a1 = (float8)(0.0f);
#if NCHUNK == 3
        float8 a2 = (float8)(0.0f);
#endif
        for (int q = 0; q < 27; ++q) {
            const float v = vals[q];
            a0 += wt[q * NCHUNK] * v;
            a1 += wt[q * NCHUNK + 1] * v;
#if NCHUNK == 3
            a2 += wt[q * NCHUNK + 2] * v;
#endif
        }
        // the coefficients of p - iso (constants reproduce exactly)
        const float8 i8 = (float8)(iso);
        a0 -= i8;
        a1 -= i8;
#if NCHUNK == 3
        a2 -= i8;
        const float c[NCOEF] = {a0.s0, a0.s1, a0.s2, a0.s3, a0.s4, a0.s5, a0.s6, a0.s7,
                                a1.s0, a1.s1, a1.s2, a1.s3, a1.s4, a1.s5, a1.s6, a1.s7,
                                a2.s0, a2.s1, a2.s2, a2.s3};
#else
        const float c[NCOEF] = {a0.s0, a0.s1, a0.s2, a0.s3, a0.s4, a0.s5, a0.s6, a0.s7,
                                a1.s0, a1.s1};
#endif
        float3 g;
        float h6[6];
        const float sh = tet_segment_root(c, red, r0, r1, r2, r3, l, av, lo, hi, &g,
                                          want_hess, h6);
        if (sh >= 0.0f && (best < 0.0f || sh < best)) {
            best = sh;
            *grad = g;
            if (want_hess)
                for (int i = 0; i < 6; ++i) hess[i] = h6[i];
        }
    }
    return best;
}

// The 24-bit tet code of the cube whose stencil starts at `base`: bit t set when the
// B-coefficients of tet t straddle the isovalue (convex hull property, thesis §6.1.1). First
// the cheap cube bounds of classify.cl (stencil range widened by the negative weight mass):
// most cubes the rays reach end there. Then all cube coefficients by the cube program: the
// determining set from the 27 stencil values, every other coefficient by the smoothness
// (averaging) rules from already computed ones (thesis §5.1-5.2, eq. (5.2);
// type6_rules.apply_rules is the NumPy reference), written out as straight-line code with
// the tet masks as literals (type6_points_code, generated by
// splineviz/compute/raycast/type6_program.py and prepended to this file).
inline uint type6_tet_code(__global const DATA_T *pdata, offset_t base,
                           __constant const int *stencil, float negmass, float iso)
{
    float vals[27];
    float vlo = INFINITY, vhi = -INFINITY;
    for (int q = 0; q < 27; ++q) {
        vals[q] = pdata[base + stencil[q]];
        vlo = min_acc(vlo, vals[q]);
        vhi = max_acc(vhi, vals[q]);
    }
    const float w = negmass * (vhi - vlo);
    if (!(vlo - w <= iso && iso <= vhi + w)) return 0u;
    return type6_points_code(vals, iso);
}

// The tet code of `cube` at this epoch: from the brick cache, or computed and stored. The
// first ray to store a cube's code also counts it (counts[0] cubes with a relevant tet,
// counts[1] relevant tets); rays that raced it computed the same code and count nothing.
inline uint type6_cached_code(__global uint *slots, __global uint *pool, int pool_cap,
                              uint epoch, int3 cube, int BY, int BZ,
                              __global const DATA_T *pdata, offset_t base,
                              __constant const int *stencil, float negmass, float iso,
                              __global int *counts)
{
    const int a = brick_entry(slots, pool, pool_cap, epoch, cube, BY, BZ, counts);
    const int at = a >= 0 ? cell_word(a, cube) : 0;
    if (a >= 0) {
        const uint v = ((volatile __global const uint *)pool)[at];
        if (v & VALID) return v & CODE_MASK;
    }
    const uint code = type6_tet_code(pdata, base, stencil, negmass, iso);
    if (a >= 0 && atomic_cmpxchg((volatile __global uint *)&pool[at], 0u, VALID | code) == 0u
        && code != 0u) {
        atomic_inc(&counts[0]);
        atomic_add(&counts[1], (int)popcount(code));
    }
    return code;
}

// Pool entries of the listed level-1 bricks (flat slot indices, each listed once), taken
// before tet_codes writes their cubes' words: there the 8 cubes of a brick race for its
// entry, and on a GPU the cubes that met it busy (claimed, not yet published) would leave
// their words out of the cache (on an H200, 7 in 10 of classify_all's words).
__kernel void brick_entries(__global const int *bricks, __global uint *slots,
                            __global uint *pool, int pool_cap, uint epoch, int BY, int BZ,
                            __global int *counts)
{
    const int b = bricks[get_global_id(0)];
    const int3 cell = 2 * (int3)(b / (BY * BZ), (b / BZ) % BY, b % BZ);
    brick_entry(slots, pool, pool_cap, epoch, cell, BY, BZ, counts);
}

// Classification of all candidate cubes at once (RayCaster.classify_all): their tet codes,
// written to the brick cache at this epoch (brick_entries published their entries first),
// and per candidate the code and its relevant tets.
__kernel void tet_codes(__global const DATA_T *pdata, int PY, int PZ, int NY, int NZ,
                        __global const int *cubes, __constant const int *stencil,
                        float negmass, float iso, __global uint *slots, __global uint *pool,
                        int pool_cap, uint epoch, int BY, int BZ, __global int *counts,
                        __global uint *code_out, __global int *n_relevant)
{
    const int g = get_global_id(0);
    const int cube = cubes[g];
    const int k = cube % NZ, j = (cube / NZ) % NY, i = cube / (NY * NZ);
    const offset_t base = (((offset_t)i + 1) * PY + (j + 1)) * PZ + (k + 1);
    const uint code = type6_tet_code(pdata, base, stencil, negmass, iso);
    const int3 c3 = (int3)(i, j, k);
    const int a = brick_entry(slots, pool, pool_cap, epoch, c3, BY, BZ, counts);
    if (a >= 0) pool[cell_word(a, c3)] = VALID | code;
    code_out[g] = code;
    n_relevant[g] = popcount(code);
}
#endif

#ifdef MODEL_TO
// Relevance bit set of the (TO, tet) pieces of a cell (bit e - ent_start[cls]: the piece's
// B-coefficients straddle the isovalue, the thesis' tet code for the 144 tets of a TO);
// returns the number of relevant pieces. The data a cell's pieces read (the class union, at
// most NUNION values) are gathered once. First the cheap cell bounds of classify.cl (their
// range widened by the negative weight mass): most cells the rays reach end there. Then each
// distinct B-net point of the class's pieces is computed once: min <= iso <= max over a
// piece's coefficients iff one is <= iso and one is >= iso, so each point marks the pieces
// whose B-net holds it in two masks (to_class_points, generated from the class tables by
// splineviz/compute/raycast/to_program.py and prepended to this file). *range receives a bound of
// the spline on the cell that does not depend on the isovalue: the points' (min, max) when
// they were computed, else the cheap bounds.
inline int to_relevance(__global const DATA_T *pdata, offset_t corner, int cls,
                        __constant const int *cls_start, __constant const int *cls_offsets,
                        float negmass, float iso, uint *words, float2 *range)
{
    float vals[NUNION];
    const int u0 = cls_start[cls], nu = cls_start[cls + 1] - u0;
    float vlo = INFINITY, vhi = -INFINITY;
    for (int u = 0; u < nu; ++u) {
        vals[u] = pdata[corner + cls_offsets[u0 + u]];
        vlo = min_acc(vlo, vals[u]);
        vhi = max_acc(vhi, vals[u]);
    }
    const float wid = negmass * (vhi - vlo);
    if (!(vlo - wid <= iso && iso <= vhi + wid)) {
        for (int w = 0; w < NWORDS; ++w) words[w] = 0u;
        *range = (float2)(vlo - wid, vhi + wid);
        return 0;
    }
    return to_class_points(vals, cls, iso, words, range);
}

// ---- the cell ranges (isovalue-independent, kept while the data stay) ----
// Per cell 2 bytes (8 per level-1 node, in the order of cell_word): the (min, max) of its B-net points (or its cheap bounds) quantised to
// 1/255 of the bounds of its level-1 octree node, rounded outwards by one more step; (0, 255)
// means "not known yet" (the node's bounds). Filled by the first classification of a cell at
// any isovalue, they let every later isovalue skip the cells whose range excludes it with a
// 2-byte read instead of their ~150-365 point sums (about 6 in 10 of the cells rays classify).
// A cell whose range excludes iso has no point <= iso (or none >= iso), so its bit set is 0:
// the skip gives the very bits the sums would.

// Size of a quantisation step of the node bounds nb; 0 when the steps are too fine for float
// rounding (a few hundred ulps of the values) to stay inside the extra step.
inline float range_step(float2 nb)
{
    const float step = (nb.y - nb.x) * (1.0f / 255.0f);
    // comparisons, not fmax/fabs: PoCL calls those out of line
    const float scale = max_acc(nb.x < 0.0f ? -nb.x : nb.x, nb.y < 0.0f ? -nb.y : nb.y);
    return (isfinite(step) && step > 1e-5f * scale) ? step : 0.0f;
}

// Whether the quantised range q of a cell in node bounds nb excludes iso.
inline bool range_excludes(uchar2 q, float2 nb, float iso)
{
    const float step = range_step(nb);
    if (step == 0.0f) return false;
    return (q.x > 0 && iso < nb.x + (float)q.x * step)
           || (q.y < 255 && iso > nb.x + (float)q.y * step);
}

// Quantised range of the (lo, hi) bound r of a cell in node bounds nb, rounded outwards.
inline uchar2 range_quantise(float2 r, float2 nb)
{
    const float step = range_step(nb);
    if (step == 0.0f || !(r.x <= r.y)) return (uchar2)(0, 255);
    const float a = floor((r.x - nb.x) / step) - 1.0f, b = ceil((r.y - nb.x) / step) + 1.0f;
    return (uchar2)((uchar)clamp(a, 0.0f, 255.0f), (uchar)clamp(b, 0.0f, 255.0f));
}

// The bit set of `cell` at this epoch. A cell whose known range (ranges, see above) excludes
// iso is 0 at once, from two bytes: it takes no pool entry and no atomics (at a new isovalue
// about 6 in 10 of the cells the rays classify end here). Otherwise from the brick cache, or
// computed by this ray and stored (words first, then the written flag), and the range of a
// newly classified cell is stored for the next isovalues. The first ray to store a cell
// counts it (counts[0] cells with a relevant piece, counts[1] relevant pieces).
inline void to_cached_bits(__global uint *slots, __global uint *pool, int pool_cap,
                           uint epoch, int3 cell, int BY, int BZ,
                           __global const DATA_T *pdata, offset_t corner, int cls,
                           __constant const int *cls_start, __constant const int *cls_offsets,
                           float negmass, float iso, __global int *counts,
                           __global uchar2 *ranges, __global const float2 *bounds,
                           uint *words)
{
    // level 1 of the octree is stored first (offset 0) with the node strides BY, BZ; the
    // ranges of a node's 8 cells lie together
    const int node = ((cell.x >> 1) * BY + (cell.y >> 1)) * BZ + (cell.z >> 1);
    const float2 nb = bounds[node];
    const int ci = 8 * node + (((cell.x & 1) << 2) | ((cell.y & 1) << 1) | (cell.z & 1));
    const uchar2 q = ranges[ci];
    if (range_excludes(q, nb, iso)) {
        for (int w = 0; w < NWORDS; ++w) words[w] = 0u;
        return;
    }
    const int a = brick_entry(slots, pool, pool_cap, epoch, cell, BY, BZ, counts);
    const int at = a >= 0 ? cell_word(a, cell) : 0;
    volatile __global const uint *vpool = pool;
    if (a >= 0 && vpool[at + NWORDS] != 0u) {
        read_mem_fence(CLK_GLOBAL_MEM_FENCE);  // the flag before the words it publishes
        for (int w = 0; w < NWORDS; ++w) words[w] = vpool[at + w];
        return;
    }
    float2 r;
    const int n = to_relevance(pdata, corner, cls, cls_start, cls_offsets, negmass, iso, words,
                               &r);
    if (q.x == 0 && q.y == 255) ranges[ci] = range_quantise(r, nb);
    if (a < 0) return;
    for (int w = 0; w < NWORDS; ++w) pool[at + w] = words[w];
    mem_fence(CLK_GLOBAL_MEM_FENCE);  // the words before their flag
    if (atomic_cmpxchg((volatile __global uint *)&pool[at + NWORDS], 0u, 1u) == 0u && n > 0) {
        atomic_inc(&counts[0]);
        atomic_add(&counts[1], n);
    }
}

// Classification of all candidate cells at once (RayCaster.classify_all): the bit set and
// the number of relevant pieces per candidate.
__kernel void to_codes(__global const DATA_T *pdata, int PY, int PZ, int CY, int CZ,
                       __global const int *cells, __constant const int *cls_start,
                       __constant const int *cls_offsets, float negmass, float iso,
                       __global uint *bits, __global int *n_relevant)
{
    const int a = get_global_id(0);
    const int cell = cells[a];
    const int k = cell % CZ, j = (cell / CZ) % CY, i = cell / (CY * CZ);
    const int cls = ((i & 1) << 2) | ((j & 1) << 1) | (k & 1);
    const offset_t corner = (((offset_t)i + GHOST) * PY + (j + GHOST)) * PZ + (k + GHOST);
    uint words[NWORDS];
    float2 range;
    n_relevant[a] = to_relevance(pdata, corner, cls, cls_start, cls_offsets, negmass, iso, words,
                                 &range);
    for (int w = 0; w < NWORDS; ++w) bits[a * NWORDS + w] = words[w];
}

// The pieces of class `cls` that the segment p0 + s d, s in [0, len], of a cell (cell-local
// p0) may meet: the union of the masks of the TO_SUB^3 subcells it crosses (to_sub_masks of
// the prelude, each subcell widened by a margin that covers rounding), found by a walk
// through the subcells. The walk never leaves the cell's subcells: a point of the segment
// just outside the cell (rounding of the cell traversal) counts to the boundary subcell.
inline void to_segment_pieces(int cls, int nw, float3 p0, float3 d, float len, uint *near)
{
    for (int w = 0; w < NWORDS; ++w) near[w] = 0u;
    const float3 q = p0 * (float)TO_SUB, dq = d * (float)TO_SUB;
    int3 c = clamp(convert_int3_rtn(q), (int3)(0), (int3)(TO_SUB - 1));
    for (int it = 0; it < 3 * TO_SUB; ++it) {
        __constant const uint *m = to_sub_masks
            + (((cls * TO_SUB + c.x) * TO_SUB + c.y) * TO_SUB + c.z) * NWORDS;
        for (int w = 0; w < nw; ++w) near[w] |= m[w];
        // the next crossing of an inner subcell plane per axis (none past the cell's last)
        const float tx = (dq.x > 0.0f && c.x < TO_SUB - 1) ? (c.x + 1 - q.x) / dq.x
                       : (dq.x < 0.0f && c.x > 0) ? (c.x - q.x) / dq.x : INFINITY;
        const float ty = (dq.y > 0.0f && c.y < TO_SUB - 1) ? (c.y + 1 - q.y) / dq.y
                       : (dq.y < 0.0f && c.y > 0) ? (c.y - q.y) / dq.y : INFINITY;
        const float tz = (dq.z > 0.0f && c.z < TO_SUB - 1) ? (c.z + 1 - q.z) / dq.z
                       : (dq.z < 0.0f && c.z > 0) ? (c.z - q.z) / dq.z : INFINITY;
        const float tn = min_acc(tx, min_acc(ty, tz));
        if (!(tn <= len)) break;
        if (tx == tn) c.x += dq.x > 0.0f ? 1 : -1;
        else if (ty == tn) c.y += dq.y > 0.0f ? 1 : -1;
        else c.z += dq.z > 0.0f ? 1 : -1;
    }
}

// First root of Q_k - iso on the segment p0 + s d, s in [0, len], in the unit cell whose
// corner is the origin of p0; the cell's (TO, tet) pieces come from its parity class and
// only those with their bit set in `words` are tested.
inline float to_cell_root(__global const DATA_T *pdata, offset_t corner, int cls, const uint *words,
                          __constant const int *ent_start,
                          __constant const float4 *ent_centre, __constant const int *ent_base,
                          __constant const int *ent_tet, __global const int *tet_offsets,
                          __global const float16 *tet_weights,
                          __constant const float4 *bary, __constant const int *red,
                          float3 p0, float3 d, float len, float iso, float3 *grad,
                          int want_hess, float *hess)
{
    float best = -1.0f;
    const int e0 = ent_start[cls];
    const int nw = (ent_start[cls + 1] - e0 + 31) >> 5;
    // only the pieces near the segment (about a third of the class's) need their planes
    uint near[NWORDS];
    to_segment_pieces(cls, nw, p0, d, len, near);
    // the set bits only (about 30 of the class's 64 or 144 pieces relevant, a third of them
    // near the segment), lowest first
    for (int w = 0; w < nw; ++w)
    for (uint bits = words[w] & near[w]; bits != 0u; bits &= bits - 1u) {
        const int e = e0 + (w << 5) + (31 - (int)clz(bits & (0u - bits)));
        const int t = ent_tet[e];
        const float4 r0 = bary[4 * t], r1 = bary[4 * t + 1], r2 = bary[4 * t + 2],
                     r3 = bary[4 * t + 3];
        const float3 pc = p0 - ent_centre[e].xyz;  // relative to the TO centre
        float lo, hi = best >= 0.0f ? best : len;
        float4 l, av;
        if (!tet_interval(r0, r1, r2, r3, pc, d, &lo, &hi, &l, &av)) continue;
        const offset_t base = corner + ent_base[e];
        // the dense stencil (every tet reads TO_STENCIL data values): each value feeds the
        // 10 coefficients' independent sums, where a sparse row per coefficient made one
        // serial chain of loads and multiply-adds (half the weights are zero)
        // (weights padded to a float16 per value: PoCL calls vload8/vload2 out of line)
        __global const int *off = tet_offsets + t * TO_STENCIL;
        __global const float16 *wt = tet_weights + t * TO_STENCIL;
        float16 acc = (float16)(0.0f);
        for (int m = 0; m < TO_STENCIL; ++m) acc += wt[m] * (float)pdata[base + off[m]];
        const float c[NCOEF] = {acc.s0 - iso, acc.s1 - iso, acc.s2 - iso, acc.s3 - iso,
                                acc.s4 - iso, acc.s5 - iso, acc.s6 - iso, acc.s7 - iso,
                                acc.s8 - iso, acc.s9 - iso};
        float3 g;
        float h6[6];
        const float sh = tet_segment_root(c, red, r0, r1, r2, r3, l, av, lo, hi, &g,
                                          want_hess, h6);
        if (sh >= 0.0f && (best < 0.0f || sh < best)) {
            best = sh;
            *grad = g;
            if (want_hess)
                for (int i = 0; i < 6; ++i) hess[i] = h6[i];
        }
    }
    return best;
}
#endif

__kernel void raycast(__global const DATA_T *data,   // samples; type-6: the padded samples
                      int NX, int NY, int NZ,        // whole volume's samples (box [0, n-1])
                      int SY, int SZ,                // strides of `data` (i*SY*SZ + j*SZ + k)
                      int3 grid_cells,               // cells of the whole traversal grid
                      int3 cell_lo, int3 cell_hi,    // the cells this cast traverses
                      int3 cell_off,                 // whole-grid cell of data/octree cell 0
                      float grid_shift,              // cell c covers [c, c+1) - shift in u
                      __global const float2 *bounds,  // min-max octree (classify.cl)
                      __constant const int4 *levels, int n_levels,
#if defined(MODEL_TYPE6) || defined(MODEL_TO)
                      __global uint *slots, __global uint *pool, int pool_cap, uint epoch,
                      int BY, int BZ, __global int *counts, float negmass,
#endif
#ifdef MODEL_TYPE6
                      __constant const int *stencil, __global const float8 *tet_weights,
                      __constant const float4 *bary, __constant const int *red,
#endif
#ifdef MODEL_TO
                      __global uchar2 *ranges,  // isovalue-independent cell ranges
                      __constant const int *cls_start,
                      __constant const int *cls_offsets, __constant const int *ent_start,
                      __constant const float4 *ent_centre, __constant const int *ent_base,
                      __constant const int *ent_tet, __global const int *tet_offsets,
                      __global const float16 *tet_weights,
                      __constant const float4 *bary, __constant const int *red,
#endif
                      float iso,
                      float3 eye_u,        // eye, index space
                      float3 dop, float3 right_s, float3 up_s,  // right/up scaled by tan
                      float3 inv_spacing,
                      __global const float4 *planes, int n_planes,  // index space: n.u + w >= 0
                      float depth_a, float depth_b,  // window depth = a - b / z_eye
                      __global uchar *hit_out, __global float4 *pos_out,
                      __global float4 *normal_out, __global float *depth_out,
                      __global uchar4 *color_out,
                      int want_hess,       // 1: write the world Hessian and |grad| per hit
                      __global float8 *hess_out,  // (xx, yy, zz, xy, xz, yz, |grad|, 0)
                      int W, int H,        // frame size
                      int C0, int R0,      // first column and row of the window cast ...
                      int WW, int WH)      // ... and its size (the outputs' rows); the launch
                                           // is padded to whole groups
{
    const int wcol = get_global_id(0), wrow = get_global_id(1);
    if (wcol >= WW || wrow >= WH) return;
    const int pix = wrow * WW + wcol;
    const int col = C0 + wcol, row = R0 + wrow;

    const float x = 2.0f * (col + 0.5f) / W - 1.0f;
    const float y = 1.0f - 2.0f * (row + 0.5f) / H;
    const float3 dw = normalize(dop + x * right_s + y * up_s);
    const float3 d = dw * inv_spacing;  // index-space direction per world unit
    const float3 inv_d = 1.0f / d;

    // interval of the ray inside the data box [0, n-1] ...
    const float3 hiB = (float3)(NX - 1, NY - 1, NZ - 1);
    float3 ta = (0.0f - eye_u) * inv_d, tb = (hiB - eye_u) * inv_d;
    float3 tn = fmin(ta, tb), tf = fmax(ta, tb);
    // axis-parallel rays: inside the slab or never
    if (d.x == 0.0f) { tn.x = (eye_u.x >= 0.0f && eye_u.x <= hiB.x) ? -INFINITY : INFINITY; tf.x = -tn.x; }
    if (d.y == 0.0f) { tn.y = (eye_u.y >= 0.0f && eye_u.y <= hiB.y) ? -INFINITY : INFINITY; tf.y = -tn.y; }
    if (d.z == 0.0f) { tn.z = (eye_u.z >= 0.0f && eye_u.z <= hiB.z) ? -INFINITY : INFINITY; tf.z = -tn.z; }
    float t0 = fmax(0.0f, fmax(tn.x, fmax(tn.y, tn.z)));
    float t1 = fmin(tf.x, fmin(tf.y, tf.z));
    // ... and on the kept side of every clip plane (an intersection of half-spaces)
    for (int p = 0; p < n_planes; ++p) {
        const float4 pl = planes[p];
        const float a0 = dot(pl.xyz, eye_u) + pl.w;
        const float b = dot(pl.xyz, d);
        if (b > 0.0f) t0 = fmax(t0, -a0 / b);
        else if (b < 0.0f) t1 = fmin(t1, -a0 / b);
        else if (a0 < 0.0f) t1 = -INFINITY;
    }

    bool found = false;
    float3 upos = (float3)(0.0f);
    float3 grad_u = (float3)(0.0f);
    float hess_u[6] = {0.0f, 0.0f, 0.0f, 0.0f, 0.0f, 0.0f};
    float t_hit = 0.0f;

    if (t0 <= t1) {
        const float3 ue = eye_u + t0 * d;           // entry point, index space
        const float3 we = ue + grid_shift;          // the same in cell coordinates
        const float send = t1 - t0;
        int3 cell = clamp(convert_int3_rtn(we), (int3)(0), grid_cells - 1);
        float s = 0.0f;
#ifdef BRICKS
        // the whole grid's first cell; a brick not holding it starts where the ray enters it
        const bool enters = (all(cell >= cell_lo) && all(cell < cell_hi))
                            || enter_cells(we, d, inv_d, cell_lo, cell_hi, send, &s, &cell);
        const int3 span = cell_hi - cell_lo;
        const int max_steps = enters ? 4 * (span.x + span.y + span.z) + 16 : 0;
#else
        const int max_steps = 4 * (grid_cells.x + grid_cells.y + grid_cells.z) + 16;
#endif
        for (int step = 0; step < max_steps; ++step) {
            const int3 lc = LOCAL_CELL(cell);  // the cell in this cast's data and octree
            const int L = skip_level(bounds, levels, n_levels, lc, iso);
            if (L < 0) {
                const float3 te = exit_params(we, d, inv_d, cell, cell + 1);
                const float s_exit = max_acc(s, min_acc(te.x, min_acc(te.y, te.z)));
                const float s_end = min_acc(s_exit, send);
#ifdef MODEL_TRILINEAR
                const Trilinear f = trilinear_coeffs(data, lc, SY, SZ);
                const float3 p = we + s * d - convert_float3(cell);
                const float4 k = tri_ray_cubic(&f, p, d, iso);
                const float r = first_cubic_root(k, s_end - s);
                if (r >= 0.0f) {
                    const float3 q = p + r * d;
                    upos = convert_float3(cell) + q;
                    grad_u = tri_gradient(&f, q);
                    // the trilinear piece has no pure second derivatives
                    hess_u[3] = f.bxy + f.bxyz * q.z;
                    hess_u[4] = f.bxz + f.bxyz * q.y;
                    hess_u[5] = f.byz + f.bxyz * q.x;
                    t_hit = t0 + s + r;
                    found = true;
                    break;
                }
#elif defined(MODEL_TO)
                const offset_t corner = (((offset_t)lc.x + GHOST) * SY + (lc.y + GHOST)) * SZ
                                   + (lc.z + GHOST);
                // (bricks of TO splines start at even offsets: the parity is the whole grid's)
                const int cls = ((lc.x & 1) << 2) | ((lc.y & 1) << 1) | (lc.z & 1);
                uint words[NWORDS];
                to_cached_bits(slots, pool, pool_cap, epoch, lc, BY, BZ, data, corner, cls,
                               cls_start, cls_offsets, negmass, iso, counts, ranges, bounds,
                               words);
                uint any_bit = 0u;
                for (int w = 0; w < NWORDS; ++w) any_bit |= words[w];
                if (any_bit != 0u) {
                    const float3 p = we + s * d - convert_float3(cell);
                    float3 g;
                    const float r = to_cell_root(data, corner, cls, words, ent_start,
                                                 ent_centre, ent_base, ent_tet, tet_offsets,
                                                 tet_weights, bary, red, p, d, s_end - s, iso, &g,
                                                 want_hess, hess_u);
                    if (r >= 0.0f) {
                        upos = convert_float3(cell) + p + r * d;
                        grad_u = g;
                        t_hit = t0 + s + r;
                        found = true;
                        break;
                    }
                }
#elif defined(MODEL_CUSTOM)
                // a plugin's family: data[base] is the first sample the cell reads
                const offset_t base = ((offset_t)lc.x * SY + lc.y) * SZ + lc.z;
                const float3 p = we + s * d - convert_float3(cell);
                float3 g;
                const float r = custom_cell_root(data, base, SY, SZ, p, d, s_end - s, iso, &g,
                                                 want_hess, hess_u);
                if (r >= 0.0f) {
                    upos = convert_float3(cell) + p + r * d;
                    grad_u = g;
                    t_hit = t0 + s + r;
                    found = true;
                    break;
                }
#else
                // cube centred at data point `cell`
                const offset_t base = (((offset_t)lc.x + 1) * SY + (lc.y + 1)) * SZ + (lc.z + 1);
                const uint tc = type6_cached_code(slots, pool, pool_cap, epoch, lc, BY, BZ,
                                                  data, base, stencil, negmass, iso,
                                                  counts);
                if (tc != 0u) {
                    const float3 p = ue + s * d - convert_float3(cell);  // from the centre
                    float3 g;
                    const float r = type6_cube_root(data, base, stencil, tet_weights,
                                                    bary, red, tc, p, d, s_end - s, iso, &g,
                                                    want_hess, hess_u);
                    if (r >= 0.0f) {
                        upos = convert_float3(cell) + p + r * d;
                        grad_u = g;
                        t_hit = t0 + s + r;
                        found = true;
                        break;
                    }
                }
#endif
                if (s_exit >= send) break;
                s = s_exit;
                const int a = argmin3(te);
                if (a == 0) cell.x += d.x > 0.0f ? 1 : -1;
                else if (a == 1) cell.y += d.y > 0.0f ? 1 : -1;
                else cell.z += d.z > 0.0f ? 1 : -1;
            } else {
                // empty-space leaping over the macro cube of 2^L cells (thesis §6.2.1);
                // the next cell comes from integer bounds, not from an epsilon step
#ifdef BRICKS
                // the octree's macro cube in whole-grid cells, within the brick
                const int3 mlo = ((lc >> L) << L) + cell_off;
                const int3 lo = max(mlo, cell_lo);
                const int3 hi = min(mlo + (1 << L), cell_hi);
#else
                const int3 lo = (cell >> L) << L;
                const int3 hi = min(lo + (1 << L), grid_cells);
#endif
                const float3 te = exit_params(we, d, inv_d, lo, hi);
                const float s_exit = max_acc(s, min_acc(te.x, min_acc(te.y, te.z)));
                if (s_exit >= send) break;
                const int a = argmin3(te);
                const float3 q = we + s_exit * d;
                int3 nc = clamp(convert_int3_rtn(q), lo, hi - 1);
                if (a == 0) nc.x = d.x > 0.0f ? hi.x : lo.x - 1;
                else if (a == 1) nc.y = d.y > 0.0f ? hi.y : lo.y - 1;
                else nc.z = d.z > 0.0f ? hi.z : lo.z - 1;
                cell = nc;
                s = s_exit;
            }
            // componentwise: PoCL calls any() out of line
            const int3 c0 = FIRST_CELL, c1 = END_CELL;
            if (cell.x < c0.x || cell.y < c0.y || cell.z < c0.z
                || cell.x >= c1.x || cell.y >= c1.y || cell.z >= c1.z) break;
        }
    }

    hit_out[pix] = found ? 1 : 0;
    if (want_hess) {
        // chain rule: index-space second derivatives to world, d/dx_i = inv_spacing_i d/du_i
        const float3 w = inv_spacing;
        hess_out[pix] = found
            ? (float8)(hess_u[0] * w.x * w.x, hess_u[1] * w.y * w.y, hess_u[2] * w.z * w.z,
                       hess_u[3] * w.x * w.y, hess_u[4] * w.x * w.z, hess_u[5] * w.y * w.z,
                       length(grad_u * inv_spacing), 0.0f)
            : (float8)(NAN);
    }
    if (!found) {
        pos_out[pix] = (float4)(NAN);
        normal_out[pix] = (float4)(NAN);
        depth_out[pix] = 1.0f;
        color_out[pix] = (uchar4)(BG_R, BG_G, BG_B, 255);
        return;
    }
    const float3 gw = grad_u * inv_spacing;  // chain rule: index-space gradient to world
    const float gl = length(gw);
    const float3 n = gl > 0.0f ? gw / gl : (float3)(0.0f);
    pos_out[pix] = (float4)(upos, t_hit);
    normal_out[pix] = (float4)(n, 0.0f);
    const float ze = t_hit * dot(dw, dop);
    depth_out[pix] = clamp(depth_a - depth_b / ze, 0.0f, 1.0f);
    // headlight Phong, two sided; the same formula as core.raycast_reference.phong_shade
    const float ndl = dot(n, dw);
    const float cs = fabs(ndl);
    const float3 base = ndl > 0.0f ? (float3)(FRONT_R, FRONT_G, FRONT_B)
                                   : (float3)(BACK_R, BACK_G, BACK_B);
    const float3 rgb = clamp(base * (AMBIENT + DIFFUSE * cs) + SPECULAR * pow(cs, SHININESS),
                             0.0f, 1.0f);
    const float3 c255 = rint(rgb * 255.0f);
    color_out[pix] = (uchar4)((uchar)c255.x, (uchar)c255.y, (uchar)c255.z, 255);
}
