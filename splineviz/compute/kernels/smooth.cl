// Separable Gaussian smoothing of a volume: one 1-D convolution pass along one axis.
//
// Layout: data[(i*NY + j)*NZ + k]. The pass along `axis` convolves with `weights[0..2R]`
// (centre at R). Boundary: mirror about the edge sample's outer side, x[-1] = x[0]
// (scipy.ndimage mode "reflect", the default of gaussian_filter).

__kernel void convolve_axis(__global const float *src, __global float *dst,
                            __constant float *weights, int R, int axis,
                            int NX, int NY, int NZ)
{
    const int k = get_global_id(0), j = get_global_id(1), i = get_global_id(2);
    if (i >= NX || j >= NY || k >= NZ) return;
    const int n = axis == 0 ? NX : (axis == 1 ? NY : NZ);
    const int stride = axis == 0 ? NY * NZ : (axis == 1 ? NZ : 1);
    const int pos = axis == 0 ? i : (axis == 1 ? j : k);
    const int base = (i * NY + j) * NZ + k - pos * stride;
    const int period = 2 * n;
    float acc = 0.0f;
    for (int t = -R; t <= R; ++t) {
        // reflect: ... 1 0 | 0 1 2 ... n-1 | n-1 n-2 ...  (period 2n)
        int q = (pos + t) % period;
        if (q < 0) q += period;
        if (q >= n) q = period - 1 - q;
        acc += weights[t + R] * src[base + q * stride];
    }
    dst[(i * NY + j) * NZ + k] = acc;
}
