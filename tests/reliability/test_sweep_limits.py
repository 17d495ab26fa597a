"""Sweeps under absurd sizes, unused keys and concurrency: checked from the plan before anything
is allocated; identical sweeps at once end with one store and no leftovers; an interrupted store opens as
what it holds."""

import math
import sys
import tracemalloc
from pathlib import Path

import numpy as np
import pytest
import xarray as xr

from vibkit.runtime.budget import BudgetError
from vibkit.sweep import SUMMARIES, SweepError, open_sweep, plan_sweep

from corpus import tiny

ROOT = Path(__file__).resolve().parents[2]
LEON = ROOT / "sim" / "leon.toml"
STORE = sys.modules["vibkit.sweep.store"]
RUN = sys.modules["vibkit.sweep.run"]
import importlib  # noqa: E402

LIMITS = importlib.import_module("vibkit.sweep.limits")


def test_a_billion_runs_are_refused_from_the_shape_within_100_MB():
    plan_sweep(LEON, {"motion.speed": "0.4,0.5"})  # imports and the scene cache out of the measurement
    for vary, samples in (
        ({"motion.speed": "0.4:0.5:1000000000"}, None),
        (
            {"motion.speed": "0.4:0.5:1000", "motion.step": "0.001:0.002:1000", "chain.link_pitch": "0.133:0.134:1000"},
            None,
        ),
        ({"motion.speed": "0.4:0.5"}, 1_000_000_000),
    ):
        tracemalloc.start()
        try:
            with pytest.raises(BudgetError, match=r"1e\+09 runs .* more than the limit of 2 GiB.*--max-result-bytes"):
                plan_sweep(LEON, vary, samples=samples)
            peak = tracemalloc.get_traced_memory()[1]
        finally:
            tracemalloc.stop()
        assert peak < 100e6, (vary, peak)


def test_the_size_is_runs_times_values_and_the_limit_is_the_budgets(monkeypatch):
    from vibkit.model.scene import load_scene

    scene = load_scene(LEON)
    est = LIMITS.estimate_sweep(scene, 1000, keep=("delta",), duration=1.0)
    samples = 1.0 / scene.section("motion")["step"] + 1
    assert est["samples"] == pytest.approx(samples)
    values = len(SUMMARIES) + 2  # the summaries, the status and the wall time of each run
    assert est["bytes"] == pytest.approx(1000 * ((values + samples) * 8 + LIMITS.BYTES_PER_RUN))
    # just under and just over a limit given in bytes, through the environment as the CLI would
    n = int(2e6 // (values * 8 + LIMITS.BYTES_PER_RUN))
    monkeypatch.setenv("VIBKIT_MAX_RESULT_BYTES", "2e6")
    assert len(plan_sweep(LEON, {"motion.speed": f"0.4:0.5:{n}"}).points) == n
    with pytest.raises(BudgetError):
        plan_sweep(LEON, {"motion.speed": f"0.4:0.5:{n + 1}"})
    assert len(plan_sweep(LEON, {"motion.speed": f"0.4:0.5:{n + 1}"}, max_result_bytes=math.inf).points) == n + 1


def test_lazy_grid_values_are_numpy_linspace_bit_for_bit():
    plan = plan_sweep(LEON, {"motion.speed": "0.4:0.6:7", "chain.link_pitch": "0.1331:0.1337:13"})
    speeds, pitches = np.linspace(0.4, 0.6, 7), np.linspace(0.1331, 0.1337, 13)
    assert list(plan.axes[0].values) == list(speeds) and list(plan.axes[1].values) == list(pitches)
    pts = list(plan.points)
    assert len(pts) == 91 and pts[13 * 3 + 5] == {"motion.speed": speeds[3], "chain.link_pitch": pitches[5]}
    np.testing.assert_array_equal(np.asarray(plan.axes[1].values), pitches)
    whole = plan_sweep(ROOT / "sim" / "thesis-forward.toml", {"sprocket.teeth": "20:28:5"})
    assert list(whole.axes[0].values) == [20, 22, 24, 26, 28]
    with pytest.raises(SweepError, match="whole numbers"):
        plan_sweep(ROOT / "sim" / "thesis-forward.toml", {"sprocket.teeth": "20:28:4"})


@pytest.mark.parametrize(
    "scene, vary, match",
    [
        ("thesis-forward", {"motion.speed": "0.45,0.55"}, "forward analysis does not read \\[motion\\]"),
        ("thesis-forward", {"run.seed": "1,2"}, "forward analysis does not use it"),
        ("leon", {"run.duration": "1,2"}, "inverse analysis does not read \\[run\\]"),
        ("leon", {"solver.rtol": "1e-6,1e-7"}, "inverse analysis does not read \\[solver\\]"),
        ("leon", {"kinematics.step": "0.001,0.002"}, "inverse analysis does not read \\[kinematics\\]"),
        ("thesis-kinematics", {"motion.speed": "0.45,0.55"}, "kinematics analysis does not read \\[motion\\]"),
        ("thesis-kinematics", {"sprocket.mass": "100,200"}, "kinematics analysis does not use it"),
        ("leon", {"motion.speed": "0_5"}, "got '0_5'"),
        ("leon", {"motion.speed": "0x1"}, "got '0x1'"),
    ],
)
def test_keys_that_change_nothing_and_loose_numbers_are_refused(scene, vary, match):
    with pytest.raises(SweepError, match=match):
        plan_sweep(ROOT / "sim" / f"{scene}.toml", vary)


def test_settle_must_leave_two_samples():
    with pytest.raises(SweepError, match="--settle 5 s leaves fewer than two samples of the 1 s runs"):
        plan_sweep(LEON, {"motion.speed": "0.4,0.5"}, settle=5.0, duration=1.0)
    step = 0.005  # leon's motion.step: settle up to duration - step leaves exactly two samples
    plan_sweep(LEON, {"motion.speed": "0.4,0.5"}, settle=1.0 - step, duration=1.0)


def _record(i):
    return {
        "index": i,
        "status": 0,
        "error": "",
        "summary": {"delta_mean": 0.033 + i},
        "kept": {},
        "wall_time": 0.1,
        "pid": 1,
    }


def test_two_processes_storing_and_consolidating_the_same_sweep(tmp_path):
    scene = tmp_path / "tiny.toml"
    scene.write_text(tiny())
    plan = plan_sweep(scene, {"chain.link_pitch": "0.1333,0.1335,0.1337"})
    out = tmp_path / "o.zarr"
    a, b = STORE._Store(out, plan, force=False), STORE._Store(out, plan, force=False)  # b opens a's store
    for i in range(3):
        a.write_run(_record(i))
        b.write_run(_record(i))  # the same run stored twice: whole, once
    assert sorted(p.name for p in (out / "runs").iterdir() if p.name.startswith("r")) == [
        "r000000",
        "r000001",
        "r000002",
    ]
    records = b.done_runs()
    ds = STORE._assemble(plan, records, complete=True)
    assert a.finish(ds) is True
    assert b.finish(ds) is False  # the other found it consolidated: writes nothing
    b.write_run(_record(1))  # a straggler's run after the consolidation: not written
    assert not (out / "runs").exists()
    assert not list(tmp_path.glob("*partial*")) and not list(out.rglob("*.tmp"))
    back = xr.open_zarr(out)
    np.testing.assert_array_equal(back["delta_mean"].values, [0.033, 1.033, 2.033])


def test_an_interrupted_store_opens_as_what_it_holds(tmp_path):
    scene = tmp_path / "tiny.toml"
    scene.write_text(tiny())
    vary = {"chain.link_pitch": "0.1333,0.1335,0.1337"}
    plan = plan_sweep(scene, vary)
    out = tmp_path / "o.zarr"
    store = STORE._Store(out, plan, force=False)
    store.write_run(_record(1))  # then killed
    ds = open_sweep(out)
    np.testing.assert_array_equal(ds["status"].values, [-1, 0, -1])
    assert ds.attrs["runs_pending"] == 2 and ds["delta_mean"].values[1] == 1.033
    assert "open_sweep" in xr.open_zarr(out).attrs["comment"]  # xarray alone says what the store is
    store.snapshot(STORE._assemble(plan, store.done_runs(), complete=False))  # a sweep stopped by max_runs
    np.testing.assert_array_equal(xr.open_zarr(out)["status"].values, [-1, 0, -1])
    with pytest.raises(SweepError, match="not a vibkit sweep store"):
        open_sweep(tmp_path)
