"""The acceptance runs of issue 15 (``-m slow``; ``-m bench`` for the benchmark):

* bonsai in 8 bricks on a LocalCluster of 2 worker processes against the single ray caster,
  for every model, with and without a clip plane, opaque and translucent;
* a 2048^3 lazy gyroid (32 GiB as float32) at 1024x768 with the coarse preview first and a
  peak resident memory (client and workers) under 6 GiB;
* a 1024^3 uint8 OME-Zarr in chunks of 128^3, written here, opened and rendered.
"""

import numpy as np
import pytest

import splineviz as sv
from splineviz.compute.bricked import BrickedRayCaster
from splineviz.compute.raycast import renders_in_bricks
from splineviz.core.camera import default_camera
from splineviz.core.splines import MODELS

from .bricked_helpers import (
    assert_same_picture,
    compare_frames,
    local_client,
    write_ball_ome_zarr,
)
from .helpers import HAVE_CL
from .test_bricked import ISO

pytestmark = pytest.mark.skipif(not HAVE_CL, reason="no OpenCL device")

GIB = 2.0**30


@pytest.fixture(scope="module")
def bonsai(shared_data):
    return sv.read_volume(shared_data / "volumes" / "bonsai.vti")


@pytest.mark.slow
def test_every_model_in_8_bricks_on_2_worker_processes(bonsai):
    cam = default_camera(bonsai.bounds)
    centre = np.asarray(bonsai.bounds).mean(axis=1)
    clips = {"none": (), "plane": [(centre + (10, 0, 0), (-1.0, 0.3, 0.2))]}
    size = (256, 192)
    rows = []
    with local_client(workers=2, processes=True) as client:
        # every model with a kernel whose bricks carry its spline: the plugin's tricubic
        # B-spline interpolant is global (a prefilter over the whole volume), so no finite
        # halo makes a brick's spline its own
        for model in [m for m in MODELS if renders_in_bricks(m)]:
            rc = sv.RayCaster(bonsai, model=model)
            rc.set_isovalue(ISO)
            brc = BrickedRayCaster(bonsai, model=model, client=client, bricks=2)
            brc.set_isovalue(ISO)
            for name, planes in clips.items():
                single = rc.render(cam, size, clip_planes=planes)
                for composite in ("nearest", "back-to-front"):
                    frame = brc.render(cam, size, clip_planes=planes, composite=composite)
                    m = compare_frames(single, frame, opacity=0.4)
                    rows.append((model, name, composite, m))
                    assert brc.stats["bricks"] == 8
                    assert len({t["worker"] for t in brc.stats["brick_times"]}) == 2
                    assert_same_picture(m)
    for model, name, composite, m in rows:
        print(f"{model:>16} clip {name:>5} {composite:>13}: hits {m['hits']} agreement "
              f"{100 * m['hit_agreement']:.4f} % depth max {m['depth_max']:.1e} (equal on "
              f"{100 * m['depth_exact']:.3f} %), colour {m['color_max']}, blended "
              f"{m['blend_max']}")


@pytest.mark.slow
def test_2048_cubed_lazy_volume_under_6_gib():
    from splineviz.compute.bench_bricks import measure

    r = measure(2048, workers=2, model="cubic-c1", size=(1024, 768), brick=256)
    print(f"2048^3 gyroid, cubic-c1, 1024x768, 2 workers: {r['wall_s']:.1f} s (preview "
          f"{r['preview_s']:.2f} s), bricks {r['bricks']} rendered {r['bricks_rendered']} "
          f"culled {r['bricks_culled']}, peak RSS {r['peak_rss'] / GIB:.2f} GiB")
    assert r["first_stage"] == "preview"
    assert r["peak_rss"] < 6 * GIB
    assert r["hits"] > 0.2 * 1024 * 768  # the cube of gyroid tunnels fills a third
    assert r["bricks_culled"] > 0


@pytest.fixture(scope="module")
def big_zarr(tmp_path_factory):
    return write_ball_ome_zarr(tmp_path_factory.mktemp("big") / "ball.ome.zarr", 1024, 128)


@pytest.mark.slow
def test_1024_cubed_ome_zarr_renders(big_zarr):
    from splineviz.core.chunked import ChunkedVolume

    vol = sv.read_volume(big_zarr)
    assert isinstance(vol, ChunkedVolume) and vol.shape == (1024,) * 3
    assert vol.chunks == (128,) * 3 and vol.dtype == np.uint8
    with local_client(workers=2, processes=True) as client:
        brc = BrickedRayCaster(vol, model="cubic-c1", client=client)
        brc.set_isovalue(100)
        frames = list(brc.frames(default_camera(vol.bounds), (320, 240)))
    assert frames[0][0] == "preview" and frames[-1][0] == "exact"
    assert frames[-1][3].hit.mean() > 0.1
    print(f"1024^3 OME-Zarr, cubic-c1, 320x240: {brc.stats['render_s']:.1f} s, bricks "
          f"{brc.stats['bricks']} rendered {brc.stats['bricks_rendered']} culled "
          f"{brc.stats['bricks_culled']}")


@pytest.mark.bench
def test_bricks_benchmark_prints_its_table():
    from splineviz.compute.bench_bricks import run_bricks_bench

    lines = []
    results = run_bricks_bench(n=256, size=(320, 240), brick=64, workers=(1, 2),
                               out=lines.append)
    print("\n".join(lines))
    assert [r["workers"] for r in results] == [1, 2]
    assert results[0]["bricks"] == 64 and results[0]["hits"] > 0
    text = "\n".join(lines)
    assert "speed-up 2 workers / 1 worker" in text and "projected" in text
