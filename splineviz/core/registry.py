"""The one registry helper behind every extension point (spline models, file formats, sources).

A :class:`Registry` is a mapping from a key to an entry, with the operations every extension
point needs: :meth:`~Registry.register` (a second entry under the same key is refused unless
replaced on purpose), :meth:`~Registry.unregister`, :meth:`~Registry.lookup` with the one error
sentence "unknown spline model 'x'; choose one of a, b", and :meth:`~Registry.names`.

Plugins add entries, but this layer must not import :mod:`splineviz.plugins` (it sits above
``core``, ``io`` and ``model``). Instead one *loader hook* is installed with
:func:`set_loader` (the package ``splineviz`` installs the plugin loader on import), and a
registry calls it through :func:`load_extensions` when a lookup misses or when it lists its
entries, so a plugin's model, format or source is found by whichever layer asks first.

The plain mapping interface (``key in registry``, ``registry[key]``, iteration) never calls the
hook: it is what import-time code and the plugin loader itself use.
"""

from __future__ import annotations

import threading
from collections.abc import Callable, Hashable, Iterator, MutableMapping
from typing import Generic, TypeVar

from splineviz.core.errors import SplinevizError

V = TypeVar("V")

_LOADER: Callable[[], None] | None = None
# a hook that looks entries up while it runs (a plugin's register() checking for duplicates)
# must not start the hook again on the same thread
_IN_HOOK = threading.local()
_RAISE = object()


class RegistryError(SplinevizError, ValueError):
    """An unknown or duplicate registry key (the default error of a :class:`Registry`)."""


def set_loader(loader: Callable[[], None] | None) -> Callable[[], None] | None:
    """Install the hook that loads extensions (plugins); returns the previous one.

    ``loader()`` takes no arguments, registers what it finds into the registries, and must be
    cheap when called again (registries call it on every miss).
    """
    global _LOADER
    previous, _LOADER = _LOADER, loader
    return previous


def load_extensions() -> None:
    """Run the loader hook, if one is installed (a no-op inside the hook itself)."""
    loader = _LOADER
    if loader is None or getattr(_IN_HOOK, "active", False):
        return
    _IN_HOOK.active = True
    try:
        loader()
    finally:
        _IN_HOOK.active = False


class Registry(MutableMapping, Generic[V]):
    """Entries of one extension point, by key.

    Parameters
    ----------
    what : str
        What an entry is, for messages: ``"spline model"``.
    entries : mapping, optional
        The built-in entries, in the order front ends list them.
    error : type of Exception
        Raised with one sentence by :meth:`lookup` for an unknown key (:meth:`register`
        raises :class:`RegistryError` for a duplicate).
    describe : callable, optional
        ``describe(key) -> str`` names a key in messages (default ``repr``).

    Examples
    --------
    >>> r = Registry("colour", {"red": (1, 0, 0)})
    >>> r.register("blue", (0, 0, 1))
    (0, 0, 1)
    >>> r.lookup("green")
    Traceback (most recent call last):
    ...
    splineviz.core.registry.RegistryError: unknown colour 'green'; choose one of red, blue
    """

    def __init__(self, what: str, entries=None, *, error: type[Exception] = RegistryError,
                 describe: Callable[[Hashable], str] = repr):
        self.what = what
        self.error = error
        self.describe = describe
        self._entries: dict = dict(entries or {})
        self._lock = threading.RLock()

    # -- the plain mapping (never calls the loader hook) -------------------------------

    def __getitem__(self, key) -> V:
        return self._entries[key]

    def __setitem__(self, key, value: V) -> None:
        with self._lock:
            self._entries[key] = value

    def __delitem__(self, key) -> None:
        with self._lock:
            del self._entries[key]

    def __iter__(self) -> Iterator:
        return iter(list(self._entries))

    def __len__(self) -> int:
        return len(self._entries)

    def __repr__(self) -> str:
        return f"Registry({self.what!r}, {self._entries!r})"

    # -- the registry operations -------------------------------------------------------

    def register(self, key, entry: V, *, replace: bool = False) -> V:
        """Add ``entry`` under ``key`` and return it; an existing key raises
        :class:`RegistryError` unless ``replace``."""
        with self._lock:
            if key in self._entries and not replace:
                raise RegistryError(f"{self.what} {self.describe(key)} is already registered")
            self._entries[key] = entry
        return entry

    def unregister(self, key) -> V | None:
        """Remove ``key`` and return its entry (None when it was not registered)."""
        with self._lock:
            return self._entries.pop(key, None)

    def lookup(self, key, default=_RAISE) -> V:
        """The entry of ``key``, loading extensions first when it is missing.

        Parameters
        ----------
        key : hashable
        default : optional
            Returned when ``key`` is still missing after loading; without it, that raises.

        Raises
        ------
        error
            ``"unknown <what> <key>; choose one of <keys>"`` when neither a built-in entry
            nor an extension has ``key``.
        """
        if key not in self._entries:
            load_extensions()
        try:
            return self._entries[key]
        except KeyError:
            if default is not _RAISE:
                return default
        keys = ", ".join(k if isinstance(k, str) else self.describe(k) for k in self._entries)
        choice = f"choose one of {keys}" if keys else "none is installed"
        raise self.error(f"unknown {self.what} {self.describe(key)}; {choice}")

    def names(self) -> list:
        """Every key, extensions loaded, in registration order."""
        load_extensions()
        return list(self._entries)

    def entries(self) -> dict:
        """A copy of every entry by key, extensions loaded, in registration order."""
        load_extensions()
        with self._lock:
            return dict(self._entries)
