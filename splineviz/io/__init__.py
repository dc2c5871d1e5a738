"""Readers, writers and session files (no Qt, no rendering).

Public entry points: :func:`read_volume`, :func:`read_volume_sequence` (4-D files),
:func:`read_points`, :func:`write_volume`,
:func:`write_mesh`, :func:`read_mesh`, :func:`write_screenshot`, :func:`describe`,
:func:`open_path` (session, volume or points, whichever the file is), and the session API
:func:`load_session` / :func:`save_session` / :func:`migrate`. Formats live in a registry
(:func:`register_format`) that plugins extend. Errors are the typed, one-sentence classes of
:mod:`splineviz.io.errors`.
"""

from splineviz.io import chunked, dicom, neuro, tiff  # noqa: F401  (register their formats)
from splineviz.io.describe import describe  # noqa: F401
from splineviz.io.errors import (  # noqa: F401
    CorruptFileError,
    DataFileNotFoundError,
    DataSizeError,
    DataTooLargeError,
    FileFormatError,
    InvalidDataError,
    PluginError,
    SessionError,
    SessionPathError,
    SessionVersionError,
    UnknownFormatError,
    WriteError,
)
from splineviz.io.meshes import (  # noqa: F401
    read_image,
    read_mesh,
    write_mesh,
    write_screenshot,
)
from splineviz.io.opening import Opened, open_path  # noqa: F401
from splineviz.io.points import PointData, load_point_data, read_points  # noqa: F401
from splineviz.io.registry import FORMATS, Format, find_format, register_format  # noqa: F401
from splineviz.io.sequence import VolumeSequence, read_volume_sequence  # noqa: F401
from splineviz.io.session import Session, load_session, migrate, save_session  # noqa: F401
from splineviz.io.volumes import (  # noqa: F401
    VolumeData,
    load_volume_data,
    read_volume,
    to_volume,
    write_volume,
)
