"""The compiled kernels' named slots (vibkit.model.slots): parameters packed from a scene with every
effect on read back by name, and every name tuple consistent with its constants and its array."""

import math
from dataclasses import replace
from pathlib import Path

import numpy as np
import pytest

from vibkit.analyses.forward import ForwardModel, initial_state
from vibkit.model import slots
from vibkit.model.effects import Work, pack_parameters, reset_closure
from vibkit.model.escalator import EscalatorModel
from vibkit.model.pitch_table import empty_table
from vibkit.model.scene import load_scene
from vibkit.model.schema import EFFECT_OPTIONS
from vibkit.model.slots import (
    FP,
    FP_NAMES,
    INFO,
    INFO_NAMES,
    IP,
    IP_NAMES,
    PRM_NAMES,
    TB_NAMES,
    WS_NAMES,
)

from support.effects import every_effect

SIM = Path(__file__).resolve().parents[2] / "sim"

# every effect on, every option away from its default (so that a slot read from the wrong place shows)
AWAY_FROM_DEFAULTS = {
    "gravity": {"g": 9.80665},
    "contact": {"stiffness": 2.5e6, "exponent": 1.4, "damping": 0.3},
    "motor": {"kp": 600.0, "ki": 25.0, "speed": 0.55, "torque_limit": 1.0e5, "initial_torque": 50.0},
    "tensioner": {"stiffness": 2.0e4, "preload": 3000.0, "mass": 40.0},
    "passengers": {
        "mass": [70.0, 90.0],
        "step": [3, 53],
        "board": ["lower_landing"] * 2,
        "alight": ["upper_landing"] * 2,
    },
    "rolling_resistance": {"coefficient": 0.01},
}
EVERY = every_effect(AWAY_FROM_DEFAULTS, "tests/model/test_kernel_slots.py AWAY_FROM_DEFAULTS")
BY_TIME = dict(EVERY, passengers={"mass": [70.0], "step": [3], "board": [0.5], "alight": [5.0]})


@pytest.fixture(scope="module")
def every():
    scene = replace(load_scene(SIM / "thesis-forward.toml"), effects=EVERY)
    model = EscalatorModel(scene)
    return scene, model, pack_parameters(model, EVERY)


def test_every_float_slot_reads_the_scene(every):
    scene, model, prm = every
    fp = prm[slots.PRM_FP]
    expected = {
        "FP_P0": model.guide.p0,
        "FP_LT": scene.guide.tensioner_length,
        "FP_PITCH": scene.chain.link_pitch,
        "FP_G": 9.80665,
        "FP_STIFFNESS": 2.5e6,
        "FP_EXPONENT": 1.4,
        "FP_DAMPING": 0.3,
        "FP_KP": 600.0,
        "FP_KI": 25.0,
        "FP_SPEED_REF": -2 * math.pi * 0.55 / (scene.sprocket.teeth * scene.chain.link_pitch),
        "FP_TORQUE_LIMIT": 1.0e5,
        "FP_TENSIONER_STIFFNESS": 2.0e4,
        "FP_PRELOAD": 3000.0,
        "FP_CARRIAGE_MASS": 40.0,
        "FP_ROLLING": 0.01,
        "FP_INERTIA": scene.sprocket.inertia,
        "FP_ROLLER_RADIUS": scene.chain.roller_radius,
        "FP_CX": model.centre[0],
        "FP_CZ": model.centre[1],
        "FP_ROOT_RADIUS": model.geometry["root_radius"],
        "FP_TOOTH_PITCH": 2.0 * math.pi / scene.sprocket.teeth,
        "FP_CLOSURE_TOL": model.chain.tol,
        # the farthest tooth corner (tip corner: (tip width / 2, root radius + height)) plus r_d
        "FP_REACH": math.hypot(
            scene.sprocket.tip_width / 2, model.geometry["root_radius"] + scene.sprocket.tooth_height
        )
        + scene.chain.roller_radius,
    }
    # every slot has a name and an expectation here: a new slot must be added to this test
    assert sorted(getattr(slots, k) for k in expected) == list(range(len(FP_NAMES)))
    for name, value in expected.items():
        assert fp[getattr(slots, name)] == pytest.approx(value, rel=1e-12), name


def test_every_integer_slot_reads_the_scene(every):
    scene, model, prm = every
    ip = prm[slots.PRM_IP]
    expected = {
        "IP_N": scene.chain.n_rollers,
        "IP_TEETH": scene.sprocket.teeth,
        "IP_GRAVITY": 1,
        "IP_CONTACT": 1,
        "IP_MOTOR": 1,
        "IP_PASSENGERS": slots.PASSENGERS_BY_PLACE,
        "IP_TENSIONER": 1,
        "IP_ROLLING": 1,
        "IP_LINKS_PER_STEP": 3,
    }
    assert sorted(getattr(slots, k) for k in expected) == list(range(len(IP_NAMES)))
    for name, value in expected.items():
        assert ip[getattr(slots, name)] == value, name
    by_time = pack_parameters(model, BY_TIME)
    assert by_time[slots.PRM_IP][slots.IP_PASSENGERS] == slots.PASSENGERS_BY_TIME
    assert list(by_time[slots.PRM_PASS_BOARD]) == [0.5] and list(by_time[slots.PRM_PASS_ALIGHT]) == [5.0]
    none = pack_parameters(model, {})[slots.PRM_IP]
    for name in ("IP_GRAVITY", "IP_CONTACT", "IP_MOTOR", "IP_PASSENGERS", "IP_TENSIONER", "IP_ROLLING"):
        assert none[getattr(slots, name)] == 0, name


def test_every_parameter_entry_by_name(every):
    scene, model, prm = every
    assert len(prm) == len(PRM_NAMES)
    assert prm[slots.PRM_TABLE] is model.guide.table
    assert prm[slots.PRM_CORNERS].shape == (4, 2)
    np.testing.assert_array_equal(prm[slots.PRM_MASS], np.full(scene.chain.n_rollers, scene.chain.roller_mass))
    np.testing.assert_array_equal(prm[slots.PRM_PASS_MASS], [70.0, 90.0])
    np.testing.assert_array_equal(prm[slots.PRM_PASS_STEP], [3, 53])
    # boarding and alighting places of step 3's middle roller: one ride apart is less than a loop
    board, alight = prm[slots.PRM_PASS_BOARD], prm[slots.PRM_PASS_ALIGHT]
    assert np.all(board < alight) and np.all(alight - board < model.guide.p0)
    np.testing.assert_array_equal(prm[slots.PRM_PITCHES], np.full(scene.chain.n_rollers, scene.chain.link_pitch))


def test_an_evaluation_leaves_its_info_by_name(every):
    scene, model, _ = every
    fm = ForwardModel(model, EVERY)
    y0, d0 = initial_state(model, start=0.3)
    reset_closure(fm.info, d0)
    fm.info[slots.INFO_WALKS] = 0.0
    dy = fm.rhs(0.0, y0)
    info = fm.info
    fp = fm.prm[slots.PRM_FP]
    assert info[slots.INFO_DELTA] == pytest.approx(d0, abs=1e-9)
    assert info[slots.INFO_AT] == y0[0]
    assert info[slots.INFO_WALKS] >= 1
    # at rest: no delta rate, the motor pushes kp (thetadot_ref - 0), the sprocket accelerates by it
    assert info[slots.INFO_DELTA_DOT] == 0.0
    assert info[slots.INFO_MOTOR] == pytest.approx(600.0 * fp[slots.FP_SPEED_REF], rel=1e-12)
    assert dy[3] == pytest.approx(
        (info[slots.INFO_MOTOR] + info[slots.INFO_TORQUE_C]) / scene.sprocket.inertia, rel=1e-12
    )
    # meshed midway between teeth: no contact
    assert info[slots.INFO_ACTIVE] == 0 and info[slots.INFO_WORST] == 0.0


@pytest.mark.parametrize("names", [PRM_NAMES, FP_NAMES, IP_NAMES, WS_NAMES, INFO_NAMES, TB_NAMES, slots.HEAD_NAMES])
def test_names_are_unique(names):
    assert len(set(names)) == len(names)


@pytest.mark.parametrize(
    "prefix, names, aliases",
    [
        ("PRM_", PRM_NAMES, ()),
        ("FP_", FP_NAMES, ()),
        ("IP_", IP_NAMES, ()),
        ("INFO_", INFO_NAMES, ("INFO_MEMORY", "INFO_MEMORY_END")),
        ("TB_", TB_NAMES, ()),
        ("HEAD_", slots.HEAD_NAMES, ()),
    ],
)
def test_constants_cover_each_tuple_once(prefix, names, aliases):
    consts = {
        k: v for k, v in vars(slots).items() if k.startswith(prefix) and k != prefix + "NAMES" and k not in aliases
    }
    assert sorted(consts.values()) == list(range(len(names)))


def test_the_arrays_have_the_tuples_lengths(every):
    _, model, prm = every
    assert prm[slots.PRM_FP].size == len(FP) == len(FP_NAMES)
    assert prm[slots.PRM_IP].size == len(IP) == len(IP_NAMES)
    work = Work(model.n, model.sprocket.teeth).arrays
    assert len(work) == len(WS_NAMES)
    assert work[slots.WS_INFO].size == len(INFO) == len(INFO_NAMES)
    tb = empty_table()
    assert len(tb) == len(TB_NAMES) and tb[slots.TB_HEAD].size == len(slots.HEAD_NAMES)
    # the closure's memory is a slice of consecutive slots
    assert (slots.INFO_MEMORY, slots.INFO_MEMORY_END) == (slots.INFO_AT, slots.INFO_DH_DDELTA + 1)


def test_every_option_of_every_effect_is_away_from_its_default():
    """EVERY sets each option the schema declares for an effect (a switch or a derived key aside) to a
    value other than its default, so that a slot packed from the wrong option shows above."""
    for name, cls in EFFECT_OPTIONS.items():
        for f in cls.fields():
            if f.metadata["types"] == (bool,) or f.metadata["derived"]:
                continue
            assert f.name in EVERY[name], f"EVERY lacks effects.{name}.{f.name}"
            assert EVERY[name][f.name] != f.default, f"EVERY leaves effects.{name}.{f.name} at its default"
