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

import vibkit

ROOT = Path(vibkit.__file__).resolve().parents[1]  # the vibkit under test, wherever the clone lives
HEAVY = ("numba", "matplotlib", "obspy", "dask", "scipy.stats")


def _loaded_after(code, heavy=HEAVY):
    """Which of ``heavy`` a fresh interpreter has imported after running ``code``."""
    probe = (
        textwrap.dedent(code) + f"\nimport json, sys\nprint(json.dumps({{m: m in sys.modules for m in {heavy!r}}}))\n"
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


def test_the_spectrum_command_compiles_nothing_it_does_not_run(tmp_path):
    """`vibkit spectrum` needs no compiled kernel: numba stays unloaded (the signal package imports its kernels
    inside the functions that run them), and xarray is told there are no dask arrays, so dask.array (and the
    modules it brings) stays unloaded; xarray still imports dask's base to ask whether a value is a dask collection,
    and scipy.signal itself imports scipy.stats, so those two are not checked."""
    path = _csv(tmp_path)
    loaded = _loaded_after(
        f"""
        from vibkit.cli import main
        assert main(["spectrum", {str(path)!r}, "--band", "2.5:6", "--json"]) in (0, 1, 3)
        """,
        heavy=(*HEAVY, "dask.array"),
    )
    assert loaded - {"dask", "scipy.stats"} == set()


def test_a_numpy_only_command_gives_the_same_numbers_without_the_dask_probe(tmp_path):
    """The probe's answer changes nothing but the import: `vibkit spectrum --json` of the same file, with xarray
    told there are no dask arrays (the command line) and with its own probe (the library's `main` after dask is
    imported), gives the same JSON."""
    path = _csv(tmp_path)
    code = f"""
        import contextlib, io
        {{}}
        from vibkit.cli import main
        out = io.StringIO()
        with contextlib.redirect_stdout(out):
            assert main(["spectrum", {str(path)!r}, "--band", "2.5:6", "--json"]) == 0
        print(out.getvalue().replace(chr(10), " "))
        """
    env = dict(os.environ, PYTHONPATH=str(ROOT) + os.pathsep + os.environ.get("PYTHONPATH", ""))
    outs = []
    for first in ("pass", "import dask.array"):
        probe = textwrap.dedent(code.format(first))
        proc = subprocess.run([sys.executable, "-c", probe], capture_output=True, text=True, env=env, cwd=ROOT)
        assert proc.returncode == 0, proc.stderr
        outs.append(json.loads(proc.stdout.splitlines()[-1]))
    for d in outs:
        d.pop("elapsed_s", None)
    assert outs[0] == outs[1]


def test_loading_a_scene_loads_no_compiler():
    """A scene's checks (its chain closing within the tensioner's travel) need the guide's constants, not its kernels."""
    assert _loaded_after("import vibkit\nvibkit.load_scene('leon')") == set()
