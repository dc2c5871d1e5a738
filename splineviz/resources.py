"""Files shipped with splineviz in the top-level ``resources/`` folder (docs/architecture.md).

* ``resources/icons/*.svg`` -- toolbar icons (24x24 view box, strokes in ``currentColor``,
  which the root element sets to a mid grey that reads on light and dark toolbars; an accent
  blue for the highlighted part) and the colour app icon ``splineviz.svg``;
* ``resources/sessions/*.svs`` -- example sessions that open synthetic data of the
  first-party ``sources`` plugin (no data files), each with a camera that shows the whole
  data set. :data:`DEFAULT_SESSION` describes the scene of the embedded default data
  (Marschner-Lobb sampled on 41^3 points, a cubic C1 isosurface) as a session; the app
  itself builds that scene in code (:func:`splineviz.model.opening.default_scene`) when
  ``splineviz`` runs with no argument.

This module names files only: it imports no Qt, so the command line and tests use it too.
A GUI makes a ``QIcon(str(icon_path("open")))``, or a ``QSvgRenderer`` of
:func:`icon_svg` with another colour for a theme.

Examples
--------
>>> icon_path("open").name
'open.svg'
>>> "marschner-lobb" in example_sessions()
True
"""

from __future__ import annotations

import os
import re
from pathlib import Path

from splineviz.core.errors import SplinevizError

#: environment variable naming another resources folder (a packaged or patched copy)
RESOURCES_ENV = "SPLINEVIZ_RESOURCES"


def _resources_dir() -> Path:
    """The top-level ``resources/`` beside the package (a source checkout or an editable
    install), else ``splineviz/_resources`` (where a wheel may place a copy); the
    environment variable :data:`RESOURCES_ENV` overrides both."""
    env = os.environ.get(RESOURCES_ENV)
    if env:
        return Path(env).expanduser().resolve()
    top = Path(__file__).resolve().parents[1] / "resources"
    packaged = Path(__file__).resolve().parent / "_resources"
    return top if top.is_dir() or not packaged.is_dir() else packaged


#: the resources folder
RESOURCES: Path = _resources_dir()
ICONS_DIR: Path = RESOURCES / "icons"
SESSIONS_DIR: Path = RESOURCES / "sessions"

#: toolbar icons, in toolbar order
TOOLBAR_ICONS = ("open", "save", "screenshot", "reset-camera", "view-px", "view-mx", "view-py",
                 "view-my", "view-pz", "view-mz", "view-iso", "add-isosurface", "clip-plane",
                 "cancel")
#: the application's icon (window, task bar, desktop entry)
APP_ICON = "splineviz"
#: every icon shipped
ICONS = (*TOOLBAR_ICONS, APP_ICON)
#: standard view (:data:`splineviz.model.STANDARD_VIEWS` key) -> its icon
VIEW_ICONS = {"+X": "view-px", "-X": "view-mx", "+Y": "view-py", "-Y": "view-my",
              "+Z": "view-pz", "-Z": "view-mz", "isometric": "view-iso"}
#: the example session that describes the scene of the embedded default data
DEFAULT_SESSION = "marschner-lobb"

_ROOT_COLOR = re.compile(r'(<svg\b[^>]*?\bcolor=")([^"]*)(")')
_COLOR = re.compile(r"^(#[0-9A-Fa-f]{3}|#[0-9A-Fa-f]{6}|[A-Za-z]{3,20})$")


class ResourceError(SplinevizError, FileNotFoundError):
    """A resource (icon, example session) that is not shipped."""


def icon_names() -> list[str]:
    """Names of the icons in :data:`ICONS_DIR` (file names without ``.svg``), sorted."""
    return sorted(p.stem for p in ICONS_DIR.glob("*.svg"))


def icon_path(name: str) -> Path:
    """The SVG file of the icon ``name``.

    Parameters
    ----------
    name : str
        An icon name such as ``"open"``, ``"view-px"`` or ``"splineviz"`` (see :data:`ICONS`).

    Returns
    -------
    pathlib.Path
        ``resources/icons/<name>.svg``.

    Raises
    ------
    ResourceError
        No such icon; the message names it and the icons there are.

    Examples
    --------
    >>> icon_path(VIEW_ICONS["+X"]).stem
    'view-px'
    """
    path = ICONS_DIR / f"{name}.svg"
    if not isinstance(name, str) or "/" in name or "\\" in name or not path.is_file():
        names = ", ".join(icon_names()) or "none"
        raise ResourceError(f"no icon {name!r} in {ICONS_DIR}; icons: {names}")
    return path


def icon_svg(name: str, color: str | None = None) -> bytes:
    """The SVG text of the icon ``name``, its ``currentColor`` strokes set to ``color``.

    Toolbar icons draw in ``currentColor``, which their root element sets to a mid grey;
    a theme may give another colour (the accent blue and the app icon do not change).

    Parameters
    ----------
    name : str
        As for :func:`icon_path`.
    color : str, optional
        ``"#rgb"``, ``"#rrggbb"`` or an SVG colour name; None keeps the shipped grey.

    Returns
    -------
    bytes
        UTF-8 SVG document (``QSvgRenderer(QByteArray(data))`` reads it).

    Raises
    ------
    ResourceError
        No such icon.
    ValueError
        ``color`` is not a colour.

    Examples
    --------
    >>> b'color="#ffffff"' in icon_svg("save", "#ffffff")
    True
    """
    text = icon_path(name).read_text(encoding="utf-8")
    if color is not None:
        if not isinstance(color, str) or not _COLOR.match(color):
            raise ValueError(f"not an SVG colour: {color!r} (use #rrggbb or a colour name)")
        text = _ROOT_COLOR.sub(lambda m: f"{m[1]}{color}{m[3]}", text, count=1)
    return text.encode("utf-8")


def example_sessions() -> dict[str, Path]:
    """The example sessions shipped: name (file name without ``.svs``) -> path, sorted.

    Each opens synthetic data of the ``sources`` plugin, so it works without data files:
    ``splineviz.model.session.load_scene(path)``.

    Returns
    -------
    dict of str to pathlib.Path

    Examples
    --------
    >>> sorted(example_sessions())[:1]
    ['barth-sextic']
    """
    return {p.stem: p for p in sorted(SESSIONS_DIR.glob("*.svs"))}


def example_session(name: str) -> Path:
    """The path of the example session ``name`` (a key of :func:`example_sessions`).

    Raises
    ------
    ResourceError
        No such example; the message lists the examples.

    Examples
    --------
    >>> example_session(DEFAULT_SESSION).name
    'marschner-lobb.svs'
    """
    sessions = example_sessions()
    if name not in sessions:
        names = ", ".join(sessions) or "none"
        raise ResourceError(f"no example session {name!r} in {SESSIONS_DIR}; examples: {names}")
    return sessions[name]


def default_session() -> Path:
    """The example session :data:`DEFAULT_SESSION`: Marschner-Lobb on 41^3 points of
    [-1, 1]^3, a cubic C1 isosurface at 0.5, a camera that shows the whole box (the scene
    of the embedded default data, for scripts that want it as a file; the app does not
    read it)."""
    return example_session(DEFAULT_SESSION)
