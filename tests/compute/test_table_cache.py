"""The on-disk cache of the truncated-octahedral tables gives exactly what the core makes."""

import numpy as np

from splineviz.compute import table_cache, to_tables
from splineviz.core.splines import to_quadratic


def test_cached_stencils_equal_the_core_ones_and_survive_damage(tmp_path, monkeypatch):
    monkeypatch.setenv(table_cache.CACHE_ENV, str(tmp_path))
    to_tables.stencils.cache_clear()
    first = to_tables.stencils(2)          # made and written
    files = list(tmp_path.glob("to-stencils-k2-*.npz"))
    assert len(files) == 1
    to_tables.stencils.cache_clear()
    again = to_tables.stencils(2)          # read back
    core = to_quadratic.stencils(2)
    assert len(first) == len(again) == len(core) == 144
    for (o1, w1), (o2, w2), (oc, wc) in zip(first, again, core, strict=True):
        assert np.array_equal(o1, oc) and np.array_equal(o2, oc)
        assert np.array_equal(w1, wc) and np.array_equal(w2, wc)
    files[0].write_bytes(b"not an npz")    # a damaged file is made again, not trusted
    to_tables.stencils.cache_clear()
    for (o, w), (oc, wc) in zip(to_tables.stencils(2), core, strict=True):
        assert np.array_equal(o, oc) and np.array_equal(w, wc)
    to_tables.stencils.cache_clear()


def test_cell_classes_cached_equal_made(tmp_path, monkeypatch):
    monkeypatch.setenv(table_cache.CACHE_ENV, str(tmp_path))
    to_tables.cell_classes.cache_clear()
    cached = to_tables.cell_classes()
    made = to_tables.make_cell_classes()
    for a, b in zip(cached, made, strict=True):
        assert np.array_equal(a, b)
    to_tables.cell_classes.cache_clear()
