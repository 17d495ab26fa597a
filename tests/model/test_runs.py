"""The chain closed run by run against the exact closure it stands for (to rounding)."""

from dataclasses import replace
from pathlib import Path

import numpy as np
import pytest

import vibkit
from vibkit.analyses.forward import ForwardModel
from vibkit.model.effects import evaluate
from vibkit.model.escalator import EscalatorModel
from vibkit.model.pitch_table import empty_table
from vibkit.model.runs_rhs import build_runs, runs_evaluate, runs_observe
from vibkit.model.scene import load_scene, parse_scene
from vibkit.model.slots import (
    HEAD_BY_ROLLER,
    HEAD_LINK_ERROR,
    INFO_AT,
    INFO_CURVATURE,
    INFO_DELTA,
    INFO_SLOPE,
    INFO_WALKS,
    TB_HEAD,
    WS,
)

from support.effects import ALL_EFFECTS, random_state

SIM = Path(__file__).resolve().parents[2] / "sim"
PITCH = 0.4 / 3
WORN = f"worn_links = [[40, {PITCH + 1e-3}], [70, {PITCH + 1e-3}], [100, {PITCH + 1e-3}]]"


def _scene(name, chain="", effects=None):
    base = load_scene(SIM / name)
    scene = parse_scene(base.text.replace("n_rollers = 159", "n_rollers = 159\n" + chain), base.source)
    return scene if effects is None else replace(scene, effects=effects)


def _errors(scene, rng, count=300):
    """Largest differences between the run-by-run and the exact right-hand side over random states
    (roller 1 anywhere on two loops, the telescopic runs and the lower head included), with the
    largest magnitudes, and the mean number of walks the run-by-run closure took."""
    model = EscalatorModel(scene)
    fm = ForwardModel(model, scene.effects)
    d0 = model.chain.configure(0.0).delta
    tb = build_runs(model, fm.prm, empty_table(), 0.0, d0)
    assert tb[TB_HEAD][HEAD_LINK_ERROR] <= 1e-12
    p0 = model.guide.p0
    worst, scale = np.zeros(4), np.zeros(2)
    walks = 0.0
    for _ in range(count):
        y = random_state(rng, p0)
        exact, runs = np.empty(5), np.empty(5)
        delta = model.chain.configure(y[0]).delta
        fm.info[:] = 0.0
        fm.info[INFO_DELTA] = delta
        assert evaluate(0.0, y, exact, fm.prm, fm.work.arrays, False) == 0
        d_exact, c_exact = fm.info[INFO_DELTA], fm.info[INFO_SLOPE]
        # the run-by-run closure from a guess 0.1 mm off, as a step's prediction may be
        fm.info[:] = 0.0
        fm.info[INFO_DELTA] = delta + 1e-4
        assert runs_evaluate(0.0, y, runs, fm.prm, fm.work.arrays, False, tb) == 0
        walks += fm.info[INFO_WALKS]
        worst = np.maximum(
            worst,
            np.abs(
                [exact[1] - runs[1], exact[3] - runs[3], d_exact - fm.info[INFO_DELTA], c_exact - fm.info[INFO_SLOPE]]
            ),
        )
        scale = np.maximum(scale, np.abs([exact[1], exact[3]]))
    return worst, scale, walks / count, tb


@pytest.mark.parametrize(
    "name, chain, effects",
    [
        ("thesis-forward.toml", WORN, None),
        ("thesis-forward.toml", WORN, ALL_EFFECTS),
        ("thesis-forward.toml", WORN + "\nroller_mass_by_roller = [[3, 9.5], [50, 12.0], [120, 6.0]]", None),
        ("thesis-forward.toml", "elongation_percent = 3.0", None),
        ("las-palmas.toml", f"worn_links = [[5, {PITCH + 2e-3}], [6, {PITCH + 0.5e-3}]]", ALL_EFFECTS),
    ],
    ids=["three-worn-links", "every-effect", "own-masses", "elongated-3-percent", "las-palmas"],
)
def test_runs_right_hand_side_is_the_exact_one(name, chain, effects):
    scene = _scene(name, chain, effects)
    worst, scale, walks, tb = _errors(scene, np.random.default_rng(11))
    # measured: roller 1's acceleration within 1.4e-10 to 5e-10 m/s^2 of the exact closure's (it
    # reaches 80-110 m/s^2 in these contacts), the sprocket's within 2e-9 to 9e-9 rad/s^2 (of 1,400-1,900),
    # delta within 5e-14 to 9e-14 m (the closure's tolerance), its slope within 7e-14: rounding. A chain
    # with one link 0.1 mm off errs 1e5 times more (test_a_wrong_link_is_seen)
    assert worst[0] <= 1e-10 * max(scale[0], 1.0)
    assert worst[1] <= 1e-10 * max(scale[1], 1.0)
    assert worst[2] <= 3e-13
    assert worst[3] <= 1e-12
    # Newton from a guess 0.1 mm off: three walks (measured 3.0; the later ones only from the first
    # segment that moves with delta, where roller 1 is on one that does not)
    assert walks <= 3.5
    if effects is None and "mass_by_roller" not in chain:
        assert tb[TB_HEAD][HEAD_BY_ROLLER] == 0.0  # the closed-form sums were the ones compared


def test_a_wrong_link_is_seen():
    """The comparison above can fail: the run-by-run closure of a chain one link 0.1 mm longer
    than the exact closure's gives another delta and other accelerations."""
    scene = _scene("thesis-forward.toml", WORN)
    other = _scene("thesis-forward.toml", WORN.replace(f"[100, {PITCH + 1e-3}]", f"[100, {PITCH + 1.1e-3}]"))
    model, wrong = EscalatorModel(scene), EscalatorModel(other)
    fm, fm_wrong = ForwardModel(model, scene.effects), ForwardModel(wrong, scene.effects)
    y = np.array([3.0, 0.5, 1.0, -1.6, 0.0])
    exact, runs = np.empty(5), np.empty(5)
    d = model.chain.configure(y[0]).delta
    fm.info[INFO_DELTA] = d
    assert evaluate(0.0, y, exact, fm.prm, fm.work.arrays, False) == 0
    tb = build_runs(wrong, fm_wrong.prm, empty_table(), 0.0, d)
    fm_wrong.info[INFO_DELTA] = d
    assert runs_evaluate(0.0, y, runs, fm_wrong.prm, fm_wrong.work.arrays, False, tb) == 0
    assert abs(fm_wrong.info[INFO_DELTA] - fm.info[INFO_DELTA]) > 4e-5  # half the extra length
    assert abs(exact[1] - runs[1]) > 1e-5


def test_worn_chain_run_reads_like_the_exact_run():
    """A run of the three-worn-link chain: the same delta, sprocket speed and contact force as with
    the exact closure at the default tolerance."""
    scene = _scene("thesis-forward.toml", WORN)
    scene = replace(scene, outputs=dict(scene.outputs, variables=("delta", "sprocket_speed", "contact_force")))
    runs = {c: vibkit.simulate(scene.with_solver(closure=c), duration=6.0, progress=False) for c in ("table", "exact")}
    assert runs["table"].attrs["solver_closure"].startswith("runs (the links' pitches differ")
    assert runs["exact"].attrs["solver_closure"] == "exact"
    a, b = runs["table"], runs["exact"]
    # measured over 44 s: 1e-12 m, 7e-6 rad/s and 0.004 N (the contact's own sensitivity to rounding)
    assert np.max(np.abs(a.delta.values - b.delta.values)) < 1e-9
    assert np.max(np.abs(a.sprocket_speed.values - b.sprocket_speed.values)) < 1e-4
    assert np.max(np.abs(a.contact_force.values - b.contact_force.values)) < 0.1


def test_outputs_from_one_walk_are_the_exact_closures():
    """The outputs of a worn chain (delta and each tooth's contact force) from one walk and a
    first-order step equal the exact closure's at the same states, to 1e-12 m and 1e-6 N, where the
    walk's own prediction was 1e-9 m or more off (the step does the work)."""
    scene = _scene("thesis-forward.toml", WORN)
    model = EscalatorModel(scene)
    fm = ForwardModel(model, scene.effects)
    ws, info = fm.work.arrays, fm.info
    variables = ("s0", "sprocket_angle", "sprocket_speed")
    ds = vibkit.simulate(replace(scene, outputs=dict(scene.outputs, variables=variables)), duration=3.0, progress=False)
    d0 = model.chain.configure(0.0).delta
    tb = build_runs(model, fm.prm, empty_table(), 0.0, d0)
    sdot = np.gradient(ds.s0.values, ds.time.values)
    rows = zip(ds.s0.values, sdot, ds.sprocket_angle.values, ds.sprocket_speed.values)
    states = [np.array([s, v, a, w, 0.0]) for s, v, a, w in list(rows)[200:]]
    dy = np.empty(5)
    worst_delta = worst_force = off = 0.0
    one_walk = 0
    info[:] = 0.0
    info[INFO_DELTA] = model.chain.configure(states[0][0]).delta
    for y in states:
        guess = info[INFO_DELTA] + (y[0] - info[INFO_AT]) * (
            info[INFO_SLOPE] + 0.5 * info[INFO_CURVATURE] * (y[0] - info[INFO_AT])
        )
        memory = info.copy()
        walks = info[INFO_WALKS]
        assert runs_observe(0.0, y, dy, fm.prm, ws, True, tb) == 0
        one_walk += info[INFO_WALKS] - walks == 1
        delta, force = info[INFO_DELTA], ws[WS["tooth_force"]].copy()
        info[:] = memory
        assert runs_evaluate(0.0, y, dy, fm.prm, ws, True, tb) == 0
        worst_delta = max(worst_delta, abs(delta - info[INFO_DELTA]))
        worst_force = max(worst_force, float(np.max(np.abs(force - ws[WS["tooth_force"]]))))
        off = max(off, abs(guess - info[INFO_DELTA]))
    assert one_walk >= 0.9 * len(states)
    assert off >= 1e-9
    assert worst_delta <= 1e-12
    assert worst_force <= 1e-6
