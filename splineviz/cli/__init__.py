"""The ``splineviz`` command line.

``splineviz [FILE|SESSION]`` opens the app (:mod:`splineviz.gui`); the sub-commands
(``render``, ``movie``, ``serve``, ``remesh``, ``info``, ``bench``...) are the front-ends in
this package, one module each, listed in :data:`SUBCOMMANDS`: each entry names a function
``register(subparsers)`` that adds its parser and sets ``func`` (called with the parsed
arguments, returns an exit code).
User errors (:class:`SplinevizError`, ``OSError``, malformed arguments) are printed as one
line on stderr with exit code 2; no traceback. Documented acceptances
(:class:`SplinevizWarning`) are printed as one ``splineviz: warning:`` line each; warnings of
third-party libraries are not printed (the error or warning they lead to is ours to word).
"""

from __future__ import annotations

import argparse
import sys
import warnings
from importlib import import_module

from splineviz import __version__
from splineviz.core.errors import SplinevizError, SplinevizWarning


class UsageError(SplinevizError, ValueError):
    """Malformed command-line arguments."""


class _Parser(argparse.ArgumentParser):
    """argparse with its errors raised, not printed with the usage text and exited on:
    every refusal is one line (see :func:`main`)."""

    def error(self, message):
        raise UsageError(f"{self.prog}: {message}")



# sub-command name -> "module:register_function"
SUBCOMMANDS: dict[str, str] = {
    "info": "splineviz.cli.info:register",
    "render": "splineviz.cli.render:register",
    "bench": "splineviz.cli.bench:register",
    "remesh": "splineviz.cli.remesh:register",
    "serve": "splineviz.cli.serve:register",
    "movie": "splineviz.cli.movie:register",
}


def _build_parser() -> argparse.ArgumentParser:
    parser = _Parser(
        prog="splineviz",
        description="Smooth spline isosurfaces of volume data and meshes from point clouds.",
    )
    parser.add_argument("--version", action="version", version=f"splineviz {__version__}")
    sub = parser.add_subparsers(dest="command")
    for target in SUBCOMMANDS.values():
        module_name, _, func = target.partition(":")
        getattr(import_module(module_name), func)(sub)
    return parser


def _viewer_parser() -> argparse.ArgumentParser:
    parser = _Parser(prog="splineviz", description="Open the splineviz app.")
    parser.add_argument("file", nargs="?", help="volume, point cloud or session to open")
    from splineviz.cli.render import add_renderer_argument, finite_float

    parser.add_argument("--iso", type=finite_float, default=None, help="isovalue")
    parser.add_argument("--model", default=None,
                        help="spline model (default: the smoothest one with an OpenCL kernel)")
    add_renderer_argument(parser)
    parser.add_argument("--screenshot", metavar="PNG", help="save the view to PNG and quit")
    parser.add_argument("--size", metavar="WxH", help="window / screenshot size, e.g. 1024x768")
    parser.add_argument("--series", metavar="UID|INDEX",
                        help="DICOM folders of several series: the one to open")
    return parser


def _show_warning(message, category, filename, lineno, file=None, line=None):
    """One ``splineviz: warning:`` line for our documented acceptances; nothing for the
    warnings of third-party libraries (MetaImage, nibabel, NumPy's RuntimeWarning...)."""
    if issubclass(category, SplinevizWarning):
        text = " ".join(str(message).split())
        print(f"splineviz: warning: {text}", file=sys.stderr if file is None else file)


def _one_line(exc: BaseException) -> str:
    return " ".join(str(exc).split()) or type(exc).__name__


def main(argv: list[str] | None = None) -> int:
    argv = list(sys.argv[1:] if argv is None else argv)
    with warnings.catch_warnings():
        warnings.simplefilter("always", SplinevizWarning)
        warnings.showwarning = _show_warning
        try:
            if argv and (argv[0] in SUBCOMMANDS or argv[0] in ("-h", "--help", "--version")):
                args = _build_parser().parse_args(argv)
                return int(args.func(args) or 0)
            args = _viewer_parser().parse_args(argv)
            if args.series is not None and args.file:
                from splineviz.io.dicom import series_file

                args.file = str(series_file(args.file, args.series))
            from splineviz.gui.app import run_gui

            return int(run_gui(args) or 0)
        except (SplinevizError, OSError) as exc:
            print(f"splineviz: error: {_one_line(exc)}", file=sys.stderr)
            return 2
        except MemoryError:
            print("splineviz: error: out of memory", file=sys.stderr)
            return 2
        except KeyboardInterrupt:
            return 130
