"""The GUI fed bad files through File > Open (``Commands.open_path``) without dying.

Every refused file gives one message and leaves the scene as it was; a damaged file that a
reader can still make sense of (a flipped byte in the samples) is added with no error;
nothing prints a traceback. Files naming data outside their folder ask first; warnings
raised while reading are shown (log panel and status bar).
"""

import inspect
import json
import os
import sys
import warnings
from pathlib import Path

import numpy as np
import pytest

pytest.importorskip("pytestqt")
pv = pytest.importorskip("pyvista")

import splineviz as sv  # noqa: E402
import splineviz.gui.commands as commands_module  # noqa: E402
from splineviz.core.errors import SplinevizWarning  # noqa: E402

sys.path.insert(0, str(Path(__file__).parent))

from interaction import close_window, open_window  # noqa: E402
from recovery_driver import describe  # noqa: E402


def _part_a() -> bool:
    """Whether the io layer refuses data files outside their folder (and so takes
    ``allow_outside``) and has a NaN policy: until then those cases are only checked not
    to crash the window."""
    from splineviz.io.opening import open_path

    return "allow_outside" in inspect.signature(open_path).parameters


def _volume(n=6):
    x = np.linspace(-1, 1, n)
    return sv.Volume(np.add.outer(np.add.outer(x**2, x**2), x**2).astype(np.float32),
                     spacing=0.4, origin=(-1, -1, -1))


def valid_files(folder: Path, shared: Path | None) -> list[Path]:
    """One small valid file of every format the readers take."""
    import mrcfile
    import nibabel as nib

    vol = _volume()
    out = [sv.write_volume(folder / "v.vti", vol), sv.write_volume(folder / "v.nrrd", vol),
           sv.write_volume(folder / "v.npy", vol)]
    grid = pv.ImageData(dimensions=vol.shape, spacing=(0.4,) * 3)
    grid.point_data["values"] = np.asarray(vol.data).ravel(order="F")
    grid.save(folder / "v.vtk", binary=True)
    out.append(folder / "v.vtk")
    samples = np.asarray(vol.data, dtype="<f4")
    header = ("ObjectType = Image\nNDims = 3\nDimSize = 6 6 6\nElementSpacing = 0.4 0.4 0.4\n"
              "ElementType = MET_FLOAT\nElementByteOrderMSB = False\n")
    (folder / "v.mha").write_bytes((header + "ElementDataFile = LOCAL\n").encode()
                                   + samples.transpose(2, 1, 0).tobytes())
    out.append(folder / "v.mha")
    nib.save(nib.Nifti1Image(samples, np.diag([0.4, 0.4, 0.4, 1.0])), folder / "v.nii")
    out.append(folder / "v.nii")
    with mrcfile.new(folder / "v.mrc") as m:
        m.set_data(samples.transpose(2, 1, 0).copy())
    out.append(folder / "v.mrc")
    ball = pv.Sphere(radius=1.0, theta_resolution=8, phi_resolution=8)
    pts, tri = np.asarray(ball.points), ball.faces.reshape(-1, 4)[:, 1:]
    for suffix in (".ply", ".obj", ".stl"):
        out.append(sv.write_mesh(folder / f"p{suffix}", (pts, tri)))
    np.savetxt(folder / "p.xyz", pts)
    out.append(folder / "p.xyz")
    lines = "\n".join(" ".join(f"{c:.6f}" for c in p) for p in pts)
    (folder / "p.pcd").write_text(
        "VERSION .7\nFIELDS x y z\nSIZE 4 4 4\nTYPE F F F\nCOUNT 1 1 1\n"
        f"WIDTH {len(pts)}\nHEIGHT 1\nVIEWPOINT 0 0 0 1 0 0 0\nPOINTS {len(pts)}\n"
        f"DATA ascii\n{lines}\n")
    out.append(folder / "p.pcd")
    (folder / "p.off").write_text(f"OFF\n{len(pts)} {len(tri)} 0\n{lines}\n"
                                  + "\n".join(f"3 {a} {b} {c}" for a, b, c in tri) + "\n")
    out.append(folder / "p.off")
    if shared is not None:  # SLC has no writer: a real one, read from the shared data
        slc = shared / "volumes" / "neghip.slc"
        if slc.exists():
            (folder / "v.slc").write_bytes(slc.read_bytes())
            out.append(folder / "v.slc")
    return out


def damaged(valid: list[Path], folder: Path) -> list[Path]:
    """Each valid file truncated to half its size, and with bytes flipped."""
    rng = np.random.default_rng(16)
    out = []
    for p in valid:
        raw = p.read_bytes()
        cut = folder / f"cut_{p.name}"
        cut.write_bytes(raw[:len(raw) // 2])
        flipped = bytearray(raw)
        for i in rng.integers(0, len(raw), size=6):
            flipped[i] ^= 0xFF
        flip = folder / f"flip_{p.name}"
        flip.write_bytes(bytes(flipped))
        out += [cut, flip]
    return out


def hostile(folder: Path) -> dict[str, Path]:
    """Files that must be refused whatever the reader: name -> path."""
    cases = {}
    (folder / "empty.vti").write_bytes(b"")
    cases["empty file"] = folder / "empty.vti"
    (folder / "a folder").mkdir()
    cases["empty folder"] = folder / "a folder"
    os.mkfifo(folder / "pipe.nrrd")
    cases["FIFO"] = folder / "pipe.nrrd"
    (folder / "samples.raw").write_bytes(bytes(64))
    cases["raw without dims"] = folder / "samples.raw"
    (folder / "text.vti").write_text("not a volume at all\n")
    cases["wrong content"] = folder / "text.vti"
    sessions = {
        "deep.svs": "[" * 100_000 + "]" * 100_000,
        "dup.svs": '{"format": "splineviz-session", "format": "x"}',
        "schema1.svs": json.dumps({"format": "splineviz-session", "schema_version": 1,
                                   "objects": 5}),
        "newer.svs": json.dumps({"format": "splineviz-session", "schema_version": 99}),
        "absolute.svs": json.dumps({
            "format": "splineviz-session", "schema_version": 3,
            "objects": [{"id": "v", "type": "VolumeFile",
                         "properties": {"path": "/etc/passwd"}}]}),
        "code.svs": json.dumps({"format": "splineviz-session", "schema_version": 3,
                                "objects": [{"id": "v", "type": "Python",
                                             "properties": {"code": "import os"}}]}),
    }
    for name, text in sessions.items():
        (folder / name).write_text(text)
        cases[f"session {name}"] = folder / name
    (folder / "binary.svs").write_bytes(os.urandom(256))
    cases["session binary.svs"] = folder / "binary.svs"
    return cases


def outside_cases(folder: Path) -> dict[str, Path]:
    """Files naming data outside their folder (refused, or asked about, by the io layer)."""
    inner = folder / "inner"
    inner.mkdir()
    (folder / "outside.raw").write_bytes(np.zeros(216, "<f4").tobytes())
    (inner / "hdr.mhd").write_text(
        "ObjectType = Image\nNDims = 3\nDimSize = 6 6 6\nElementType = MET_FLOAT\n"
        "ElementDataFile = ../outside.raw\n")
    (inner / "up.svs").write_text(json.dumps({
        "format": "splineviz-session", "schema_version": 3,
        "objects": [{"id": "v", "type": "VolumeFile",
                     "properties": {"path": "../../../../../../../../etc/passwd",
                                    "dims": [4, 4, 4], "dtype": "uint8"}}]}))
    return {"header outside": inner / "hdr.mhd", "session outside": inner / "up.svs"}


class _Questions:
    """Stands in for QMessageBox in commands.py: records questions, answers No."""

    StandardButton = commands_module.QMessageBox.StandardButton
    asked: list[str] = []

    @classmethod
    def question(cls, parent, title, text, *args):
        cls.asked.append(text)
        return cls.StandardButton.No


def _errors(window) -> int:
    return sum(" error: " in f" {line}" for line in window.log.lines())


@pytest.fixture
def window(qtbot, tmp_path):
    w = open_window(tmp_path / "settings", size=(160, 120))
    yield w
    close_window(w)


def _open(window, path) -> None:
    window.open_path(path, mode="add")
    window.wait_idle(60)


#: the default run's share of the corpus (each open is a job process: ~0.3-1 s on a loaded
#: machine); the whole corpus runs under -m slow
QUICK = ("damaged cut_v.vti", "damaged flip_v.nrrd", "damaged cut_p.ply", "damaged flip_p.xyz",
         "empty file", "empty folder", "FIFO", "raw without dims", "session deep.svs",
         "session schema1.svs", "session absolute.svs", "header outside", "session outside",
         "NaN volume")


@pytest.mark.parametrize("full", [False, pytest.param(True, marks=pytest.mark.slow)],
                         ids=["quick", "full"])
def test_bad_files_through_open_give_one_message_and_leave_the_scene(window, tmp_path,
                                                                     capfd, monkeypatch,
                                                                     full):
    shared = Path(os.environ.get("SPLINEVIZ_SHARED_DATA", "")) or None
    if shared is None or not shared.is_dir():
        from conftest import SHARED_DATA

        shared = SHARED_DATA if SHARED_DATA.is_dir() else None
    _Questions.asked = []
    monkeypatch.setattr(commands_module, "QMessageBox", _Questions)
    window.open_default()
    window.wait_idle()
    base = tmp_path / "corpus"
    base.mkdir()
    valid = valid_files(base, shared)
    corpus = {f"damaged {p.name}": p for p in damaged(valid, base)}
    must_refuse = hostile(base)
    corpus.update(must_refuse)
    outside = outside_cases(base)
    corpus.update(outside)
    strict = _part_a()
    x = np.asarray(_volume().data).copy()
    x[2, 2, 2] = np.nan
    np.save(base / "nan.npy", x)
    corpus["NaN volume"] = base / "nan.npy"
    if not full:
        corpus = {k: v for k, v in corpus.items() if k in QUICK}
        must_refuse = {k: v for k, v in must_refuse.items() if k in QUICK}
    outcomes = {"refused": [], "accepted": [], "asked": []}
    for name, path in corpus.items():
        before, n_err, n_asked = describe(window.scene), _errors(window), len(_Questions.asked)
        n_log = len(window.log.lines())
        ids = [n.id for n in window.scene]
        _open(window, path)
        assert window.isVisible(), name
        new_errors = _errors(window) - n_err
        asked = len(_Questions.asked) - n_asked
        added = [n for n in window.scene if n.id not in ids]
        if asked:
            # the question is the one message; answered No, nothing is read
            assert asked == 1 and new_errors == 0, name
            assert describe(window.scene) == before, name
            assert "outside its folder. Read it anyway?" in _Questions.asked[-1], name
            outcomes["asked"].append(name)
        elif new_errors:
            assert new_errors == 1, (name, window.log.lines()[n_log:])
            assert describe(window.scene) == before, name
            assert window.statusBar().currentMessage() or window.last_error, name
            outcomes["refused"].append(name)
        else:
            # read after all (a flipped sample, a cut text file): added like any file
            assert added and name not in must_refuse, (name, window.log.lines()[n_log:])
            if name == "NaN volume" and strict:
                # a warned acceptance: the log panel says so
                assert any("warning:" in ln for ln in window.log.lines()[n_log:]), name
            for node in added:
                if node.id in window.scene:
                    window.scene.remove(node)
            outcomes["accepted"].append(name)
        window.wait_idle()
    if strict:
        assert set(outside) <= set(outcomes["asked"]), outcomes
    if not full:
        assert sorted(corpus) == sorted(QUICK)  # every quick case was made
    out, err = capfd.readouterr()
    assert "Traceback" not in out + err
    assert window.isVisible() and window.scene.volumes[0].source == "marschner-lobb"
    counts = {k: len(v) for k, v in outcomes.items()}
    print(f"{len(corpus)} bad files through File > Open: {counts}; accepted: "
          f"{outcomes['accepted']}")
    assert counts["refused"] >= len(must_refuse)


def _Outside(referrer, data_path):
    """The io layer's refusal of a data file outside the folder of ``referrer``."""
    from splineviz.io.errors import OutsideFolderError

    return OutsideFolderError(f"{Path(referrer).name} names {data_path}, outside its folder",
                              path=Path(data_path), folder=Path(referrer).parent,
                              referrer=Path(referrer))


def _run_here(window):
    """JobRunner.run done at once in this process: a reader patched in this process is
    the one that runs."""
    from splineviz.gui.jobs import error_message

    def run(label, func, *args, on_done=None, on_error=None, cancellable=True,
            process=False, **kwargs):
        try:
            result = func(*args, **kwargs)
        except Exception as exc:  # noqa: BLE001  (as a job reports it)
            window.show_error(error_message(exc))
            return None
        on_done(result)
        return None

    return run


@pytest.mark.parametrize("answer", ["Yes", "No"])
def test_outside_data_file_is_asked_about_and_read_only_when_confirmed(window, tmp_path,
                                                                       monkeypatch, answer):
    from splineviz.io import opening

    calls = []

    def fake_open_path(path, *, repoint=None, allow_outside=False):
        calls.append(allow_outside)
        if not allow_outside:
            raise _Outside(path, "/srv/elsewhere/x.raw")
        warnings.warn("2 NaN samples replaced by 0.0", SplinevizWarning, stacklevel=2)
        return opening.Opened("volume", _volume(), Path(path))

    asked = []

    class Box(_Questions):
        @classmethod
        def question(cls, parent, title, text, *args):
            asked.append(text)
            return getattr(cls.StandardButton, answer)

    monkeypatch.setattr(opening, "open_path", fake_open_path)
    monkeypatch.setattr(window.jobs, "run", _run_here(window))
    monkeypatch.setattr(commands_module, "QMessageBox", Box)
    hdr = tmp_path / "h.mhd"
    hdr.write_text("ObjectType = Image\n")
    window.open_path(hdr, mode="add")
    assert asked == ["h.mhd names data file /srv/elsewhere/x.raw outside its folder. "
                     "Read it anyway?"]
    if answer == "Yes":
        assert calls == [False, True] and [v.name for v in window.scene.volumes] == ["h.mhd"]
        # the warning raised while reading is shown: log panel and status bar
        assert "warning: h.mhd: 2 NaN samples replaced by 0.0" in window.log.lines()[-1]
        assert "NaN samples replaced" in window.statusBar().currentMessage()
    else:
        assert calls == [False] and not len(window.scene)
        assert "not read" in window.log.lines()[-1] and window.last_error is None


def test_outside_session_is_asked_about_then_loaded(window, tmp_path, monkeypatch):
    from splineviz.io import session as io_session

    real = io_session.load_session
    calls = []

    def fake_load_session(path, *, repoint=None, check_data=True, allow_outside=False):
        calls.append(allow_outside)
        if not allow_outside:
            raise _Outside(path, "/data/ct.nrrd")
        return real(path, repoint=repoint, check_data=check_data)

    asked = []

    class Box(_Questions):
        @classmethod
        def question(cls, parent, title, text, *args):
            asked.append(text)
            return cls.StandardButton.Yes

    window.open_default()
    path = tmp_path / "s.svs"
    window.save_session(path)
    window.scene.clear()
    monkeypatch.setattr(io_session, "load_session", fake_load_session)
    monkeypatch.setattr(commands_module, "QMessageBox", Box)
    window.open_path(path)
    window.wait_idle()
    assert calls == [False, True] and len(asked) == 1 and "s.svs names data file" in asked[0]
    assert window.scene.volumes[0].source == "marschner-lobb" and window.last_error is None


def test_unexpected_error_while_parsing_a_session_is_one_message(window, tmp_path,
                                                                 monkeypatch, capfd):
    from splineviz.io import session as io_session

    def broken(path, **kwargs):
        raise TypeError("'int' object is not iterable")

    monkeypatch.setattr(io_session, "load_session", broken)
    (tmp_path / "x.svs").write_text("{}")
    window.open_path(tmp_path / "x.svs")
    assert window.last_error == "TypeError: 'int' object is not iterable"
    assert window.isVisible() and "Traceback" not in "".join(capfd.readouterr())
