"""Every right-hand side carries every effect the scene schema declares.

The forward dynamics has four right-hand sides: the exact closure (:func:`vibkit.model.effects.evaluate`),
the pitch table (:func:`vibkit.model.pitch_table.table_evaluate`), the chain closed run by run for a
worn chain (:func:`vibkit.model.runs_rhs.runs_evaluate`, with its closed-form fast path
:func:`~vibkit.model.runs_rhs.runs_fast`) and the study's formulation in all coordinates
(:func:`vibkit.analyses.study_kernels.assemble`). For each effect of
:data:`vibkit.model.schema.EFFECT_OPTIONS`, switched on alone at a state where it acts (contact pressed,
the motor off its speed, passengers aboard, the chain moving), what it adds to roller 1's and the
sprocket's accelerations must be what it adds in the exact closure, which computes the forces on the
rollers in one routine (:func:`vibkit.model.effects.roller_forces`). An effect some right-hand side
leaves out adds nothing there and fails, naming the right-hand side and the effect.
"""

from dataclasses import replace
from pathlib import Path

import numpy as np
import pytest

from vibkit.analyses.forward import ForwardModel, _events, initial_state
from vibkit.analyses.reference import StudyFormulation
from vibkit.model import schema
from vibkit.model.effects import evaluate, left_out
from vibkit.model.escalator import EscalatorModel
from vibkit.model.pitch_table import build_table, empty_table, rhs, table_spacing
from vibkit.model.runs_rhs import FAST_CARRIES, build_runs
from vibkit.model.scene import load_scene, parse_scene
from vibkit.model.slots import INFO_DELTA, IP, PRM_IP

from support.effects import ALL_EFFECTS

SIM = Path(__file__).resolve().parents[2] / "sim"
PITCH = 0.4 / 3
WORN = f"worn_links = [[40, {PITCH + 1e-3}], [70, {PITCH + 1e-3}], [100, {PITCH + 1e-3}]]"
# the schema's effects, passengers aboard by time (the study takes no other) at the time evaluated
EFFECTS = dict(
    ALL_EFFECTS, passengers={"mass": [70.0, 90.0], "step": [3, 53], "board": [0.0, 0.0], "alight": [5.0] * 2}
)
T = 1.0  # [s]
START, SPEED, TURN = (
    3.7,
    0.45,
    -0.02,
)  # roller 1 [m], chain speed [m/s] (the motor's is 0.5), sprocket turned into the rollers [rad]


def _scene(chain=""):
    base = load_scene(SIM / "thesis-forward.toml")
    return parse_scene(base.text.replace("n_rollers = 159", "n_rollers = 159\n" + chain), base.source)


def _state(model):
    y, d0 = initial_state(model, start=START, speed=SPEED)
    y[2] += TURN
    return y, d0


def _forward(scene, effects, table):
    """Roller 1's and the sprocket's accelerations from pitch_table.rhs with the table or run-by-run
    closure of ``table`` ("table", "runs") or from the exact closure ("exact")."""
    model = EscalatorModel(replace(scene, effects=effects))
    fm = ForwardModel(model, effects)
    y, d0 = _state(model)
    fm.info[INFO_DELTA] = d0
    dy = np.empty(5)
    if table == "exact":
        assert evaluate(T, y, dy, fm.prm, fm.work.arrays, False) == 0
    else:
        if table == "runs":
            tb = build_runs(model, fm.prm, empty_table(), 0.0, d0)
        else:
            tb = build_table(model, fm.prm, _events(model, fm)[0][0], table_spacing(1e-7))
        assert rhs(T, y, dy, fm.prm, fm.work.arrays, False, tb) == 0
    return np.array([dy[1], dy[3]])


def _study(scene, effects):
    model = EscalatorModel(replace(scene, effects=effects))
    form = StudyFormulation(model, effects, coordinate_map="vibkit")
    y, _ = _state(model)
    dy = form.rhs(T, form.state_from_independent(y))
    return np.array([dy[form.n], dy[form.n + form.p + 1]])


#: right-hand side -> (the chain it runs on, accelerations from (scene, effects)), and the reference
#: each is compared with: the exact closure on the same chain
RIGHT_HAND_SIDES = {
    "pitch table": ("", lambda scene, effects: _forward(scene, effects, "table")),
    "run by run (worn chain)": (WORN, lambda scene, effects: _forward(scene, effects, "runs")),
    "study formulation": ("", _study),
}
# of what the effect adds; measured (2026-12-07): at most 6.3e-8 (table), 7.9e-11 (run by run) and 2.8e-8
# (study), each on the tensioner's few um/s^2; 2e-12 or less on the others' 0.005-95 m/s^2 or rad/s^2
RTOL = {"pitch table": 1e-6, "run by run (worn chain)": 1e-9, "study formulation": 1e-6}


def check_carries(name, options, which, right_hand_sides=RIGHT_HAND_SIDES):
    """Raise AssertionError unless right-hand side ``which`` adds what the exact closure adds with effect
    ``name`` (``options``) switched on alone."""
    chain, accelerations = right_hand_sides[which]
    scene = _scene(chain)
    exact = _forward(scene, {name: options}, "exact") - _forward(scene, {}, "exact")
    other = accelerations(scene, {name: options}) - accelerations(scene, {})
    # rounding scales with the accelerations; what the effect adds (the tensioner's a few um/s^2 on the
    # uniform chain, whose delta hardly moves with roller 1) must stand well above it
    scale = np.abs(_forward(scene, {name: options}, "exact")) + 1.0
    assert np.any(np.abs(exact) > 1e-7 * scale), f"{name} does not act at the state tested: {exact}"
    assert np.all(np.abs(other - exact) <= RTOL[which] * np.abs(exact).max() + 1e-10 * scale), (
        f"the {which} right-hand side does not carry effect {name}: it adds {other} to (roller 1, sprocket)'s "
        f"accelerations where the exact closure adds {exact}"
    )


@pytest.mark.parametrize("which", list(RIGHT_HAND_SIDES))
@pytest.mark.parametrize("name", list(schema.EFFECT_OPTIONS))
def test_every_right_hand_side_carries_every_effect(name, which):
    check_carries(name, EFFECTS[name], which)


def test_the_worn_chain_takes_the_fast_path_for_the_effects_it_carries():
    """The run-by-run cases above cover both routes: the fast path for the effects it declares, the
    exact closure's forces for the others (derived from the schema, so a new effect is among them)."""
    assert FAST_CARRIES < set(schema.EFFECT_OPTIONS)
    left = {name for name in schema.EFFECT_OPTIONS if IP[name] in left_out(FAST_CARRIES)}
    assert left == set(schema.EFFECT_OPTIONS) - FAST_CARRIES
    assert {"passengers", "rolling_resistance"} <= left


def test_a_right_hand_side_that_drops_an_effect_is_caught():
    """The check fails on a right-hand side that leaves an effect out: here the run-by-run one with the
    effect's switch cleared, as a fast path that does not know the effect would."""

    def dropping(scene, effects):
        model = EscalatorModel(replace(scene, effects=effects))
        fm = ForwardModel(model, effects)
        fm.prm[PRM_IP][IP["rolling_resistance"]] = 0
        y, d0 = _state(model)
        fm.info[INFO_DELTA] = d0
        dy = np.empty(5)
        assert rhs(T, y, dy, fm.prm, fm.work.arrays, False, build_runs(model, fm.prm, empty_table(), 0.0, d0)) == 0
        return np.array([dy[1], dy[3]])

    planted = dict(RIGHT_HAND_SIDES, **{"run by run (worn chain)": (WORN, dropping)})
    with pytest.raises(AssertionError, match="run by run .* does not carry effect rolling_resistance"):
        check_carries("rolling_resistance", EFFECTS["rolling_resistance"], "run by run (worn chain)", planted)


def test_an_effect_declared_but_carried_nowhere_is_caught(monkeypatch):
    """An effect added to the schema (its options, its switch) whose force no right-hand side writes:
    every closed form leaves it to the general path, and the check fails there."""

    monkeypatch.setitem(schema.EFFECT_OPTIONS, "planted", schema.RollingResistanceOptions)
    monkeypatch.setitem(IP, "planted", len(IP))
    assert IP["planted"] in left_out(FAST_CARRIES)  # the fast path would not take a scene with it
    with pytest.raises(AssertionError, match="does not act|does not carry effect planted"):
        check_carries("planted", {"coefficient": 0.01}, "study formulation")
