"""Entry-point plugins: discovery, lazy loading, failures reported and skipped, rollback."""

import sys
import textwrap

import numpy as np
import pytest

import splineviz as sv
from splineviz import plugins
from splineviz.core.splines import MODELS
from splineviz.io import registry

GOOD = '''
import numpy as np
from splineviz.core.splines.base import Spline
from splineviz.io.volumes import VolumeData

class ConstantSpline(Spline):
    model = "plugtest-constant"
    def index_derivatives(self, upoints, order):
        out = np.zeros((len(upoints), (1, 4, 13)[order]))
        out[:, 0] = 7.0
        return out

def read_fake(path):
    n = int(path.read_text())
    return VolumeData(np.arange(n ** 3, dtype=np.uint8).reshape(n, n, n), (2, 2, 2),
                      (0, 0, 0), "plugtest-fake")

def register(api):
    api.add_volume_format("plugtest-fake", [".plugtest"], read_fake,
                          sniff=lambda head: head.strip().isdigit())
    api.add_source("plugtest-sphere", lambda x, y, z: x * x + y * y + z * z,
                   ((-1, 1), (-1, 1), (-1, 1)), title="Sphere", shape=(8, 8, 8))
    api.add_model("plugtest-constant", ConstantSpline)
'''
BROKEN_IMPORT = "raise ImportError('needs libfoo')\ndef register(api): pass\n"
HALFWAY = '''
def register(api):
    api.add_source("plugtest-half", lambda x, y, z: x, ((0, 1), (0, 1), (0, 1)))
    raise RuntimeError("oops after registering")
'''
DUPLICATE = '''
def register(api):
    api.add_model("trilinear", "somewhere:Else")
'''


@pytest.fixture
def fake_plugins(tmp_path, monkeypatch):
    """A distribution on sys.path declaring five entry points of group splineviz.plugins."""
    mods = {"plugtest_good": GOOD, "plugtest_broken": BROKEN_IMPORT,
            "plugtest_half": HALFWAY, "plugtest_dup": DUPLICATE,
            "plugtest_notcallable": "register = 42\n"}
    for name, text in mods.items():
        (tmp_path / f"{name}.py").write_text(textwrap.dedent(text))
    info = tmp_path / "plugtest-0.1.dist-info"
    info.mkdir()
    (info / "METADATA").write_text("Metadata-Version: 2.1\nName: plugtest\nVersion: 0.1\n")
    (info / "entry_points.txt").write_text(
        "[splineviz.plugins]\n" + "".join(
            f"{n.removeprefix('plugtest_')} = {n}:register\n" for n in mods))
    monkeypatch.syspath_prepend(str(tmp_path))
    snapshot = (dict(registry.FORMATS), dict(plugins.SOURCES), dict(MODELS),
                dict(plugins._RECORDS), plugins._LOADED)
    yield tmp_path
    plugins._LOADED = snapshot[4]
    registry.FORMATS.clear()
    registry.FORMATS.update(snapshot[0])
    plugins.SOURCES.clear()
    plugins.SOURCES.update(snapshot[1])
    MODELS.clear()
    MODELS.update(snapshot[2])
    plugins._RECORDS.clear()
    plugins._RECORDS.update(snapshot[3])
    for name in mods:
        sys.modules.pop(name, None)


def test_discovery_imports_nothing(fake_plugins):
    names = {r.name for r in plugins.discover()}
    assert {"good", "broken", "half", "dup", "notcallable"} <= names
    assert "plugtest_good" not in sys.modules


def test_failures_are_reported_and_skipped(fake_plugins, caplog):
    records = {r.name: r for r in plugins.load_plugins(reload=True)}
    assert records["good"].state == "loaded"
    assert records["good"].registered == ["volume format plugtest-fake",
                                          "source plugtest-sphere", "model plugtest-constant"]
    assert records["broken"].state == "failed" and "needs libfoo" in records["broken"].error
    assert records["half"].state == "failed" and "oops" in records["half"].error
    assert records["dup"].state == "failed" and "redefines the spline model" in \
        records["dup"].error
    assert records["notcallable"].state == "failed"
    assert {r.name for r in plugins.failures()} >= {"broken", "half", "dup", "notcallable"}
    assert "plugtest-half" not in plugins.SOURCES  # rolled back: nothing half-registered
    assert MODELS["trilinear"].target != "somewhere:Else"
    assert "failed and was skipped" in caplog.text


def test_plugin_reader_source_and_model_work(fake_plugins, tmp_path):
    plugins.load_plugins(reload=True)
    (tmp_path / "cube.plugtest").write_text("3")
    vol = sv.read_volume(tmp_path / "cube.plugtest")
    assert vol.shape == (3, 3, 3) and vol.spacing == (2, 2, 2)
    assert vol.data[2, 1, 0] == 2 * 9 + 1 * 3 + 0  # the reader's C-order arange
    src = plugins.source_volume("plugtest-sphere")
    assert src.shape == (8, 8, 8) and src.finite_range[1] == pytest.approx(3.0)
    s = sv.build_spline(vol, model="plugtest-constant")
    np.testing.assert_array_equal(s.evaluate([[1.0, 1.0, 1.0]]), [7.0])


def test_disabled_plugins_are_not_loaded(fake_plugins, monkeypatch):
    monkeypatch.setenv(plugins.DISABLE_ENV, "good,broken")
    records = {r.name: r for r in plugins.load_plugins(reload=True)}
    assert records["good"].state == "disabled" and records["broken"].state == "disabled"
    assert "plugtest_good" not in sys.modules


def test_first_party_sources_plugin_is_installed_and_lists_the_thesis_functions():
    recs = {r.name: r for r in plugins.discover()}
    if "sources" not in recs:
        pytest.skip("plugins/splineviz-sources is not installed (run ./install.sh --dev)")
    assert recs["sources"].distribution == "splineviz-sources"
    srcs = plugins.sources()
    assert {"marschner-lobb", "barth", "chmutov", "blob"} <= set(srcs)
    from splineviz.core.testfunctions import TEST_FUNCTIONS

    ml = plugins.source_volume("marschner-lobb", (9, 9, 9))
    x = np.linspace(*srcs["marschner-lobb"].bounds[0], 9)
    expect = TEST_FUNCTIONS["ml"](x[3], x[5], x[7])
    assert ml.data[3, 5, 7] == pytest.approx(float(expect), rel=1e-6)


def test_a_plugin_reader_that_raises_anything_gives_a_typed_error(fake_plugins, tmp_path):
    from splineviz.io import errors

    plugins.load_plugins(reload=True)
    (tmp_path / "bad.plugtest").write_text("0x")  # int("0x") inside the plugin's reader
    with pytest.raises(errors.CorruptFileError, match="cannot be read as plugtest-fake"):
        sv.read_volume(tmp_path / "bad.plugtest", format="plugtest-fake")
