"""Analytic test surfaces for the point-cloud tests: samplers and exact distance functions.

Each sampler returns ``(N, 3)`` points spread uniformly by area; each ``*_distance`` returns
the exact unsigned distance of ``(M, 3)`` points to the surface.
"""

import numpy as np


def sphere(n, radius=1.0, seed=0):
    rng = np.random.default_rng(seed)
    v = rng.normal(size=(n, 3))
    return radius * v / np.linalg.norm(v, axis=1, keepdims=True)


def sphere_distance(x, radius=1.0):
    return np.abs(np.linalg.norm(x, axis=1) - radius)


def torus(n, big=1.0, small=0.4, seed=0):
    """Area-uniform samples by rejection on the tube angle (density ~ big + small cos v)."""
    rng = np.random.default_rng(seed)
    out = []
    while sum(len(o) for o in out) < n:
        u = rng.uniform(0, 2 * np.pi, 2 * n)
        v = rng.uniform(0, 2 * np.pi, 2 * n)
        keep = rng.uniform(0, big + small, 2 * n) < big + small * np.cos(v)
        u, v = u[keep], v[keep]
        out.append(np.stack([(big + small * np.cos(v)) * np.cos(u),
                             (big + small * np.cos(v)) * np.sin(u), small * np.sin(v)], axis=1))
    return np.concatenate(out)[:n]


def torus_distance(x, big=1.0, small=0.4):
    ring = np.hypot(x[:, 0], x[:, 1]) - big
    return np.abs(np.hypot(ring, x[:, 2]) - small)


def paraboloid(n, a=0.5, radius=1.0, seed=0):
    """Samples of z = a (x^2 + y^2) over the disc of the given radius (an open patch)."""
    rng = np.random.default_rng(seed)
    r = radius * np.sqrt(rng.uniform(0, 1, 3 * n))
    t = rng.uniform(0, 2 * np.pi, 3 * n)
    x, y = r * np.cos(t), r * np.sin(t)
    # thin to uniform area density: the area element grows with sqrt(1 + (2 a r)^2)
    w = np.sqrt(1 + (2 * a * r) ** 2)
    keep = rng.uniform(0, w.max(), 3 * n) < w
    pts = np.stack([x, y, a * (x**2 + y**2)], axis=1)[keep]
    return pts[:n]


def paraboloid_distance(x, a=0.5):
    """Exact distance to z = a (x^2 + y^2): minimise over the radial foot parameter by Newton
    on the cubic of the normal condition (rotationally symmetric, so 2-D)."""
    rho = np.hypot(x[:, 0], x[:, 1])
    z = x[:, 2]
    r = rho.copy()
    for _ in range(60):
        # d/dr [(r - rho)^2 + (a r^2 - z)^2] / 2 = (r - rho) + 2 a r (a r^2 - z)
        g = (r - rho) + 2 * a * r * (a * r * r - z)
        h = 1 + 2 * a * (3 * a * r * r - z)
        r = r - g / np.where(np.abs(h) < 1e-12, 1e-12, h)
    return np.hypot(r - rho, a * r * r - z)
