"""A command imports what it uses: reading a recording and the frequency analysis load neither numba nor the
plotting, seismic or statistics libraries (those come with the paths that need them: compiled filters, reports,
miniSEED, Dask).  Checked on ``sys.modules`` of a fresh interpreter, never on a time."""

import json
import os
import subprocess
import sys
import textwrap
from pathlib import Path

import numpy as np
import pytest

import vibkit

ROOT = Path(vibkit.__file__).resolve().parents[1]  # the vibkit under test, wherever the clone lives
HEAVY = ("numba", "matplotlib", "obspy", "dask", "scipy.stats")


def _loaded_after(code, heavy=HEAVY):
    """Which of ``heavy`` a fresh interpreter has imported after running ``code`` (one marked not importable, None in
    ``sys.modules``, is not)."""
    probe = (
        textwrap.dedent(code)
        + f"\nimport json, sys\nprint(json.dumps({{m: sys.modules.get(m) is not None for m in {heavy!r}}}))\n"
    )
    env = dict(os.environ, PYTHONPATH=str(ROOT) + os.pathsep + os.environ.get("PYTHONPATH", ""))
    proc = subprocess.run([sys.executable, "-c", probe], capture_output=True, text=True, env=env, cwd=ROOT)
    assert proc.returncode == 0, proc.stderr
    return {m for m, loaded in json.loads(proc.stdout.splitlines()[-1]).items() if loaded}


def _csv(tmp_path):
    fs = 100.0
    t = np.arange(1000) / fs
    x = 1e-3 * np.sin(2 * np.pi * 3.5 * t)
    path = tmp_path / "ten-seconds.csv"
    path.write_text("time_s,accel_m_s2\n" + "".join(f"{a:.4f},{b:.6e}\n" for a, b in zip(t, x, strict=True)))
    return path


def test_the_command_line_and_the_readers_import_nothing_heavy():
    assert _loaded_after("import vibkit.cli.app, vibkit.io") == set()


def test_reading_a_recording_loads_no_numba_statistics_plots_or_seismic_reader(tmp_path):
    path = _csv(tmp_path)
    loaded = _loaded_after(
        f"import vibkit.io\nds = vibkit.io.read_recording({str(path)!r})\nassert ds.sizes['time'] == 1000"
    )
    # xarray imports dask (when installed) the first time it builds an index: not vibkit's choice, not checked
    assert loaded - {"dask"} == set()


def _as_the_script(args):
    """Code that runs ``vibkit ARGS`` as the ``vibkit`` script does: the process's own command line."""
    return f"import sys\nsys.argv = ['vibkit', *{list(map(str, args))!r}]\nfrom vibkit.cli import main\nrc = main()\n"


def test_the_spectrum_command_imports_nothing_it_does_not_run(tmp_path):
    """`vibkit spectrum` needs no compiled kernel, no plot, no seismic reader and no dask: numba stays unloaded (the
    signal package imports its kernels inside the functions that run them), and the process, being the command's,
    runs xarray as where dask is not installed, so that not even dask's base is imported to ask whether an array is
    a dask one.  scipy.signal itself imports scipy.stats, so that one is not checked."""
    path = _csv(tmp_path)
    heavy = (*HEAVY, "dask.base", "dask.array", "h5py", "netCDF4", "vibkit.analyses")
    loaded = _loaded_after(_as_the_script(["spectrum", path, "--band", "2.5:6", "--json"]) + "assert rc == 0\n", heavy)
    assert loaded - {"scipy.stats"} == set()


@pytest.mark.slow
def test_the_report_command_imports_no_dask(tmp_path):
    """`vibkit report` run as its own process needs no dask: xarray runs as where dask is not installed (not even
    dask's base imported to ask whether an array is a dask one), and its PDF is written."""
    out = tmp_path / "r.pdf"
    code = _as_the_script(["report", _csv(tmp_path), "-o", out, "--speed", "0.5"]) + "assert rc == 0\n"
    loaded = _loaded_after(code, ("dask", "dask.base", "dask.array", "obspy"))
    assert loaded == set()
    assert out.read_bytes().startswith(b"%PDF")


def test_a_library_caller_keeps_dask(tmp_path):
    """`main(argv)` called by a program (which may hold dask arrays) leaves dask importable, and xarray imports it as
    it does anywhere; once xarray is imported the command line leaves dask alone (xarray has decided then whether
    dask is there)."""
    code = f"""
        import contextlib, io, sys
        from vibkit.cli import main
        with contextlib.redirect_stdout(io.StringIO()):
            assert main(["spectrum", {str(_csv(tmp_path))!r}, "--band", "2.5:6"]) == 0
        from vibkit.runtime.duck_arrays import without_dask
        assert without_dask() is False
        """
    assert _loaded_after(code, ("dask", "xarray")) == {"dask", "xarray"}


def test_the_script_leaves_what_it_holds_to_the_exit_and_a_library_caller_keeps_its_collector(tmp_path):
    """`vibkit` run as its own process freezes its objects once the command is done and its output flushed, so that
    the interpreter's exit frees them without walking them all; `main(argv)` called by a program, which goes on,
    leaves its garbage collector as it was."""
    args = ["spectrum", _csv(tmp_path), "--band", "2.5:6", "--json"]
    script = _as_the_script(args) + "import gc\nassert rc == 0 and gc.get_freeze_count() > 0, gc.get_freeze_count()\n"
    assert _loaded_after(script, ()) == set()  # (the asserts ran: the probe ran after them)
    library = f"""
        import contextlib, gc, io
        from vibkit.cli import main
        with contextlib.redirect_stdout(io.StringIO()):
            assert main({list(map(str, args))!r}) == 0
        assert gc.get_freeze_count() == 0, gc.get_freeze_count()
        """
    assert _loaded_after(library, ()) == set()


def test_a_numpy_only_command_gives_the_same_numbers_without_dask(tmp_path):
    """Whether dask is there changes nothing but the imports: `vibkit spectrum --json` of the same file, run as the
    script (xarray without dask) and called by a program that uses dask arrays, gives the same JSON."""
    path = _csv(tmp_path)
    args = ["spectrum", path, "--band", "2.5:6", "--json"]
    script = _as_the_script(args) + "assert rc == 0 and sys.modules['dask'] is None\n"
    library = (
        "import dask.array\nfrom vibkit.cli import main\nimport sys\n"
        f"assert main({list(map(str, args))!r}) == 0 and sys.modules['dask'] is not None\n"
    )
    env = dict(os.environ, PYTHONPATH=str(ROOT) + os.pathsep + os.environ.get("PYTHONPATH", ""))
    outs = []
    for code in (script, library):
        proc = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, env=env, cwd=ROOT)
        assert proc.returncode == 0, proc.stderr
        outs.append(json.loads(proc.stdout))
    for d in outs:
        d.pop("elapsed_s", None)
    assert outs[0] == outs[1]


def test_a_command_is_parsed_by_its_own_parser_as_by_the_whole_one():
    """The command line builds only the named command's parser: its help, and what it makes of its arguments, are
    the whole parser's; anything but a command's name first (``--help``, a misspelling) gets the whole parser."""
    from vibkit.cli.app import COMMANDS, _named_command, _parser

    whole = _parser()
    names = [c.__name__.rpartition(".")[2] for c in COMMANDS]
    for name in names:
        own = _parser(name)
        assert _subparser(own, name).format_help() == _subparser(whole, name).format_help()
        assert list(_subparser(own, "").choices) == [name]
    argv = ["spectrum", "x.csv", "--band", "2.5:6", "--harmonics", "3", "--json"]
    assert vars(_parser("spectrum").parse_args(argv)) == vars(whole.parse_args(argv))
    assert [_named_command(a) for a in (["pitch", "x"], ["--help"], ["pitchh"], [], ["fleet", "scan"])] == [
        "pitch",
        None,
        None,
        None,
        "fleet",
    ]


def _subparser(parser, name):
    """The subparsers' action of ``parser`` (``name`` empty), or the parser of command ``name``."""
    import argparse

    action = next(a for a in parser._actions if isinstance(a, argparse._SubParsersAction))
    return action if not name else action.choices[name]


def test_loading_a_scene_loads_no_compiler():
    """A scene's checks (its chain closing within the tensioner's travel) need the guide's constants, not its kernels."""
    assert _loaded_after("import vibkit\nvibkit.load_scene('leon')") == set()


@pytest.mark.slow
def test_what_the_report_command_imports_ahead_is_what_it_imports_anyway(tmp_path):
    """Run as its own process, `vibkit report` imports its libraries (its module's ``LIBRARY``) before it runs, with
    the collector paused; called by a program, which imports them only as the command runs, it loads every one of
    them too: importing them ahead adds no module a report does not use."""
    from vibkit.cli import report

    assert report.LIBRARY
    out = tmp_path / "r.pdf"
    args = ["report", _csv(tmp_path), "-o", out, "--speed", "0.5"]
    library = f"""
        import contextlib, io
        from vibkit.cli import main
        with contextlib.redirect_stdout(io.StringIO()):
            assert main({list(map(str, args))!r}) == 0
        """
    assert _loaded_after(library, report.LIBRARY) == set(report.LIBRARY)


def test_a_refused_report_imports_no_plotting(tmp_path):
    """`vibkit report` run as its own process checks its output before it imports its libraries: an output that
    exists, without --force, is refused before matplotlib is loaded (and so at once)."""
    out = tmp_path / "r.pdf"
    out.write_bytes(b"%PDF-1.4 kept")
    code = _as_the_script(["report", _csv(tmp_path), "-o", out, "--speed", "0.5"]) + "assert rc != 0, rc\n"
    assert _loaded_after(code, ("matplotlib", "vibkit.diagnose.report")) == set()
    assert out.read_bytes() == b"%PDF-1.4 kept"
