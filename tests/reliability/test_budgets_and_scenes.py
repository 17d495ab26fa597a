"""Run budgets checked before work, and the scene validation gaps found by probing."""

import math
from pathlib import Path

import numpy as np
import pytest

import vibkit
from vibkit.model.scene import SceneError, load_scene, parse_scene
from vibkit.runtime import budget

SIM = Path(__file__).resolve().parents[2] / "sim"


def _text(name, **replace):
    text = (SIM / f"{name}.toml").read_text()
    for old, new in replace.items():
        assert old in text
        text = text.replace(old, new, 1)
    return text


def test_estimate_bounds_the_real_result():
    """The estimate counts what the analyses allocate: at least the result, at most a few times it."""
    for name, duration in (("thesis-kinematics", 0.01), ("leon", 0.5), ("thesis-forward", 0.2)):
        scene = load_scene(SIM / f"{name}.toml")
        ds = vibkit.simulate(scene, duration=duration, progress=False)
        est = budget.estimate_result(scene, duration)
        n = ds.sizes.get("time", ds.sizes.get("advance"))
        assert est["samples"] == pytest.approx(n, abs=1)
        assert ds.nbytes <= est["bytes"], name
        if name != "leon":  # the inverse allocates every link tension whatever is asked (170 columns)
            assert est["bytes"] <= 6 * ds.nbytes + 64 * est["columns"], name


def test_result_limit_refuses_before_work_and_names_what_to_change(monkeypatch):
    scene = load_scene(SIM / "thesis-forward.toml")
    with pytest.raises(budget.BudgetError, match=r"run.output_step.*limit of 2 GiB"):
        vibkit.simulate(scene, duration=1e9)
    # precedence: keyword > scene key > environment > default
    monkeypatch.setenv("VIBKIT_MAX_RESULT_BYTES", "1kB")
    assert budget.max_result_bytes(scene) == 1000.0
    with pytest.raises(budget.BudgetError, match="VIBKIT_MAX_RESULT_BYTES"):
        vibkit.simulate(scene, duration=0.1)
    keyed = parse_scene(
        _text("thesis-forward", **{'method = "dopri5"': 'method = "dopri5"\nmax_result_bytes = "3GiB"'})
    )
    assert budget.max_result_bytes(keyed) == 3 * 1024**3
    assert budget.max_result_bytes(keyed, "0") == math.inf
    monkeypatch.setenv("VIBKIT_MAX_RESULT_BYTES", "lots")
    with pytest.raises(budget.BudgetError, match="VIBKIT_MAX_RESULT_BYTES"):
        budget.max_result_bytes(scene)


def test_parse_bytes():
    assert budget.parse_bytes("2e9") == 2e9
    assert budget.parse_bytes("500MB") == 5e8
    assert budget.parse_bytes("2GiB") == 2 * 1024**3
    assert budget.parse_bytes("0") == math.inf
    for bad in ("-1", "lots", "5 parsecs", "nan"):
        with pytest.raises(ValueError):
            budget.parse_bytes(bad)


def test_wall_time_default_and_precedence(monkeypatch):
    scene = load_scene(SIM / "thesis-forward.toml")
    monkeypatch.delenv("VIBKIT_MAX_WALL_TIME", raising=False)
    assert budget.max_wall_time(scene) == budget.DEFAULT_MAX_WALL_TIME == 600.0
    monkeypatch.setenv("VIBKIT_MAX_WALL_TIME", "30")
    assert budget.max_wall_time(scene) == 30.0
    keyed = parse_scene(_text("thesis-forward", **{'method = "dopri5"': 'method = "dopri5"\nmax_wall_time = 7.0'}))
    assert budget.max_wall_time(keyed) == 7.0
    assert budget.max_wall_time(keyed, 0) == math.inf


def test_wall_time_budget_stops_with_a_clear_error():
    scene = parse_scene(
        _text("thesis-forward", **{'method = "dopri5"': 'method = "dopri5"\nmax_step = 1e-5'}), "slow.toml"
    )
    from vibkit.analyses.integrate import IntegrationError

    with pytest.raises(IntegrationError, match=r"slow.toml: dopri5: wall-time budget of 0.2 s exceeded.*max_wall_time"):
        vibkit.simulate(scene, max_wall_time=0.2, progress=False)


def test_a_short_budget_on_a_machine_without_the_kernels_stops_before_compiling(monkeypatch):
    """A budget of seconds where the kernels still have to be compiled (a minute after an install) is exceeded by the
    compile alone: said before it starts, not found after it (the reliability corpus's 0.5 s case ran 389 s of
    compile on a loaded machine first)."""
    from vibkit.analyses import integrate
    from vibkit.analyses.integrate import IntegrationError

    scene = load_scene(SIM / "thesis-forward.toml")
    monkeypatch.setattr(integrate, "_cold", lambda method: True)
    with pytest.raises(
        IntegrationError, match=r"wall-time budget of 0.5 s exceeded before the first step, by compiling"
    ):
        vibkit.simulate(scene, max_wall_time=0.5, progress=False)


def test_a_kernel_index_counts_only_for_the_source_it_was_written_for(tmp_path, monkeypatch):
    """numba drops an index whose stamp (the source's modification time and size) is not the source's: such an index
    is no cache, and the compile note and the budget's check must not take it for one."""
    import os
    import pickle

    from vibkit.runtime import kernel_cache
    from vibkit.runtime.kernel_cache import kernel_cached

    monkeypatch.delenv("NUMBA_CACHE_DIR", raising=False)  # the index beside the source, as numba keeps it by default
    monkeypatch.setitem(kernel_cache._STATE, "dir", None)
    src = tmp_path / "mod.py"
    src.write_text("x = 1\n")
    cache = tmp_path / "__pycache__"
    cache.mkdir()
    st = os.stat(src)
    with open(cache / "mod.kern-3.py311.nbi", "wb") as f:
        pickle.dump("0.59.1", f)
        f.write(pickle.dumps(((st.st_mtime, st.st_size), {})))
    assert kernel_cached(str(src), "kern")
    assert not kernel_cached(str(src), "other")
    src.write_text("x = 22\n")  # edited: the index is stale
    assert not kernel_cached(str(src), "kern")


def test_tiny_max_step_refused_before_work():
    scene = parse_scene(
        _text("thesis-forward", **{'method = "dopri5"': 'method = "dopri5"\nmax_step = 1e-12'}), "s.toml"
    )
    with pytest.raises(budget.BudgetError, match=r"s.toml: 'solver.max_step' = 1e-12 s forces at least 4.4e\+13"):
        vibkit.simulate(scene)


@pytest.mark.parametrize(
    "name, replace, match",
    [
        ("thesis-passengers", {"mass = [70.0, 90.0]": "mass = [70.0, inf]"}, r"'effects.passengers.mass\[1\]'.*finite"),
        ("thesis-passengers", {"mass = [70.0, 90.0]": "mass = [70.0, true]"}, r"'effects.passengers.mass\[1\]'"),
        ("thesis-passengers", {"step = [3, 53]": "step = [3, 54]"}, r"'effects.passengers.step\[1\]'.*1..53"),
        (
            "thesis-kinematics",
            {'variables = ["delta", "s1", "closure_residual"]': 'variables = ["delta"]\nrollers = [true]'},
            r"'outputs.rollers'",
        ),
        ("thesis-forward", {'method = "dopri5"': 'method = "rk99"'}, r"'solver.method' must be one of dopri5"),
        (
            "thesis-forward",
            {"tooth_height = 0.070": "tooth_height = 10"},
            r"'sprocket.tooth_height' = 10 m is not plausible",
        ),
        ("thesis-forward", {"base_width = 0.060": "base_width = 0.2"}, r"'sprocket.base_width'"),
        (
            "thesis-forward",
            {"stiffness = 1.0e6": "stiffness = 1e20"},
            r"'effects.contact.stiffness' = 1e\+20 is outside",
        ),
        # the shipped scene sets no rtol (the default follows the contact stiffness)
        ("thesis-forward", {'method = "dopri5"': 'method = "dopri5"\nrtol = 10'}, r"'solver.rtol' = 10"),
        ("thesis-forward", {"kp = 600.0": "kp = 1e20"}, r"'effects.motor.kp'"),
        ("thesis-forward", {"gravity = true": "gravity = { g = 1e10 }"}, r"'effects.gravity.g'"),
        (
            "thesis-kinematics",
            {"start = 3.0": "start = 1e9", "stop = 3.5333333": "stop = 1000000000.5"},
            r"'kinematics.start' = 1e\+09 m is more than 100 loops",
        ),
    ],
)
def test_scene_gaps_are_load_time_errors_naming_file_and_key(name, replace, match):
    with pytest.raises(SceneError, match=match) as exc:
        parse_scene(_text(name, **replace), f"{name}-bad.toml")
    assert str(exc.value).startswith(f"{name}-bad.toml: ")


def test_the_shipped_scenes_still_load():
    for path in sorted(SIM.glob("*.toml")):
        load_scene(path)


def test_bom_accepted(tmp_path):
    p = tmp_path / "bom.toml"
    p.write_bytes(b"\xef\xbb\xbf" + (SIM / "thesis-kinematics.toml").read_bytes())
    assert load_scene(p).name == "thesis-kinematics"


def test_non_regular_scene_files_refused(tmp_path):
    import os

    fifo = tmp_path / "scene.toml"
    os.mkfifo(fifo)
    with pytest.raises(SceneError, match="not a regular file"):
        load_scene(fifo)  # would block forever if opened
    with pytest.raises(SceneError, match="is a folder"):
        load_scene(tmp_path)
    big = tmp_path / "big.toml"
    big.write_bytes(b"#" * (2 << 20))
    with pytest.raises(SceneError, match="a scene is a small TOML file"):
        load_scene(big)


def test_far_start_reduced_to_one_loop_with_full_accuracy():
    """motion.start = 1e9 m is the configuration at fmod(1e9, P): the same numbers, closure to 1e-12 m
    (unreduced, rounding at 1e9 m costs about 6e-7 m)."""
    far = parse_scene(_text("leon", **{"start = 0.0": "start = 1e9"}))
    perimeter = far.guide.perimeter
    near = parse_scene(_text("leon", **{"start = 0.0": f"start = {math.fmod(1e9, perimeter)!r}"}))
    assert far.section("motion")["start"] == pytest.approx(math.fmod(1e9, perimeter), abs=0)
    a = vibkit.simulate(far, duration=0.5, progress=False)
    b = vibkit.simulate(near, duration=0.5, progress=False)
    np.testing.assert_array_equal(a.delta.values, b.delta.values)
    assert float(a.attrs["closure_residual_max"]) < 1e-12


def test_scene_methods_match_the_integrators():
    from vibkit.analyses.integrate import METHODS
    from vibkit.model.scene import SOLVER_METHODS

    assert tuple(SOLVER_METHODS) == tuple(METHODS)
