"""A scene from what a user names on the command line: a file, a session or nothing.

``splineviz FILE --screenshot``, ``splineviz render`` and the GUI's start-up all build their
scene here, so the same arguments give the same scene (and, through
:func:`splineviz.render.scene_view.render_scene`, the same picture) on every path.
"""

from __future__ import annotations

import warnings
from dataclasses import dataclass

from splineviz.core.errors import SplinevizError, SplinevizWarning
from splineviz.model.scene import Scene
from splineviz.model.session import apply_session, read_session_data

#: the embedded default data's name in the data panel
DEFAULT_NAME = "Marschner-Lobb 41^3"


def default_volume():
    """The embedded default data set and its isovalue: Marschner-Lobb sampled on 41^3
    points of [-1, 1]^3 (generated, nothing to download)."""
    from splineviz.core.testfunctions import ml
    from splineviz.core.volume import Volume

    return Volume.from_function(ml, (41, 41, 41), ml.domain), ml.isovalue


def default_scene(scene: Scene | None = None) -> Scene:
    """The embedded default data (:func:`default_volume`) framed isometrically."""
    scene = Scene() if scene is None else scene
    scene.clear()
    vol, iso = default_volume()
    scene.add_volume(vol, DEFAULT_NAME, source="marschner-lobb", isovalue=iso)
    scene.frame(view="isometric")
    scene.mark_saved()
    return scene


def read_file(path, *, allow_outside: bool = False, **raw):
    """Read a volume or point cloud file: ``(kind, data, summaries)`` with kind ``"volume"``
    or ``"points"`` and the summaries views show (:mod:`splineviz.model.summaries`: a
    volume's histogram, a cloud's spacing; a volume's range is kept by the volume itself)
    computed here too, so a GUI that reads in a job process pays nothing to show them.
    Hand the summaries to :func:`splineviz.model.summaries.remember` in the receiving
    process. ``allow_outside`` and ``raw`` (a raw file's dims, dtype, byteorder, offset) as
    in :func:`splineviz.io.opening.open_path`."""
    from splineviz.io.opening import open_path
    from splineviz.model.summaries import log_histogram, median_spacing, summary_samples

    opened = open_path(path, allow_outside=allow_outside, **raw)
    if opened.kind == "session":
        raise SplinevizError(f"{opened.path.name} is a session; open it as one")
    if opened.kind != "volume":
        return opened.kind, opened.value, {"spacing": median_spacing(opened.value.points)}
    _ = opened.value.finite_range
    return opened.kind, opened.value, {"histogram": log_histogram(summary_samples(opened.value))}


@dataclass(frozen=True)
class OutsideFolder:
    """A file (header or session) that names a data file outside its own folder: the io
    layer refused to read it without the user's confirmation.

    Attributes
    ----------
    path : str
        The header or session.
    data_path : str
        The data file it names.
    message : str
        The refusal, one sentence.
    """

    path: str
    data_path: str
    message: str


def outside_folder(exc: BaseException) -> OutsideFolder | None:
    """The :class:`OutsideFolder` an io error stands for (an
    :class:`~splineviz.io.errors.OutsideFolderError`: a data file outside the folder of the
    file naming it), else None."""
    from splineviz.io.errors import OutsideFolderError

    if not isinstance(exc, OutsideFolderError):
        return None
    return OutsideFolder(str(exc.referrer or exc.folder or ""), str(exc.path), str(exc))


@dataclass(frozen=True)
class Noted:
    """What a read in a job process returns to the GUI: the result (or the refusal of a
    data file outside its folder) and the warnings raised while reading.

    Attributes
    ----------
    value : object or OutsideFolder
    warnings : list of str
        :class:`~splineviz.core.errors.SplinevizWarning` messages: shown to the user.
    other_warnings : list of str
        Library warnings (``Category: message``): logged, not shown.
    """

    value: object
    warnings: list
    other_warnings: list


def noting_warnings(func, *args, **kwargs) -> Noted:
    """Call ``func`` recording the warnings it raises and turning a refusal of a data file
    outside its folder into an :class:`OutsideFolder` (run in a job process: warnings are
    process state, and the refusal's exception need not pickle)."""
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        try:
            value = func(*args, **kwargs)
        except SplinevizError as exc:
            value = outside_folder(exc)
            if value is None:
                raise
    ours = [str(w.message) for w in caught if issubclass(w.category, SplinevizWarning)]
    other = [f"{w.category.__name__}: {w.message}" for w in caught
             if not issubclass(w.category, SplinevizWarning)]
    return Noted(value, ours, other)


def scene_from_path(path, *, isovalue=None, model=None, renderer=None, repoint=None,
                    allow_outside: bool = False, **volume_options) -> Scene:
    """Read a session, volume or point cloud into a new scene, framed isometrically
    (a session keeps its own camera). ``isovalue``/``model``/``renderer`` override every
    isosurface (:func:`override`);
    ``allow_outside`` lets headers and sessions name data outside their folders;
    ``volume_options`` (``channel``, ``oblique``) go to the volume reader."""
    from splineviz.io.opening import data_name, open_path

    opened = open_path(path, repoint=repoint, allow_outside=allow_outside, **volume_options)
    scene = Scene()
    if opened.kind == "session":
        apply_session(scene, opened.value,
                      read_session_data(opened.value, allow_outside=allow_outside))
    elif opened.kind == "volume":
        scene.add_volume(opened.value, data_name(opened.path), path=str(opened.path))
        scene.frame(view="isometric")
    else:
        scene.add_points(opened.value, opened.path.name, path=str(opened.path))
        scene.frame(view="isometric")
    override(scene, isovalue=isovalue, model=model, renderer=renderer)
    scene.mark_saved()
    return scene


def override(scene: Scene, *, isovalue=None, model=None, renderer=None) -> None:
    """Set the isovalue, spline model and/or renderer (a name or alias of
    :data:`splineviz.core.renderers.RENDERERS`) of every isosurface (command-line flags)."""
    from splineviz.core.registry import load_extensions
    from splineviz.core.renderers import renderer_name

    if model is not None:
        load_extensions()  # a plugin model named on the command line
    if renderer is not None:
        renderer = renderer_name(renderer)
    if (isovalue is not None or model is not None) and not scene.isosurfaces:
        raise SplinevizError("--iso and --model need a volume; this scene has no isosurface")
    for iso in scene.isosurfaces:
        if isovalue is not None:
            iso.isovalue = float(isovalue)
        if model is not None:
            iso.model = model
        if renderer is not None:
            iso.renderer = renderer
