"""Fault injection on every writer: a write that fails part-way (no space, file too large,
no permission, an error at the rename, a kill between write and rename) leaves the previous
file byte for byte and no temporary file; saved files get the mode the umask gives."""

import errno
import os
import signal
import stat
import subprocess
import sys
import textwrap

import numpy as np
import pytest

import splineviz as sv
from splineviz.io import _util
from splineviz.io import errors as E
from splineviz.io.session import Session, save_session

OLD = b"previous contents, kept byte for byte\n" * 3


def _mesh():
    import pyvista as pv

    return pv.Icosphere(nsub=3)


VOL = sv.Volume(np.random.default_rng(0).random((12, 11, 10)))
IMG = (np.random.default_rng(1).random((60, 80, 3)) * 255).astype(np.uint8)

WRITERS = {
    "m.ply": lambda p: sv.write_mesh(p, _mesh()),
    "m.obj": lambda p: sv.write_mesh(p, _mesh()),
    "m.stl": lambda p: sv.write_mesh(p, _mesh()),
    "m.vtp": lambda p: sv.write_mesh(p, _mesh()),
    "v.vti": lambda p: sv.write_volume(p, VOL),
    "v.nrrd": lambda p: sv.write_volume(p, VOL),
    "v.npy": lambda p: sv.write_volume(p, VOL),
    "s.png": lambda p: sv.write_screenshot(p, IMG),
    "s.svs": lambda p: save_session(Session(), p),
    "r.json": lambda p: _util.atomic_write_bytes(p, b'{"report": 1}\n' * 100),
}


def _intact(d, name):
    assert (d / name).read_bytes() == OLD
    assert not [p.name for p in d.iterdir() if ".part" in p.name]


@pytest.mark.parametrize("name", sorted(WRITERS))
@pytest.mark.parametrize("err", [errno.ENOSPC, errno.EFBIG, errno.EACCES, errno.EIO])
def test_failed_rename_keeps_the_old_file(tmp_path, monkeypatch, name, err, tried):
    (tmp_path / name).write_bytes(OLD)

    def fail(*args):
        raise OSError(err, os.strerror(err))

    monkeypatch.setattr(_util.os, "replace", fail)
    with pytest.raises(E.WriteError) as info:
        WRITERS[name](tmp_path / name)
    assert "\n" not in str(info.value) and os.strerror(err) in str(info.value)
    _intact(tmp_path, name)
    tried["write faults"] += 1


@pytest.mark.parametrize("name", sorted(WRITERS))
@pytest.mark.parametrize("err", [errno.ENOSPC, errno.EIO])
def test_failed_fsync_keeps_the_old_file(tmp_path, monkeypatch, name, err, tried):
    """Delayed allocation: the data are written to the page cache, the disk is full at
    flush time; fsync is the only call that reports it."""
    (tmp_path / name).write_bytes(OLD)

    def fail(fd):
        raise OSError(err, os.strerror(err))

    monkeypatch.setattr(_util.os, "fsync", fail)
    with pytest.raises(E.WriteError):
        WRITERS[name](tmp_path / name)
    _intact(tmp_path, name)
    tried["write faults"] += 1


_LIMITED = textwrap.dedent("""
    import resource, sys
    from pathlib import Path
    sys.path.insert(0, {test_dir!r})
    from test_write_faults import WRITERS
    from splineviz.core.errors import SplinevizError
    d = Path(sys.argv[1])
    resource.setrlimit(resource.RLIMIT_FSIZE, (120, 120))  # Python ignores SIGXFSZ: EFBIG
    for name in sorted(WRITERS):
        try:
            WRITERS[name](d / name)
            print(name, "written")
        except SplinevizError as exc:
            print(name, "refused", str(exc).count(chr(10)))
""")


def test_file_size_limit_keeps_every_previous_file(tmp_path, tried):
    """The real thing, in a child process: RLIMIT_FSIZE makes every write past 120 bytes
    fail with EFBIG inside the libraries (VTK's PLY and OBJ writers ignore it)."""
    for name in WRITERS:
        (tmp_path / name).write_bytes(OLD)
    code = _LIMITED.format(test_dir=os.path.dirname(__file__))
    r = subprocess.run([sys.executable, "-c", code, str(tmp_path)], capture_output=True,
                       text=True, timeout=300)
    assert r.returncode == 0, r.stderr[-2000:]
    lines = dict(ln.split(" ", 1) for ln in r.stdout.splitlines())
    assert lines == {name: "refused 0" for name in WRITERS}, r.stdout
    for name in WRITERS:
        _intact(tmp_path, name)
    tried["write faults"] += len(WRITERS)


_KILLED = textwrap.dedent("""
    import os, sys, time
    from splineviz.io import _util
    def stall(src, dst):
        print("written", flush=True)
        time.sleep(60)
    _util.os.replace = stall
    _util.atomic_write_bytes(sys.argv[1], b"new contents" * 1000)
""")


def test_kill_between_write_and_rename_keeps_the_old_file(tmp_path, tried):
    target = tmp_path / "s.svs"
    target.write_bytes(OLD)
    with subprocess.Popen([sys.executable, "-c", _KILLED, str(target)],
                          stdout=subprocess.PIPE, text=True) as p:
        try:
            assert p.stdout.readline().strip() == "written"
        finally:
            p.send_signal(signal.SIGKILL)
            p.wait(timeout=60)
    assert target.read_bytes() == OLD
    # the complete temporary file is all that is left; a later save replaces the target
    assert len(list(tmp_path.iterdir())) == 2
    tried["write faults"] += 1


@pytest.mark.parametrize("mask", [0o022, 0o077, 0o002])
def test_new_files_get_the_mode_of_the_umask(tmp_path, mask):
    old = os.umask(mask)
    try:
        for name in ("m.ply", "s.svs", "v.npy", "s.png"):
            WRITERS[name](tmp_path / name)
            assert stat.S_IMODE((tmp_path / name).stat().st_mode) == 0o666 & ~mask, name
    finally:
        os.umask(old)


def test_replaced_files_keep_their_mode(tmp_path):
    (tmp_path / "s.svs").write_bytes(OLD)
    os.chmod(tmp_path / "s.svs", 0o640)
    save_session(Session(), tmp_path / "s.svs")
    assert stat.S_IMODE((tmp_path / "s.svs").stat().st_mode) == 0o640


def test_short_write_is_never_renamed(tmp_path):
    (tmp_path / "r.json").write_bytes(OLD)
    with pytest.raises(E.WriteError, match="stopped after 3 of 10 bytes"):
        with _util.atomic_output(tmp_path / "r.json", expected_size=10) as tmp:
            tmp.write_bytes(b"abc")
    _intact(tmp_path, "r.json")


def test_unwritable_folder(tmp_path):
    if os.geteuid() == 0:
        pytest.skip("root writes into read-only folders")
    (tmp_path / "ro").mkdir()
    os.chmod(tmp_path / "ro", 0o500)
    with pytest.raises(E.WriteError):
        save_session(Session(), tmp_path / "ro" / "s.svs")


def test_remesh_report_keeps_the_previous_report(tmp_path, monkeypatch, capsys):
    from splineviz import cli

    v = np.random.default_rng(2).normal(size=(400, 3))
    np.savetxt(tmp_path / "c.xyz", v / np.linalg.norm(v, axis=1, keepdims=True))
    (tmp_path / "report.json").write_bytes(OLD)

    def fail(*args):
        raise OSError(errno.ENOSPC, os.strerror(errno.ENOSPC))

    real = _util.os.replace
    monkeypatch.setattr(_util.os, "replace",
                        lambda a, b: fail() if str(b).endswith(".json") else real(a, b))
    rc = cli.main(["remesh", str(tmp_path / "c.xyz"), "-o", str(tmp_path / "m.ply"), "-q",
                   "--edge-length", "0.4", "--report", str(tmp_path / "report.json")])
    assert rc == 2
    assert capsys.readouterr().err.count("\n") == 1
    _intact(tmp_path, "report.json")
