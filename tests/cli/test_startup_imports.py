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


def _loaded_after(code):
    """Which of HEAVY a fresh interpreter has imported after running ``code``."""
    probe = (
        textwrap.dedent(code) + f"\nimport json, sys\nprint(json.dumps({{m: m in sys.modules for m in {HEAVY!r}}}))\n"
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
    inside the functions that run them); scipy.signal itself imports scipy.stats, so that one is not checked."""
    path = _csv(tmp_path)
    loaded = _loaded_after(
        f"""
        from vibkit.cli import main
        assert main(["spectrum", {str(path)!r}, "--band", "2.5:6", "--json"]) in (0, 1, 3)
        """
    )
    assert loaded - {"dask", "scipy.stats"} == set()


def test_loading_a_scene_loads_no_compiler():
    """A scene's checks (its chain closing within the tensioner's travel) need the guide's constants, not its kernels."""
    assert _loaded_after("import vibkit\nvibkit.load_scene('leon')") == set()
