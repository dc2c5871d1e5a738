"""Helpers of the bricked-rendering tests: a small LocalCluster and the comparison of a
bricked frame with a single ray caster's (the acceptance metrics of issue 15)."""

from __future__ import annotations

import contextlib

import numpy as np

#: hit masks agree on at least this share of pixels
HIT_AGREEMENT = 0.9999
#: window depth tolerance on every pixel both frames hit. Bricks are cast in the whole
#: volume's coordinates (core.bricks.Placement), so their floats are the single cast's: on
#: bonsai every model's bricked frame is the single one bit for bit (depth_exact 1)
DEPTH_TOL = 1e-6
#: colour tolerance (8-bit steps)
COLOR_TOL = 1


@contextlib.contextmanager
def local_client(workers: int = 2, processes: bool = False):
    """A dask.distributed client of a LocalCluster of ``workers`` single-thread workers (in
    this process unless ``processes``), closed afterwards."""
    from distributed import Client, LocalCluster

    with LocalCluster(n_workers=workers, threads_per_worker=1, processes=processes,
                      dashboard_address=":0") as cluster, Client(cluster) as client:
        yield client


def compare_frames(single, bricked, opacity: float | None = None) -> dict:
    """The metrics of a bricked frame against the single ray caster's; with ``opacity`` the
    translucent pictures (first hit blended over the background) are compared too."""
    from splineviz.core.compositing import blend

    both = single.hit & bricked.hit
    out = {"hit_agreement": float(np.mean(single.hit == bricked.hit)),
           "hits": int(single.hit.sum()),
           "depth_max": float(np.max(np.abs(single.depth[both] - bricked.depth[both]),
                                     initial=0.0)),
           "depth_exact": float(np.mean(single.depth[both] == bricked.depth[both]))
           if both.any() else 1.0,
           "color_max": int(np.max(np.abs(single.color[both].astype(int)
                                          - bricked.color[both].astype(int)), initial=0))}
    if opacity is not None:
        a, b = blend(single, opacity), blend(bricked, opacity)
        same = single.hit == bricked.hit
        out["blend_max"] = int(np.max(np.abs(a[same].astype(int) - b[same].astype(int)),
                                      initial=0))
    return out


def assert_same_picture(metrics: dict) -> None:
    assert metrics["hits"] > 100, metrics
    assert metrics["hit_agreement"] >= HIT_AGREEMENT, metrics
    assert metrics["depth_max"] <= DEPTH_TOL, metrics
    assert metrics["color_max"] <= COLOR_TOL, metrics
    assert metrics.get("blend_max", 0) <= COLOR_TOL, metrics


def write_ball_ome_zarr(path, n: int, chunk: int, levels: int = 2):
    """An ``n^3`` uint8 OME-Zarr (chunks ``chunk^3``) of a wavy ball, computed and written
    chunk by chunk through dask (never whole in memory), with ``levels`` coarser levels."""
    import warnings

    import dask.array as da
    import zarr
    from ome_zarr.io import parse_url

    with warnings.catch_warnings():
        # ome-zarr 0.18 warns about its own deprecated Scaler at import
        warnings.simplefilter("ignore", DeprecationWarning)
        from ome_zarr.writer import write_image

    def block(block_info=None):
        (z0, z1), (y0, y1), (x0, x1) = block_info[None]["array-location"]
        c = np.linspace(-1, 1, n, dtype=np.float32)
        z, y, x = c[z0:z1, None, None], c[None, y0:y1, None], c[None, None, x0:x1]
        r = np.sqrt((x - 0.1) ** 2 + 1.3 * y**2 + 0.8 * z**2) + 0.08 * np.sin(7 * x + 3 * z)
        return np.clip(255 * (1.2 - r), 0, 255).astype(np.uint8)

    zyx = da.map_blocks(block, chunks=da.core.normalize_chunks(chunk, (n,) * 3),
                        dtype=np.uint8, meta=np.empty((0, 0, 0), np.uint8))
    root = zarr.group(store=parse_url(str(path), mode="w").store)
    write_image(zyx, root, axes="zyx", storage_options={"chunks": (chunk,) * 3},
                scale_factors=[{a: 2**k for a in "zyx"} for k in range(1, levels + 1)])
    return path
