"""The report's simulation is kept on disk by scene (:mod:`vibkit.diagnose.kept_simulation`): a kept run is the fresh
simulation bit for bit, anything that changes the run (the scene's text, a setting, the duration) misses, a file that
fails a check is simulated again, and a warm report loads neither the model nor its kernels."""

import dataclasses
import os
import subprocess
import sys

import numpy as np
import pytest
import xarray as xr

import vibkit
from vibkit.diagnose import fresh_simulation, kept_simulation
from vibkit.diagnose.knock import step_rollers_of
from vibkit.diagnose.ride_simulation import with_ride_outputs
from vibkit.model.escalator import EscalatorModel
from vibkit.model.scene import load_scene

ROOT = os.path.dirname(os.path.dirname(vibkit.__file__))
DURATION = 0.5


@pytest.fixture
def cache(tmp_path, monkeypatch):
    """An empty cache folder, and a list of the fresh simulations run."""
    monkeypatch.setenv("XDG_CACHE_HOME", str(tmp_path / "cache"))
    runs = []
    real = fresh_simulation.simulate_fresh

    def counting(scene, **kw):
        runs.append(scene)
        return real(scene, **kw)

    monkeypatch.setattr(fresh_simulation, "simulate_fresh", counting)
    return tmp_path / "cache", runs


def _scene():
    # the report's scene: the step's rollers added (a 3-D variable and a text coordinate kept too)
    return with_ride_outputs(load_scene(os.path.join(ROOT, "sim", "las-palmas.toml")))


def _without_wall_time(ds):
    out = ds.copy()
    out.attrs = {k: v for k, v in ds.attrs.items() if k != "solver_wall_time_s"}
    return out


def test_a_kept_run_is_the_fresh_simulation_bit_for_bit(cache):
    folder, runs = cache
    sc = _scene()
    first = kept_simulation.simulate_kept(sc, duration=DURATION)
    kept = kept_simulation.simulate_kept(sc, duration=DURATION)
    assert len(runs) == 1 and len(list((folder / "vibkit" / "simulations").glob("*.npz"))) == 1
    xr.testing.assert_identical(kept, first)  # values, coordinates, attributes, each variable's units
    assert [*kept.data_vars] == [*first.data_vars] and kept.attrs == first.attrs
    for name in first.variables:
        assert kept[name].dtype == first[name].dtype
        np.testing.assert_array_equal(kept[name].values, first[name].values, strict=True)
    # an independent run of the same scene: the same numbers exactly (only its own wall time differs)
    fresh = vibkit.simulate(sc, duration=DURATION, progress=False)
    xr.testing.assert_identical(_without_wall_time(kept), _without_wall_time(fresh))


def test_any_change_of_the_run_misses(cache):
    _, runs = cache
    sc = _scene()
    kept_simulation.simulate_kept(sc, duration=DURATION)
    edited = dataclasses.replace(sc, text=sc.text + "\n# a comment\n")
    kept_simulation.simulate_kept(edited, duration=DURATION)
    kept_simulation.simulate_kept(sc.with_solver(rtol=1e-7), duration=DURATION)
    kept_simulation.simulate_kept(sc, duration=0.25)
    assert len(runs) == 4
    keys = {kept_simulation.run_key(s, d) for s, d in [(sc, DURATION), (edited, DURATION), (sc, 0.25)]}
    assert len(keys) == 3
    kept_simulation.simulate_kept(edited, duration=DURATION)  # each of them kept
    assert len(runs) == 4


@pytest.mark.parametrize("damage", ["truncated", "edited", "others may write"])
def test_a_kept_file_that_fails_a_check_is_simulated_again(cache, damage):
    folder, runs = cache
    sc = _scene()
    first = kept_simulation.simulate_kept(sc, duration=DURATION)
    (path,) = (folder / "vibkit" / "simulations").glob("*.npz")
    data = path.read_bytes()
    if damage == "truncated":
        path.write_bytes(data[: len(data) // 2])
    elif damage == "edited":
        path.write_bytes(data[:-10] + bytes(10))
    else:
        path.chmod(0o666)
    again = kept_simulation.simulate_kept(sc, duration=DURATION)
    assert len(runs) == 2
    xr.testing.assert_identical(_without_wall_time(again), _without_wall_time(first))


def test_the_step_rollers_without_the_model_are_the_models():
    """The knock test's step roller (read for the report without building the model) is the model's."""
    for name, step in [("las-palmas", None), ("leon", None), ("las-palmas", 7)]:
        sc = load_scene(os.path.join(ROOT, "sim", f"{name}.toml"))
        if step is not None:
            sc = dataclasses.replace(sc, outputs=dict(sc.outputs, step_accelerometer=step))
        model = EscalatorModel(sc)
        roller = int(model.step_rollers(sc.outputs.get("step_accelerometer") or 1)[1])
        radius, pitch, per_step, where = step_rollers_of(scene=sc)
        assert (radius, where) == (float(model.radii[roller]), f"roller {roller + 1} of the scene")
        assert (pitch, per_step) == (sc.chain.link_pitch, sc.chain.links_per_step)


@pytest.mark.slow
def test_a_warm_report_loads_neither_the_model_nor_its_kernels(tmp_path):
    """A second report of the same recording and scene reads the kept run: no module of the model or the analyses
    is imported, and numba not at all (the spike search filters a short record with numpy).  Where numbagg is
    installed, dask imports it and it numba: not vibkit's, not checked."""
    code = (
        "import sys\nfrom vibkit.cli import main\n"
        f"assert main(['report', {os.path.join(ROOT, 'data', 'field', 'las-palmas-accelerometer.csv')!r}, "
        f"'--scene', {os.path.join(ROOT, 'sim', 'las-palmas.toml')!r}, '-o', {str(tmp_path / 'r.pdf')!r}, "
        "'--force', '--json']) == 0\n"
        "model = sorted(m for m in sys.modules if m.startswith(('vibkit.model.escalator', 'vibkit.analyses')))\n"
        "numba = 'numba' in sys.modules and 'numbagg' not in sys.modules\n"
        "print(model, 'vibkit.diagnose.fresh_simulation' in sys.modules, numba, file=sys.stderr)\n"
    )
    env = dict(os.environ, XDG_CACHE_HOME=str(tmp_path / "cache"), PYTHONPATH=ROOT)
    cold = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, env=env)
    assert cold.returncode == 0, cold.stderr
    assert "True" in cold.stderr.strip().splitlines()[-1], cold.stderr  # the first one simulates
    warm = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, env=env)
    assert warm.returncode == 0, warm.stderr
    assert warm.stderr.strip().splitlines()[-1] == "[] False False", warm.stderr
    assert warm.stdout == cold.stdout.replace(_date(cold.stdout), _date(warm.stdout))


def _date(text):
    return next(line for line in text.splitlines() if '"report_date"' in line)
