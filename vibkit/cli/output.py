"""What the command line tells the user: data on stdout (a table, or JSON with a schema version),
messages on stderr, :class:`CLIError` for a problem with the command's inputs (exit 1) and
:class:`UsageError` for options that exclude each other (exit 2)."""

from __future__ import annotations

import contextlib
import json
import math
import os
import sys

SCHEMA_VERSION = 1


class CLIError(ValueError):
    """A problem with the command's inputs, reported in one line (exit 1)."""


class UsageError(CLIError):
    """A usage error that argparse cannot see (options that exclude each other): one line, exit 2 as argparse's."""


def schema(cmd):
    return f"vibkit.{cmd}/{SCHEMA_VERSION}"


def color():
    return sys.stderr.isatty() and "NO_COLOR" not in os.environ and os.environ.get("TERM", "") != "dumb"


def shown(path) -> str:
    """The name a message gives a recording: ``<stdin>`` for ``-`` (as the reader's own messages name it)."""
    from vibkit.io import source_name

    return source_name(path)


def in_file(path, exc) -> Exception:
    """``exc`` if its message names ``path``, else a ValueError whose one line starts with it.

    A message that starts with the file's base name (the library names the file it read so) or with
    ``<stdin>`` (for ``-``) has that name replaced by ``path``, not repeated after it."""
    text = " ".join(str(exc).split()) or type(exc).__name__
    path = shown(path)
    if path in text:
        return exc
    name = os.path.basename(path)
    if name and text.startswith(f"{name}: "):
        text = text[len(name) + 2 :]
    return ValueError(f"{path}: {text}")


def msg(text):
    """A message on stderr: one line when piped (for grep and logs), folded at 100 columns on a terminal."""
    if len(text) > 100 and "\n" not in text and sys.stderr.isatty():
        import textwrap

        text = textwrap.fill(text, 100, subsequent_indent="    ", break_on_hyphens=False)
    print(text, file=sys.stderr)


def jsonable(o):
    import numpy as np

    if isinstance(o, dict):
        return {str(k): jsonable(v) for k, v in o.items()}
    if isinstance(o, (list, tuple)):
        return [jsonable(v) for v in o]
    if isinstance(o, np.ndarray):
        return jsonable(o.tolist())
    if isinstance(o, (np.floating, float)):
        v = float(o)
        return v if math.isfinite(v) else None
    if isinstance(o, (np.integer,)):
        return int(o)
    if isinstance(o, (np.bool_,)):
        return bool(o)
    return o


def print_json(cmd, payload):
    d = {"schema": schema(cmd)}
    d.update(jsonable(payload))
    print(json.dumps(d, indent=2, sort_keys=False, allow_nan=False))


def table(rows, header=None):
    rows = [[str(c) for c in r] for r in rows]
    if header:
        rows = [list(header)] + rows
    if not rows:
        return ""
    w = [max(len(r[i]) for r in rows) for i in range(len(rows[0]))]
    lines = ["  ".join(c.ljust(w[i]) for i, c in enumerate(r)).rstrip() for r in rows]
    if header:
        lines.insert(1, "  ".join("-" * x for x in w))
    return "\n".join(lines)


#: the file name that means standard output (``-o -``) or standard input (a recording ``-``)
STDIO = "-"


def is_stdout(path) -> bool:
    """Whether an output path is ``-``: the bytes go to standard output and no file is created."""
    return path is not None and not isinstance(path, bytes) and os.fspath(path) == STDIO


def check_output(out, inputs, force=False, *, json_flag=False):
    """Refuse an unsafe -o before any work (see :mod:`vibkit.runtime.safe_output`).

    ``-o -`` (standard output) is always safe, but not together with ``--json`` (``json_flag``):
    both would write to standard output."""
    from vibkit.runtime.safe_output import check_output_path

    if is_stdout(out):
        if json_flag:
            raise UsageError("-o - writes the output to stdout, and so does --json: give one of them")
        check_stdout_open()
        return
    check_output_path(out, overwrite=force, inputs=[p for p in inputs if p and not is_stdout(p)])


def check_stdout_open():
    """``-o -`` with standard output closed (``>&-``: Python's ``sys.stdout`` is None) is refused before any work."""
    if sys.stdout is None:
        raise CLIError("-o -: standard output is closed; give a file to write to (-o FILE), or open stdout")


def no_stdout(out, what):
    """Refuse ``-o -`` for an output that is not one stream of bytes (a folder, a store)."""
    if is_stdout(out):  # what the options say alone: a usage error (exit 2), as `-o -` with --json is
        raise UsageError(f"-o -: the output is {what}, which cannot go to stdout; give its path")


@contextlib.contextmanager
def output_path(out, suffix=""):
    """The path a command writes its output file to: ``out`` itself, or for ``-o -`` a temporary
    file (named ``*suffix``) whose bytes are copied to standard output once the command wrote it;
    what the command prints meanwhile goes to stderr. A failed command sends nothing to stdout."""
    if not is_stdout(out):
        yield out
        return
    import shutil
    import tempfile

    with tempfile.TemporaryDirectory(prefix="vibkit-stdout-") as folder:
        tmp = os.path.join(folder, "output" + suffix)
        with contextlib.redirect_stdout(sys.stderr):
            yield tmp
        sys.stdout.flush()
        with open(tmp, "rb") as f:
            shutil.copyfileobj(f, sys.stdout.buffer)
        sys.stdout.buffer.flush()
