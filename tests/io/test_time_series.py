"""Time-varying volumes (issue 27): a :class:`TimeSeries` of lazily read steps (4-D files,
folders and patterns of 3-D files, arrays with a leading time axis), the scene's current time
that volume nodes follow, sessions keeping the time axis, and ``render --time``."""

from __future__ import annotations

import threading

import numpy as np
import pytest
from PIL import Image

from splineviz.cli import main
from splineviz.io.time_series import (
    TimeSeries,
    TimeSeriesError,
    open_time_series,
    series_files,
)
from splineviz.model.nodes import ModelError
from splineviz.model.scene import Scene

nib = pytest.importorskip("nibabel")


def _ball_steps(n=3, shape=(20, 18, 16)):
    """(x, y, z, t) uint8: a ball growing step by step (an isosurface in every step)."""
    x, y, z = np.meshgrid(*(np.linspace(-1, 1, k) for k in shape), indexing="ij")
    r = np.sqrt(x**2 + y**2 + z**2)
    return np.stack([((1.0 + 0.2 * t) * (1 - r) * 120 + 40).clip(0, 255).astype(np.uint8)
                     for t in range(n)], -1)


@pytest.fixture
def nifti4d(tmp_path):
    data = _ball_steps()
    img = nib.Nifti1Image(data, np.diag([1.0, 1.5, 1.0, 1.0]))
    img.header.set_xyzt_units("mm", "sec")
    img.header["pixdim"][4] = 0.5
    path = tmp_path / "run.nii.gz"
    nib.save(img, path)
    return path, data


def test_4d_nifti_steps_and_times(nifti4d):
    path, data = nifti4d
    series = open_time_series(path)
    assert (len(series), series.unit) == (3, "s")
    assert series.times == pytest.approx((0.0, 0.5, 1.0))
    np.testing.assert_array_equal(series.step(2).data, data[..., 2])
    assert series.step(1).spacing == (1.0, 1.5, 1.0)


def test_step_names_index_or_time_with_unit(nifti4d):
    series = open_time_series(nifti4d[0])
    assert series.parse_step("1") == 1
    assert series.parse_step("-1") == 2
    assert series.parse_step("0.5s") == 1
    assert series.parse_step("1000ms") == 2
    for text, message in (("3", r"3 step\(s\) \(0 to 2\); step 3 is not one"),
                          ("0.7s", "no step at 0.7 s; its 3 steps run from 0 s to 1 s"),
                          ("1.5", "a step index is a whole number"),
                          ("2parsecs", "unknown time unit"),
                          ("soon", "--time takes a step index")):
        with pytest.raises(TimeSeriesError, match=message):
            series.parse_step(text)


def test_times_without_a_unit_take_no_unit(tmp_path):
    series = TimeSeries.from_array(np.zeros((2, 4, 4, 4), np.uint8))
    assert series.parse_step("1") == 1
    with pytest.raises(TimeSeriesError, match="without a unit"):
        series.parse_step("1s")


def test_folder_and_patterns_in_natural_order(tmp_path):
    data = _ball_steps(n=3, shape=(6, 5, 4))
    folder = tmp_path / "sim"
    folder.mkdir()
    for i, name in enumerate(("step_2.npy", "step_10.npy", "step_11.npy")):
        np.save(folder / name, data[..., i])
    (folder / "notes.txt").write_text("not a step")
    for path in (folder, folder / "step_*.npy"):
        series = open_time_series(path)
        assert len(series) == 3
        np.testing.assert_array_equal(series.step(1).data, data[..., 1])
    (folder / "run_0001.npy").write_bytes((folder / "step_2.npy").read_bytes())
    (folder / "run_0002.npy").write_bytes((folder / "step_10.npy").read_bytes())
    assert [f.name for f in series_files(folder / "run_####.npy")] == ["run_0001.npy",
                                                                        "run_0002.npy"]
    with pytest.raises(TimeSeriesError, match="no file matches"):
        open_time_series(folder / "none_##.npy")


def test_a_step_of_another_shape_is_refused(tmp_path):
    np.save(tmp_path / "a_0.npy", np.zeros((4, 4, 4), np.float32))
    np.save(tmp_path / "a_1.npy", np.zeros((4, 4, 5), np.float32))
    series = open_time_series(tmp_path / "a_#.npy")
    with pytest.raises(TimeSeriesError, match="a series keeps one shape"):
        series.step(1)


def test_cache_keeps_steps_within_its_cap_and_reads_ahead():
    steps = np.arange(6 * 8**3, dtype=np.float32).reshape(6, 8, 8, 8)
    read = []
    gate = threading.Event()

    class Logged:
        shape = steps.shape

        def __getitem__(self, i):
            if i == 3:
                gate.wait(10)  # the read ahead of step 3 holds until the test looks
            read.append(i)
            return steps[i]

    step_bytes = steps[0].nbytes
    series = TimeSeries.from_array(Logged(), cache_bytes=2 * step_bytes)
    try:
        np.testing.assert_array_equal(series.step(0).data, steps[0])
        series.step(0)
        assert read == [0]
        series.read_ahead(2, count=3)
        # room for one step beside the one shown: only step 3 is read ahead
        assert not series.cached(3)
        gate.set()
        np.testing.assert_array_equal(series.step(3).data, steps[3])
        assert read == [0, 3]
        series.step(4)
        series.step(5)
        assert [series.cached(i) for i in range(6)] == [False] * 4 + [True, True]
        assert series.reads == 4
    finally:
        gate.set()
        series.close()


def test_scene_time_moves_every_time_varying_volume():
    data = _ball_steps(n=4, shape=(8, 8, 8))
    scene = Scene()
    a = scene.add_time_series(
        TimeSeries.from_array(np.moveaxis(data, -1, 0), times=[0, 1, 2, 3], unit="s"), "a")
    b = scene.add_time_series(
        TimeSeries.from_array(np.moveaxis(data, -1, 0), times=[0, 2, 4, 6], unit="s"), "b",
        isosurface=False)
    b.time_offset = 1.0
    assert scene.time_steps() == (0.0, 1.0, 2.0, 3.0, 5.0, 7.0)
    heard = []
    scene.time_changed.connect(heard.append)
    scene.set_time(3.5)
    assert (a.time_index, b.time_index, heard) == (3, 1, [3.5])
    np.testing.assert_array_equal(a.data.data, data[..., 3])
    np.testing.assert_array_equal(b.data.data, data[..., 1])
    scene.set_step(0)  # before b starts: b shows its first step
    assert (a.time_index, b.time_index, scene.step_index()) == (0, 0, 0)
    with pytest.raises(ModelError, match="step 6 is not one"):
        scene.set_step(6)
    with pytest.raises(ModelError, match="past the last of 4 steps"):
        a.time_index = 4
    assert a.time_index == 0
    a.time_index = 2  # a step set on the node itself is read as well
    np.testing.assert_array_equal(a.data.data, data[..., 2])
    # the reading thread made the panels' summaries of each step it read
    from splineviz.model import summaries

    assert summaries._kept_value("histogram", a.data) is not None


def test_session_keeps_time_axis_step_and_rate(nifti4d, tmp_path):
    from splineviz.model.session import load_scene, save_scene

    path, data = nifti4d
    scene = Scene()
    vol = scene.add_time_series(open_time_series(path), step=2, path=str(path))
    scene.play_rate = 4.0
    save_scene(scene, tmp_path / "t.svs")
    again = load_scene(tmp_path / "t.svs")
    v = again.volumes[0]
    assert (v.time_series, v.time_index, again.play_rate, len(v.series)) == (True, 2, 4.0, 3)
    assert again.time == pytest.approx(1.0)
    np.testing.assert_array_equal(v.data.data, vol.data.data)


def test_render_step_equals_the_step_saved_alone(nifti4d, tmp_path, capsys):
    path, data = nifti4d
    alone = tmp_path / "step2.nii.gz"
    nib.save(nib.Nifti1Image(data[..., 2], np.diag([1.0, 1.5, 1.0, 1.0])), alone)
    args = ["--size", "64x48", "--model", "cubic-c1"]
    assert main(["render", str(path), "--time", "1s", *args, "-o",
                 str(tmp_path / "t.png")]) == 0
    assert main(["render", str(alone), *args, "-o", str(tmp_path / "a.png")]) == 0
    shot, ref = (np.asarray(Image.open(tmp_path / n)) for n in ("t.png", "a.png"))
    assert shot.std() > 5.0  # an isosurface is in the picture
    np.testing.assert_array_equal(shot, ref)
    assert main(["render", str(path), "--time", "3", "-o", str(tmp_path / "x.png")]) == 2
    err = capsys.readouterr().err
    assert "run.nii.gz has 3 step(s) (0 to 2); step 3 is not one" in err
    assert "Traceback" not in err


def test_render_all_times_writes_one_picture_per_step(nifti4d, tmp_path, capsys):
    path, _ = nifti4d
    out = tmp_path / "frame_{t:02d}.png"
    assert main(["render", str(path), "--all-times", "--size", "32x24", "--model", "trilinear",
                 "-o", str(out)]) == 0
    shots = [np.asarray(Image.open(tmp_path / f"frame_{k:02d}.png")) for k in range(3)]
    assert not np.array_equal(shots[0], shots[2])  # the ball grows
    assert main(["render", str(path), "--all-times", "-o", str(tmp_path / "same.png")]) == 2
    assert "frame_{t:04d}.png" in capsys.readouterr().err


def test_info_prints_steps_and_times(nifti4d, capsys):
    assert main(["info", str(nifti4d[0])]) == 0
    out = capsys.readouterr().out
    assert "steps: 3" in out
    assert "times: 0, 0.5, 1 s" in out


def test_dask_array_with_a_leading_time_axis_computes_one_step_per_read():
    da = pytest.importorskip("dask.array")
    steps = np.arange(4 * 6**3, dtype=np.float32).reshape(4, 6, 6, 6)
    computed = []

    def block(b, block_info=None):
        computed.append(block_info[0]["chunk-location"][0])
        return b

    lazy = da.from_array(steps, chunks=(1, 6, 6, 6)).map_blocks(block, dtype=np.float32)
    series = TimeSeries.from_array(lazy, spacing=(2.0, 2.0, 2.0), times=[0, 5, 10, 15],
                                   unit="ms")
    vol = series.step(2)
    np.testing.assert_array_equal(vol.data, steps[2])
    assert vol.spacing == (2.0, 2.0, 2.0) and computed == [2]
    assert series.parse_step("0.01s") == 2
    with pytest.raises(TimeSeriesError, match=r"must be 4-D \(t, x, y, z\)"):
        TimeSeries.from_array(steps[0])


def test_ome_zarr_t_axis_steps_with_times(tmp_path, capsys):
    pytest.importorskip("ome_zarr")
    import warnings

    import zarr
    from ome_zarr.io import parse_url

    with warnings.catch_warnings():
        warnings.simplefilter("ignore", DeprecationWarning)
        from ome_zarr.writer import write_image
    data = _ball_steps(n=3, shape=(12, 10, 8))  # (x, y, z, t)
    path = tmp_path / "run.ome.zarr"
    root = zarr.group(store=parse_url(str(path), mode="w").store)
    write_image(data.transpose(3, 2, 1, 0), root, axes="tzyx", scale_factors=[],
                axes_units={"t": "millisecond", "z": "micrometer", "y": "micrometer",
                            "x": "micrometer"},
                storage_options={"chunks": (1, 4, 4, 4)},
                scale={"t": 250.0, "z": 1.0, "y": 1.0, "x": 1.0})
    series = open_time_series(path)
    assert (len(series), series.unit) == (3, "ms")
    assert series.times == (0.0, 250.0, 500.0)
    np.testing.assert_array_equal(series.step(2).read(((0, 12), (0, 10), (0, 8))).data,
                                  data[..., 2])
    assert series.parse_step("0.25s") == 1
    assert main(["info", str(path)]) == 0
    out = capsys.readouterr().out
    assert "steps: 3" in out and "times: 0, 250, 500 ms" in out


def test_series_pickle_with_the_steps_read(nifti4d, tmp_path):
    """A session's series is opened in a job process and handed over pickled."""
    import pickle

    path, data = nifti4d
    np.save(tmp_path / "s_0.npy", data[..., 0])
    np.save(tmp_path / "s_1.npy", data[..., 1])
    for series in (open_time_series(path), open_time_series(tmp_path / "s_#.npy"),
                   TimeSeries.from_array(np.moveaxis(data, -1, 0))):
        series.step(1)
        series.read_ahead(0, 1)
        again = pickle.loads(pickle.dumps(series))
        assert again.cached(1) and again.times == series.times and again.reads == 1
        np.testing.assert_array_equal(again.step(0).data, data[..., 0])
        np.testing.assert_array_equal(again.step(1).data, data[..., 1])
        series.close()


def test_an_array_series_is_saved_as_the_step_shown(tmp_path):
    from splineviz.model.session import load_scene, save_scene

    data = _ball_steps(n=3, shape=(8, 8, 8))
    scene = Scene()
    scene.add_time_series(TimeSeries.from_array(np.moveaxis(data, -1, 0)), "sim", step=2)
    save_scene(scene, tmp_path / "a.svs")
    again = load_scene(tmp_path / "a.svs").volumes[0]
    assert again.series is None and not again.time_series
    np.testing.assert_array_equal(again.data.data, data[..., 2])
