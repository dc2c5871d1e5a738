"""Driving a Qt widget like a user, in tests: the input playback and the stall meter of
:mod:`splineviz.bench.driving`, image measures that tell an exact ray-cast frame from a
reduced-resolution preview, and windows opened and closed for a test.
"""

from __future__ import annotations

import numpy as np

from splineviz.bench.driving import (  # noqa: F401  (the tests import them from here)
    LEFT,
    NO_BUTTON,
    NO_MODIFIER,
    StallMeter,
    close_window,
    drag,
    drag_steps,
    line,
    mouse,
    open_window,
    pump,
    run_steps,
    wheel,
    wheel_step,
)

# -- images ------------------------------------------------------------------------------

def surface_mask(img: np.ndarray, background) -> np.ndarray:
    """Pixels of ``img`` (H, W, 3 uint8) that differ from the background colour."""
    bg = np.round(np.asarray(background, float)[:3] * 255.0)
    return np.abs(img[..., :3].astype(int) - bg).max(axis=2) > 2


def blockiness(img: np.ndarray, mask: np.ndarray) -> float:
    """Share of masked pixels equal to their left neighbour (ENVIRONMENT.md): ~0.8 for a
    20 px preview, about 1 - 1/b for b-pixel blocks, < 0.15 for an exact frame."""
    a = img[..., :3].astype(int)
    same = (a[:, 1:] == a[:, :-1]).all(axis=2)
    m = mask[:, 1:] & mask[:, :-1]
    return float(same[m].mean()) if m.any() else 0.0


def agreement(a: np.ndarray, b: np.ndarray, tol: int = 2, shift: int = 0) -> float:
    """Share of pixels of ``a`` whose channels all differ by at most ``tol`` (of 255) from
    ``b``'s pixel at the same place or, with ``shift`` > 0, from one of ``b``'s pixels up
    to ``shift`` pixels away (absorbs one-pixel differences in how lines are rasterised)."""
    if a.shape[:2] != b.shape[:2]:
        raise ValueError(f"image sizes differ: {a.shape} vs {b.shape}")
    a = a[..., :3].astype(int)
    b = b[..., :3].astype(int)
    h, w = a.shape[:2]
    s = int(shift)
    padded = np.pad(b, ((s, s), (s, s), (0, 0)), mode="edge")
    best = None
    for dy in range(2 * s + 1):
        for dx in range(2 * s + 1):
            d = np.abs(a - padded[dy:dy + h, dx:dx + w]).max(axis=2)
            best = d if best is None else np.minimum(best, d)
    return float((best <= tol).mean())


#: set in the fresh process :func:`in_fresh_process` starts
FRESH = "SPLINEVIZ_TEST_FRESH_PROCESS"


def in_fresh_process(nodeid: str, timeout_s: float = 600.0, marks: str | None = None) -> None:
    """Run the test ``nodeid`` in a new pytest process and assert that it passed (``marks``:
    the marker expression that selects it, e.g. ``"slow"``).

    GUI-stall and latency checks measure this app's GUI thread; in the process of the whole
    suite they also measured what earlier tests left behind (their threads, caches and
    libraries' state: 100-130 ms against 50-90 ms alone), so they run on their own.
    """
    import os
    import subprocess
    import sys
    from pathlib import Path

    root = Path(__file__).resolve().parents[2]
    select = ["-m", marks] if marks else []
    done = subprocess.run([sys.executable, "-m", "pytest", "-q", "-s", "-p", "no:randomly",
                           *select, nodeid], cwd=root, env={**os.environ, FRESH: "1"},
                          capture_output=True, text=True, timeout=timeout_s)
    print(done.stdout[-3000:])
    assert done.returncode == 0, done.stdout[-3000:] + done.stderr[-2000:]
