"""The ``vibkit`` command line: parses, calls the library, prints.  No physics in here.

Data go to stdout (a readable table, or JSON with ``--json`` carrying ``"schema": "vibkit.<command>/1"``),
messages to stderr.  Exit status: 0 success (also when the reader closes stdout early, as ``| head``
does: quietly), 1 bad data or a failed run (one-line message, no traceback), 2 usage error (argparse, or a
:class:`~vibkit.cli.output.UsageError`: options that exclude each other).

Each command is a module of this package with ``add_parser(subparsers)`` and ``run(args)``; the
option types and the option groups they share are in :mod:`vibkit.cli.options`, the printing in
:mod:`vibkit.cli.output`.  The library is imported inside ``run``, so that ``--help`` and
``--version`` import nothing heavy.
"""

from __future__ import annotations

import argparse
import errno
import gc
import sys

from vibkit.runtime.duck_arrays import without_dask
from vibkit.runtime.reader_options import flag_spelling

from . import (
    bench,
    compare,
    datasets,
    fleet,
    links,
    pitch,
    report,
    ride,
    rides,
    scene,
    simulate,
    spectrum,
    sweep,
    warm,
)
from .options import plain_message
from .output import UsageError, color, msg

__all__ = ["main"]

# in the order ``vibkit --help`` lists them
COMMANDS = (simulate, scene, spectrum, pitch, links, compare, report, sweep, ride, rides, fleet, datasets, warm, bench)
#: the commands that build xarray Datasets of numpy arrays only, never of dask arrays: run as the process's own
#: command line, xarray runs as where dask is not installed (:func:`vibkit.runtime.duck_arrays.without_dask`) and
#: does not import dask to ask of each array whether it is one
NUMPY_ONLY = frozenset({"simulate", "spectrum", "pitch", "links", "compare", "report", "ride", "rides"})


class _Parser(argparse.ArgumentParser):
    """argparse with a usage error in one line and where to look (argparse prints the whole usage first: 12
    lines before the one that says what is wrong); its subcommands' parsers are of this class too."""

    def error(self, message):
        where = f"'{self.prog} --help'" if " " in self.prog else "'vibkit COMMAND --help'"
        self.exit(2, f"{self.prog}: error: {message} (run {where} for the options)\n")

    def parse_known_args(self, args=None, namespace=None):
        # the innermost (sub)command parser that left arguments unrecognised is kept with them: argparse reports
        # them from the top parser ("vibkit: error: unrecognized arguments"), which does not name the command
        ns, extras = super().parse_known_args(args, namespace)
        if extras and not hasattr(ns, _LEFT_BY):
            setattr(ns, _LEFT_BY, self)
        return ns, extras

    def parse_args(self, args=None, namespace=None):
        ns, extras = self.parse_known_args(args, namespace)
        parser = vars(ns).pop(_LEFT_BY, self)
        if extras:
            parser.error(f"unrecognized arguments: {' '.join(extras)}")
        return ns


#: the namespace attribute that names the parser which left arguments unrecognised (removed before the command runs)
_LEFT_BY = "_vibkit_unrecognized_by"


def _parser(only=None):
    """The command line's parser: every command's (``--help`` lists them), or with ``only`` (a command's name) that
    command's alone, which parses its arguments as the whole parser does."""
    import vibkit

    p = _Parser(
        prog="vibkit",
        description="Escalator drive-chain vibration: simulate, analyse, compare, report.",
        formatter_class=argparse.RawDescriptionHelpFormatter,
        epilog="run 'vibkit COMMAND --help' for each command's options and an example; \n"
        "the examples' data/... files are vibkit's example recordings and fleet ('vibkit datasets copy data'\n"
        "writes them into ./data), their sim/NAME.toml the scenes shipped with vibkit (found by name)",
    )
    p.add_argument("--version", action="version", version=f"vibkit {vibkit.__version__}")
    sub = p.add_subparsers(dest="command", metavar="COMMAND", required=True)
    for command in COMMANDS:
        if only is None or command.__name__.rpartition(".")[2] == only:  # each module is named after its command
            command.add_parser(sub)
    return p


def _named_command(argv):
    """The command that ``argv`` names first (``vibkit spectrum ...``), else None (``--help``, ``--version``, a
    misspelt name: the whole parser answers those)."""
    first = argv[0] if argv else None
    return first if any(c.__name__.rpartition(".")[2] == first for c in COMMANDS) else None


def main(argv=None) -> int:
    """Run the command line; returns the exit status (argparse usage errors raise SystemExit(2)).

    Parameters
    ----------
    argv : list of str, optional
        Arguments (default ``sys.argv[1:]``: the process's own command line, as the ``vibkit`` script runs it; the
        process is then the command's, and one that never makes a dask array runs xarray without dask).
    """
    # parse first: --help and --version import nothing heavy and compile nothing
    # only the named command's parser is built: the other thirteen (200 options) cost about 0.04 CPU-s a start
    args = _parser(_named_command(sys.argv[1:] if argv is None else argv)).parse_args(argv)
    if argv is None and args.command in NUMPY_ONLY:  # the process is this command's: before xarray is imported
        without_dask()
    # the process is this command's (the script's own command line): a command may import its libraries without
    # collecting and freeze them (vibkit.runtime.frozen_imports), which a program calling main([...]) keeps from
    args.own_process = argv is None
    args.argv = list(sys.argv[1:] if argv is None else argv)  # the command as typed (e.g. a sweep's to resume it)
    from vibkit.runtime.safe_output import Interrupted, handle_termination

    bad_epoch = _source_date_epoch()
    if bad_epoch:
        msg(f"vibkit {args.command}: error: {bad_epoch}")
        return 1

    try:
        # SIGTERM runs the same clean-up as Ctrl-C; the reader names its options as their flags
        with handle_termination(), flag_spelling():
            status = int(args.func(args))
            if sys.stdout is not None:  # None: started with stdout closed (>&-)
                sys.stdout.flush()  # a closed pipe is found here, not at the interpreter's exit
            if argv is None:
                # the process ends with the command: what it holds is left to the interpreter's exit, whose
                # collections would otherwise walk every object of numpy, scipy, pandas, xarray and matplotlib
                # (0.4-1 CPU-s); frozen, they are skipped, and the exit frees the memory all the same
                gc.freeze()
            return status
    except BrokenPipeError:
        # the reader closed stdout (``vibkit spectrum ... | head -1``): it has what it wanted; end quietly
        # with 0 (the README's exit codes are 0-3) and no "Exception ignored" when Python flushes at exit
        _stdout_to_devnull()
        return 0
    except Interrupted as exc:
        written = getattr(exc, "vibkit_note", "nothing was written")  # e.g. a sweep's runs stored so far
        msg(f"vibkit {args.command}: interrupted (signal {exc.signum}); {written}")
        return 128 + exc.signum
    except KeyboardInterrupt as exc:
        msg(f"vibkit {args.command}: interrupted; {getattr(exc, 'vibkit_note', 'nothing was written')}")
        return 130
    except UsageError as exc:  # what argparse cannot check, as argparse says it
        prog = " ".join(
            ["vibkit", args.command] + ([args.fleet_command] if getattr(args, "fleet_command", None) else [])
        )
        msg(f"{prog}: error: {' '.join(str(exc).split())} (run '{prog} --help' for the options)")
        return 2
    except Exception as exc:
        if not _is_user_error(exc):
            raise
        text = " ".join(str(exc).split()) or type(exc).__name__
        if isinstance(exc, OSError) and getattr(exc, "strerror", None):
            # the file: the error's own, else the output the command was writing (a PDF written by a library)
            name = getattr(exc, "filename", None) or getattr(args, "output", None)
            where = f"{name}: " if name and name != "-" else ""
            cause = {
                errno.ENOSPC: ("the disk is full", "free space, or write elsewhere with -o"),
                errno.EFBIG: ("a file-size limit, ulimit -f, stops the write", "raise the limit"),
                errno.EDQUOT: ("your disk quota is used up", "free space, or write elsewhere"),
            }.get(exc.errno)
            # what was kept: the command's own note (a sweep's runs stored so far, and how to resume), else nothing
            kept = getattr(exc, "vibkit_note", None) or (cause and f"nothing was written: {cause[1]}")
            text = f"{where}{exc.strerror}" + (f" ({cause[0]}; {kept})" if cause else "")
        text = plain_message(text, args)
        prefix = "\033[31merror\033[0m" if color() else "error"
        msg(f"vibkit {args.command}: {prefix}: {text}")
        return 1


def _source_date_epoch():
    """``SOURCE_DATE_EPOCH`` (a report's fixed date): empty is unset (removed, as numpy, imported by scipy, reads
    it with ``int()`` and every command failed with "invalid literal for int()"); a value that is not a whole
    number of seconds is the error message returned, else ``""``."""
    import os

    raw = os.environ.get("SOURCE_DATE_EPOCH")
    if raw is None:
        return ""
    if not raw.strip():
        del os.environ["SOURCE_DATE_EPOCH"]
        return ""
    try:
        int(raw)
    except ValueError:
        return (
            f"SOURCE_DATE_EPOCH={raw!r} is not a whole number of seconds since 1970 (it fixes a report's date); "
            "unset it or give one, e.g. 1764201600"
        )
    return ""


def _stdout_to_devnull():
    """Point the stdout file descriptor at the null device, so that the final flush of a closed pipe is silent."""
    import os

    try:
        fd = sys.stdout.fileno()
    except (AttributeError, OSError, ValueError):  # replaced by a test or a caller: nothing is flushed at exit
        return
    devnull = os.open(os.devnull, os.O_WRONLY)
    try:
        os.dup2(devnull, fd)
    finally:
        os.close(devnull)


def _is_user_error(exc) -> bool:
    """A bad input, a failed run or a refused output: reported in one line (exit 1), not a traceback."""
    if isinstance(exc, (ValueError, OSError, MemoryError)):
        return True
    integrate = sys.modules.get("vibkit.analyses.integrate")  # only if it was imported can it have raised
    return integrate is not None and isinstance(exc, integrate.IntegrationError)


if __name__ == "__main__":  # pragma: no cover
    sys.exit(main())
