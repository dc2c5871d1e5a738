"""``splineviz render`` of a 1024^3 uint8 volume stays within 2.5 GB (issue 25, part 6; it
took 9.7 GB when every volume was held as float32)."""

from __future__ import annotations

import subprocess
import sys
import time
from pathlib import Path

import numpy as np
import pytest

ROOT = Path(__file__).resolve().parents[2]
#: the memory the whole render may take: all its processes (bricks render on dask workers)
LIMIT_BYTES = 2.5e9


def _write_phantom(path: Path, n: int = 1024) -> None:
    """An (n, n, n) uint8 ball with a wavy rim and noise, written slab by slab."""
    out = np.lib.format.open_memmap(path, mode="w+", dtype=np.uint8, shape=(n, n, n))
    rng = np.random.default_rng(0)
    y, z = np.meshgrid(np.linspace(-1, 1, n), np.linspace(-1, 1, n), indexing="ij")
    for i in range(n):
        x = -1 + 2 * i / (n - 1)
        r = np.sqrt(x * x + y * y + z * z)
        bump = 0.08 * np.sin(6 * np.arctan2(y, x + 1e-9)) * np.cos(5 * z)
        v = 200 * np.clip(1.2 - (r + bump) / 0.7, 0, 1) + rng.integers(0, 30, size=(n, n))
        out[i] = np.clip(v, 0, 255).astype(np.uint8)
    out.flush()
    del out


def _peak_memory(cmd, cwd, log: Path) -> tuple[float, int, int]:
    """Run ``cmd`` (output to ``log``); return (wall seconds, peak of the summed
    proportional set size of its process tree: shared libraries and shared file pages
    counted once, peak resident set size of its largest process)."""
    psutil = pytest.importorskip("psutil")
    t0 = time.perf_counter()
    with open(log, "wb") as out, subprocess.Popen(cmd, cwd=cwd, stdout=out,
                                                   stderr=subprocess.STDOUT) as proc:
        root = psutil.Process(proc.pid)
        peak = largest = 0
        while proc.poll() is None:
            total = 0
            try:
                procs = [root, *root.children(recursive=True)]
            except psutil.Error:
                break
            for p in procs:
                try:
                    info = p.memory_full_info()
                except psutil.Error:
                    continue
                total += info.pss
                largest = max(largest, info.rss)
            peak = max(peak, total)
            time.sleep(0.2)
        proc.wait()
    assert proc.returncode == 0, log.read_text(errors="replace")
    return time.perf_counter() - t0, peak, largest


@pytest.mark.slow
def test_a_1024_cubed_uint8_volume_renders_within_2_5_gb(tmp_path):
    volume = tmp_path / "ball1024.npy"
    _write_phantom(volume)
    png = tmp_path / "ball.png"
    seconds, peak, largest = _peak_memory(
        [sys.executable, "-m", "splineviz.cli", "render", str(volume), "-o", str(png)], ROOT,
        tmp_path / "render.log")
    print(f"1024^3 uint8 render: {seconds:.1f} s, peak {peak / 1e9:.2f} GB (all processes), "
          f"largest process {largest / 1e9:.2f} GB")
    assert png.stat().st_size > 1000
    assert peak <= LIMIT_BYTES, f"peak {peak / 1e9:.2f} GB"
    assert largest <= LIMIT_BYTES, f"largest process {largest / 1e9:.2f} GB"
