"""The first isovalue shows something (issue 26, part 4): on real data, read by the real
readers and rendered by render_scene, the default surface covers more than 1 % and less than
half of the data box's projected area (no noise wall, not empty)."""

import numpy as np
import pytest
from scipy.spatial import ConvexHull

import splineviz as sv
from splineviz.core.default_isovalue import (
    NOISE_ENCLOSED,
    default_isovalue,
    isovalue_from_histogram,
    separability,
)
from splineviz.model import Scene

SIZE = (160, 160)


def _coverage(volume, isovalue: float) -> float:
    """Pixels of the isosurface over pixels of the data box, both rendered from the
    isometric view of the default framing."""
    from splineviz.render.scene_view import render_scene

    scene = Scene()
    node = scene.add_volume(volume, "data", isosurface=False)
    node.show_outline = False
    scene.view.show_scale = False
    scene.view.background = (0.0, 0.0, 0.0)
    iso = scene.add_isosurface(node, isovalue=isovalue)
    scene.aspect = SIZE[0] / SIZE[1]
    scene.frame(view="isometric")
    surface = render_scene(scene, SIZE)
    iso.visible = False
    empty = render_scene(scene, SIZE)
    corners = np.array([(x, y, z) for x in volume.bounds[0] for y in volume.bounds[1]
                        for z in volume.bounds[2]], dtype=float)
    scene.add_mesh(corners, ConvexHull(corners).simplices, color=(1.0, 1.0, 1.0),
                   show_edges=False)
    box = render_scene(scene, SIZE)

    def drawn(img):
        return int((np.abs(img.astype(int) - empty).max(axis=2) > 0).sum())

    return drawn(surface) / drawn(box)


@pytest.mark.parametrize("name", ["EMD-3001.map",  # cryo-EM map: noise around 0
                                  "EMD-3197.map",  # cryo-EM map of a lattice filling the box
                                  "tooth.nrrd", "carotid.vtk",  # CT
                                  "HeadMRVolume.mhd"])  # MRI
def test_the_first_isovalue_shows_an_object_not_a_wall(shared_data, name):
    from splineviz.io.volumes import read_volume

    volume = read_volume(shared_data / "volumes" / name)
    scene = Scene()
    node = scene.add_volume(volume, name)
    iso = scene.isosurfaces_of(node)[0].isovalue
    lo, hi = volume.finite_range
    assert lo < iso < hi
    # the scene's rule reads the cached 128-bin histogram; a histogram of the samples
    # themselves gives nearly the same level
    assert abs(iso - default_isovalue(volume)) < 0.02 * (hi - lo)
    coverage = _coverage(volume, iso)
    assert 0.01 < coverage < 0.5, f"{name}: isovalue {iso:g} covers {coverage:.0%} of the box"


def test_the_middle_of_the_range_was_a_wall_on_the_cryo_em_map(shared_data):
    """What the rule replaces: the middle of the range cuts the noise all over the box
    (51 % of it measured, against 6 % for the default)."""
    from splineviz.io.volumes import read_volume

    volume = read_volume(shared_data / "volumes" / "EMD-3001.map")
    lo, hi = volume.finite_range
    middle = _coverage(volume, 0.5 * (lo + hi))
    assert middle > 0.4 and middle > 4 * _coverage(volume, default_isovalue(volume))


def test_two_classes_are_split_between_them():
    rng = np.random.default_rng(1)
    background, blob = rng.normal(10.0, 2.0, 80_000), rng.normal(100.0, 5.0, 20_000)
    counts, edges = np.histogram(np.concatenate([background, blob]), bins=128)
    level = isovalue_from_histogram(counts, edges)
    assert np.mean(background > level) < 0.001 and np.mean(blob < level) < 0.001


def test_noise_gets_the_level_enclosing_one_percent():
    rng = np.random.default_rng(2)
    samples = rng.normal(0.0, 1.0, 200_000)
    counts, edges = np.histogram(samples, bins=128)
    centres = 0.5 * (edges[1:] + edges[:-1])
    assert abs(separability(counts, centres, 0.0) - 2.0 / np.pi) < 0.01
    level = isovalue_from_histogram(counts, edges)
    assert np.mean(samples > level) == pytest.approx(NOISE_ENCLOSED, abs=0.002)


def test_an_object_class_bigger_than_the_background_gets_the_densest_percent():
    """A box the subject fills (a lattice): Otsu's split is clean but puts most samples
    above it, so its surface would be a wall through the box; the densest 1 % is shown."""
    rng = np.random.default_rng(3)
    dark, bright = rng.normal(-2.0, 0.5, 30_000), rng.normal(3.0, 1.0, 70_000)
    samples = np.concatenate([dark, bright])
    counts, edges = np.histogram(samples, bins=128)
    level = isovalue_from_histogram(counts, edges)
    assert np.mean(samples > level) == pytest.approx(NOISE_ENCLOSED, abs=0.002)
    # the same two classes the other way round: an object in a background keeps Otsu's level
    counts, edges = np.histogram(-samples, bins=128)
    level = isovalue_from_histogram(counts, edges)
    assert np.mean(-bright > level) < 0.01 and np.mean(-dark < level) < 0.01


def test_a_constant_volume_gets_its_value_and_a_given_isovalue_is_kept():
    scene = Scene()
    flat = scene.add_volume(sv.Volume(np.full((4, 4, 4), 3.0)), "flat")
    assert scene.isosurfaces_of(flat)[0].isovalue == 3.0
    ramp = sv.Volume(np.arange(64, dtype=float).reshape(4, 4, 4))
    node = scene.add_volume(ramp, "ramp", isovalue=7.25)
    assert scene.isosurfaces_of(node)[0].isovalue == 7.25


def test_big_and_chunked_volumes_are_subsampled():
    from splineviz.core.chunked import ChunkedVolume
    from splineviz.core.default_isovalue import MAX_SAMPLES, threshold_samples
    from splineviz.core.testfunctions import ml

    big = sv.Volume(np.zeros((160, 160, 160), dtype=np.float32))
    assert threshold_samples(big).size <= MAX_SAMPLES
    chunked = ChunkedVolume.from_function(ml, (64, 64, 64), ml.domain, chunks=32)
    level = default_isovalue(chunked)
    lo, hi = chunked.finite_range
    assert lo < level < hi
