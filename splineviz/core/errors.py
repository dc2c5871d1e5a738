"""User-facing error and warning types. Anything raised as a :class:`SplinevizError` is a
problem with the user's input or environment; front ends (CLI, GUI) show its message as one
sentence instead of a traceback. A :class:`SplinevizWarning` marks a documented acceptance
that changed the user's data or output (e.g. NaN samples replaced, an axis flipped); front
ends show it too, so nothing is changed silently."""


class SplinevizError(Exception):
    """Base class of errors caused by user input (files, parameters, data)."""


class SplinevizWarning(UserWarning):
    """Input was accepted with a documented change the user should know about (the GUI
    shows these; the CLI prints them as ``splineviz: warning: ...``)."""
