"""Tables that take a second of Python to generate, kept on disk between runs.

The truncated-octahedral ray caster needs the Q_k stencils of the 144 pieces and the pieces
meeting each cell class (~0.9 s of Python loops). They depend only on the code that makes
them, so they are generated once and stored as ``.npz`` in the user's cache folder, keyed by
a hash of that code: a GUI that builds a ray caster in a worker thread then does not hold the
GIL for that second (which stalled its window), and a new process starts faster. Without a
writable cache folder they are simply generated each time.
"""

from __future__ import annotations

import hashlib
import importlib
import inspect
import os
import tempfile
from functools import cache
from pathlib import Path

import numpy as np

#: environment variable naming the cache folder (default: the platform's user cache folder)
CACHE_ENV = "SPLINEVIZ_CACHE_DIR"


def cache_dir() -> Path | None:
    env = os.environ.get(CACHE_ENV)
    if env:
        return Path(env)
    try:
        import platformdirs

        return Path(platformdirs.user_cache_dir("splineviz"))
    except Exception:  # noqa: BLE001  (no cache folder: tables are generated each time)
        return None


@cache
def _source_hash(modules: tuple[str, ...]) -> str:
    h = hashlib.sha1()
    for name in modules:
        h.update(inspect.getsource(importlib.import_module(name)).encode())
    return h.hexdigest()[:16]


def cached_arrays(name: str, modules: tuple[str, ...], make) -> dict[str, np.ndarray]:
    """``make()`` (a dict of arrays), stored under ``name`` and the hash of ``modules``.

    A damaged or unreadable cache file is ignored and rewritten; writes go to a temporary
    file renamed into place, so concurrent processes never read half a file.
    """
    folder = cache_dir()
    path = None if folder is None else folder / f"{name}-{_source_hash(modules)}.npz"
    if path is not None and path.is_file():
        try:
            with np.load(path, allow_pickle=False) as z:
                return {k: z[k] for k in z.files}
        except Exception:  # noqa: BLE001  (a damaged cache file: make it again)
            pass
    arrays = make()
    if path is not None:
        try:
            folder.mkdir(parents=True, exist_ok=True)
            fd, tmp = tempfile.mkstemp(dir=folder, prefix=f".{name}.", suffix=".npz")
            with os.fdopen(fd, "wb") as fh:
                np.savez(fh, **arrays)
            os.replace(tmp, path)
        except OSError:
            pass  # read-only or full: the tables are simply made again next time
    return arrays
