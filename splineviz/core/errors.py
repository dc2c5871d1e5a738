"""User-facing error types. Anything raised as a :class:`SplinevizError` is a problem with the
user's input or environment; front ends (CLI, GUI) show its message as one sentence instead of
a traceback."""


class SplinevizError(Exception):
    """Base class of errors caused by user input (files, parameters, data)."""


class SplinevizWarning(UserWarning):
    """Input accepted with a change the user should know of (e.g. NaN samples replaced)."""
