"""Typed, user-facing errors of the ``io`` layer.

Every problem with a file, a format or a session is raised as one of these
:class:`~splineviz.core.errors.SplinevizError` subclasses with a one-sentence message, so the
CLI prints one line and the GUI shows one message box. The classes also derive from the
matching built-in exception (``ValueError``, ``FileNotFoundError``, ``MemoryError``) so that
generic handlers keep working.
"""

from __future__ import annotations

from splineviz.core.errors import SplinevizError

#: longest message kept; library messages can quote whole headers
MAX_MESSAGE = 300


class _OneSentence:
    """Mixin: the message is collapsed to one line (libraries add newlines and hints)."""

    def __init__(self, message="", *args):
        text = " ".join(str(message).split())
        if len(text) > MAX_MESSAGE:
            text = text[: MAX_MESSAGE - 3] + "..."
        super().__init__(text, *args)


class FileFormatError(_OneSentence, SplinevizError, ValueError):
    """A file whose format is unknown, unsupported or malformed."""


class UnknownFormatError(FileFormatError):
    """No registered format matches the file's suffix or content."""


class CorruptFileError(FileFormatError):
    """The file claims a known format but its header or payload is broken or truncated."""


class DataSizeError(CorruptFileError):
    """The header's dimensions and sample type do not match the size of the payload."""


class DataTooLargeError(_OneSentence, SplinevizError, MemoryError):
    """The data described by a header would not fit in the memory budget."""


class InvalidDataError(_OneSentence, SplinevizError, ValueError):
    """The file reads but its content cannot be used (empty, degenerate, NaN/Inf samples)."""


class DataFileNotFoundError(_OneSentence, SplinevizError, FileNotFoundError):
    """A data file (or a file a header refers to) does not exist or is not a regular file."""


class WriteError(_OneSentence, SplinevizError, OSError):
    """Output could not be written; no partial file is left behind."""


class SessionError(_OneSentence, SplinevizError, ValueError):
    """A session file that is malformed, hostile or of an unknown schema version."""


class SessionVersionError(SessionError):
    """The session's schema version is newer than this program or not a known one."""


class SessionPathError(SessionError):
    """A data path in a session is not allowed (absolute outside the session folder, special
    file) or cannot be found even after re-pointing."""


class PluginError(_OneSentence, SplinevizError, RuntimeError):
    """A plugin could not be loaded or registered something invalid."""


class OutsideFolderError(_OneSentence, SplinevizError, ValueError):
    """A file named by a header or a session resolves (symbolic links followed) outside the
    folder of the file that names it. Refused unless the caller opts in (``allow_outside=True``
    in the API, ``--allow-outside-data`` on the command line); a GUI asks the user about
    :attr:`path` and retries with the opt-in.

    Attributes
    ----------
    path : Path
        The resolved file that would have been read.
    folder : Path
        The resolved folder it had to stay in.
    referrer : Path
        The header or session that names the file.
    """

    def __init__(self, message="", *, path=None, folder=None, referrer=None):
        super().__init__(message)
        self.path = path
        self.folder = folder
        self.referrer = referrer


class SessionOutsideFolderError(OutsideFolderError, SessionPathError):
    """A session's data path resolves outside the session's folder (see
    :class:`OutsideFolderError`)."""
