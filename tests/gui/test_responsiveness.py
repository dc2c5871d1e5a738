"""The GUI thread never stalls: the longest gap between event-loop ticks while the user opens
data, orbits, zooms, drags the isovalue slider, splits the view (View > Split view) and drags
in the new view, switches every spline model, smooths and reverts, adds an isosurface,
remeshes and cancels — and a cancel acts within a second. The script is
:mod:`splineviz.bench.gui` (``splineviz bench gui`` prints its table).

The default run drives it once on small data (the embedded default volume, the kitten scan)
against a guard of :data:`GUARD_MS` per action: a freeze (a read or a full render in the GUI
thread) still fails it, and on a machine where another process takes a core for a tick it
holds. The 100 ms budget (:data:`splineviz.bench.gui.MAX_STALL_MS`, the median of three
measurements per action) is asserted under ``-m slow``, on the same data and on bonsai
(256^3) with the bunny (36k points), the issue's figures.
"""

import os

import pytest

pytest.importorskip("pytestqt")

from interaction import (  # noqa: E402
    FRESH,
    close_window,
    in_fresh_process,
    open_window,
)

from splineviz.bench.gui import MAX_CANCEL_S, prepare, print_table, run_script  # noqa: E402

#: the default suite's limit on an action's longest GUI-thread stall, milliseconds: three
#: times the budget, which a busy machine's tick does not reach and a freeze does
GUARD_MS = 300.0
#: the default suite's limit on a cancelled job's stop, seconds
CANCEL_GUARD_S = 3.0
#: measurements per action where the budget is asserted (its median)
REPEATS = 3


@pytest.fixture
def window(qapp, tmp_path):
    prepare()  # as in an installed app (install.sh)
    w = open_window(tmp_path)
    yield w
    close_window(w)


def _assert_guards(stalls):
    print_table(stalls, budget_ms=GUARD_MS)
    # an action whose every measurement passed the guard (it is measured again once when
    # the first did) stalls by itself
    frozen = {a: v for a, v in stalls.ms.items() if min(v) > GUARD_MS}
    assert not frozen, frozen
    assert min(stalls.cancel_s) < CANCEL_GUARD_S, stalls.cancel_s


def _assert_budget(stalls):
    rows = print_table(stalls)
    over = [r for r in rows if not r["ok"]]
    assert not over, over
    assert sorted(stalls.cancel_s)[len(stalls.cancel_s) // 2] < MAX_CANCEL_S, stalls.cancel_s


@pytest.mark.skipif(os.environ.get(FRESH) != "1", reason="run in a fresh process by "
                    "test_no_stall_on_the_default_data_and_kitten_alone")
def test_no_stall_on_the_default_data_and_kitten(window, shared_data):
    _assert_guards(run_script(window, None, shared_data / "points" / "kitten.xyz",
                              again_over=GUARD_MS))


@pytest.mark.skipif(os.environ.get(FRESH) == "1", reason="this process is the fresh one")
def test_no_stall_on_the_default_data_and_kitten_alone():
    in_fresh_process("tests/gui/test_responsiveness.py::test_no_stall_on_the_default_data_and_kitten")


@pytest.mark.slow
@pytest.mark.skipif(os.environ.get(FRESH) != "1", reason="run in a fresh process by "
                    "test_stall_budget_on_the_default_data_and_kitten_alone")
def test_stall_budget_on_the_default_data_and_kitten(window, shared_data):
    _assert_budget(run_script(window, None, shared_data / "points" / "kitten.xyz",
                              repeats=REPEATS))


@pytest.mark.slow
@pytest.mark.skipif(os.environ.get(FRESH) == "1", reason="this process is the fresh one")
def test_stall_budget_on_the_default_data_and_kitten_alone():
    in_fresh_process("tests/gui/test_responsiveness.py::"
                     "test_stall_budget_on_the_default_data_and_kitten", marks="slow")


@pytest.mark.slow
def test_stall_budget_on_bonsai_and_bunny(window, shared_data):
    _assert_budget(run_script(window, shared_data / "volumes" / "bonsai.vti",
                              shared_data / "points" / "bunny.ply", 40.5, repeats=REPEATS))

