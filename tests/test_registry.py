"""The registry helper (splineviz/core/registry.py) and its loader hook, as the model, format
and source registries use it."""

import os
import subprocess
import sys
import textwrap
from pathlib import Path

import numpy as np
import pytest

from splineviz.core import registry as reg
from splineviz.core.errors import SplinevizError
from splineviz.core.registry import Registry, RegistryError

ROOT = Path(__file__).resolve().parents[1]


@pytest.fixture
def hook():
    """A loader hook that counts its calls and adds ``"late"`` to the registry under test."""
    calls = []
    r = Registry("colour", {"red": 1, "blue": 2})

    def loader():
        calls.append(len(r))
        r.setdefault("late", 3)

    previous = reg.set_loader(loader)
    yield r, calls
    reg.set_loader(previous)


def test_lookup_loads_extensions_on_a_miss_only(hook):
    r, calls = hook
    assert r.lookup("red") == 1 and calls == []
    assert r.lookup("late") == 3 and calls == [2]


def test_an_unknown_key_names_the_valid_ones(hook):
    r, calls = hook
    with pytest.raises(RegistryError, match=r"^unknown colour 'green'; choose one of red, "
                                            r"blue, late$") as info:
        r.lookup("green")
    assert isinstance(info.value, SplinevizError) and isinstance(info.value, ValueError)
    assert calls  # the extensions were asked before giving up
    assert r.lookup("green", None) is None


def test_listing_loads_extensions_and_the_plain_mapping_does_not(hook):
    r, calls = hook
    assert "late" not in r and list(r) == ["red", "blue"] and dict(r) == {"red": 1, "blue": 2}
    assert calls == []
    assert r.names() == ["red", "blue", "late"]
    assert r.entries() == {"red": 1, "blue": 2, "late": 3}


def test_register_refuses_a_duplicate_unless_replacing(hook):
    r, _ = hook
    assert r.register("green", 4) == 4
    with pytest.raises(RegistryError, match="colour 'green' is already registered"):
        r.register("green", 5)
    assert r["green"] == 4
    r.register("green", 5, replace=True)
    assert r.unregister("green") == 5 and r.unregister("green") is None and "green" not in r


def test_the_hook_is_not_reentered_by_its_own_lookups():
    r = Registry("thing", {"a": 1})
    calls = []

    def loader():
        calls.append(1)
        r.lookup("b", None)  # a plugin's register() asking the registry while loading
        r.names()

    previous = reg.set_loader(loader)
    try:
        assert r.lookup("b", None) is None
    finally:
        reg.set_loader(previous)
    assert calls == [1]


def test_without_a_hook_a_miss_is_just_unknown():
    previous = reg.set_loader(None)
    try:
        with pytest.raises(RegistryError, match="unknown thing 'b'; none is installed"):
            Registry("thing").lookup("b")
    finally:
        reg.set_loader(previous)


def test_the_model_name_is_checked_by_one_function():
    import splineviz as sv
    from splineviz.core.splines import MODELS, UnknownModelError, model_spec

    assert model_spec("cubic-c1") is MODELS["cubic-c1"]
    with pytest.raises(UnknownModelError) as direct:
        model_spec("no-such-model")
    with pytest.raises(UnknownModelError) as built:
        sv.build_spline(np.zeros((4, 4, 4)), "no-such-model")
    assert str(direct.value) == str(built.value)
    assert str(direct.value).startswith("unknown spline model 'no-such-model'; choose one of "
                                        "trilinear, super-quadratic, cubic-c1, to-quadratic")


PLUGIN = '''
import numpy as np
from splineviz.core.splines.trilinear import TrilinearSpline
from splineviz.io.volumes import VolumeData

class HookSpline(TrilinearSpline):
    pass

def read(path):
    return VolumeData(np.ones((3, 3, 3), np.uint8), (1, 1, 1), (0, 0, 0), "hooktest")

def register(api):
    api.add_volume_format("hooktest", [".hooktest"], read)
    api.add_source("hooktest-ramp", lambda x, y, z: x, ((0, 1), (0, 1), (0, 1)))
    api.add_model("hooktest-model", HookSpline)
'''

CHECK = '''
import sys
from pathlib import Path
import splineviz.io as io
from splineviz.core.sources import source_volume
from splineviz.core.splines import model_spec

assert "splineviz.plugins" not in sys.modules
path = Path(sys.argv[1]) / "cube.hooktest"
path.write_text("x")
assert io.read_volume(path).shape == (3, 3, 3)
assert "splineviz.plugins" in sys.modules  # loaded by the format registry's listing
assert source_volume("hooktest-ramp", (4, 4, 4)).shape == (4, 4, 4)
assert model_spec("hooktest-model").plugin == "hook"
print("ok")
'''


def test_plugins_are_found_when_only_io_and_core_are_imported(tmp_path):
    (tmp_path / "hooktest_plugin.py").write_text(textwrap.dedent(PLUGIN))
    info = tmp_path / "hooktest-0.1.dist-info"
    info.mkdir()
    (info / "METADATA").write_text("Metadata-Version: 2.1\nName: hooktest\nVersion: 0.1\n")
    (info / "entry_points.txt").write_text("[splineviz.plugins]\nhook = hooktest_plugin:register\n")
    env = dict(os.environ, PYTHONPATH=os.pathsep.join(
        [str(tmp_path), str(ROOT), os.environ.get("PYTHONPATH", "")]))
    out = subprocess.run([sys.executable, "-c", CHECK, str(tmp_path)], capture_output=True,
                         text=True, env=env, cwd=tmp_path, timeout=300)
    assert out.returncode == 0 and out.stdout.strip() == "ok", out.stderr[-2000:]


def test_each_extension_point_has_one_registry():
    from splineviz import plugins
    from splineviz.core.sources import SOURCES
    from splineviz.core.splines import MODELS
    from splineviz.io.registry import FORMATS

    assert all(isinstance(r, Registry) for r in (MODELS, FORMATS, SOURCES))
    assert plugins.SOURCES is SOURCES  # the old import path names the same registry
