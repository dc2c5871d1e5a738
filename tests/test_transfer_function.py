"""Transfer functions: table, opacity correction, skipping ranges, presets, ParaView JSON."""

import numpy as np
import pytest

from splineviz.core.transfer_function import (
    PRESETS,
    TABLE_SIZE,
    TransferFunction,
    TransferFunctionError,
    corrected_alpha,
    preset,
    read_paraview_json,
    resolve,
    write_paraview_json,
)


def test_table_interpolates_the_points():
    tf = TransferFunction([0, 0, 0, 0, 10, 1, 0.5, 0], [0, 0, 5, 1, 10, 0])
    np.testing.assert_allclose(tf.lookup([0, 2.5, 5, 10]),
                               tf.evaluate([0, 2.5, 5, 10]), atol=1e-3)
    assert tf.table().shape == (TABLE_SIZE, 4)
    np.testing.assert_allclose(tf.evaluate(5.0), [0.5, 0.25, 0, 1])


def test_opacity_correction_composes():
    # two half steps are as opaque as one whole step
    a = 0.3
    half = corrected_alpha(a, 0.5)
    assert abs(1 - (1 - half) ** 2 - a) < 1e-12


def test_transparent_ranges_match_brute_force():
    tf = TransferFunction([0, 0, 0, 0, 1, 1, 1, 1], [0, 0, 0.4, 0, 0.6, 0.5, 0.7, 0, 1, 0])
    rng = np.random.default_rng(1)
    lo = rng.uniform(-0.2, 1.1, 500)
    hi = lo + rng.uniform(0, 0.3, 500)
    got = tf.transparent_between(lo, hi)
    for a, b, g in zip(lo, hi, got, strict=True):
        x = np.linspace(a, b, 400)
        if g:  # claimed transparent: truly zero everywhere the kernel may look
            assert np.all(tf.lookup(x)[:, 3] == 0)
    assert got.any() and not got.all()
    assert not tf.transparent_between(0.45, 0.5)


def test_presets_and_paraview_round_trip(tmp_path):
    for name in PRESETS:
        tf = preset(name, (-1000, 3000))
        assert tf.range[0] >= -1000 and tf.range[1] <= 3000
        assert tf.opacity_points[:, 1].max() > 0
        path = tmp_path / f"{name}.json"
        write_paraview_json(tf, path)
        back = read_paraview_json(path)
        np.testing.assert_allclose(back.rgb_points, tf.rgb_points)
        np.testing.assert_allclose(back.opacity_points, tf.opacity_points)
        assert back.name == name
        assert resolve(str(path), (0, 1)).name == name
    state = preset("mri", (0, 1)).to_state()
    np.testing.assert_allclose(TransferFunction.from_state(state).rgb_points,
                               preset("mri", (0, 1)).rgb_points)


def test_paraview_preset_without_opacity_ramps(tmp_path):
    path = tmp_path / "cmap.json"
    path.write_text('[{"Name": "x", "RGBPoints": [0, 0, 0, 1, 2, 1, 0, 0]}]')
    tf = read_paraview_json(path, value_range=(10, 20))
    assert tf.range == (10.0, 20.0)
    np.testing.assert_allclose(tf.evaluate(15.0)[3], 0.5)


@pytest.mark.parametrize("bad", ["[]", "{}", "not json", '[{"RGBPoints": [0, 1, 2]}]'])
def test_bad_files_are_one_clear_error(tmp_path, bad):
    path = tmp_path / "bad.json"
    path.write_text(bad)
    with pytest.raises(TransferFunctionError):
        read_paraview_json(path)


def test_unknown_preset():
    with pytest.raises(TransferFunctionError, match="neither a transfer function preset"):
        resolve("ct-brain", (0, 1))
