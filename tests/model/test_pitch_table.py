"""The chain tabulated over one pitch against the exact closure it stands for."""

from dataclasses import replace
from pathlib import Path

import numpy as np
import pytest

import vibkit
from vibkit.analyses.convergence import compare, summary
from vibkit.analyses.forward import ForwardModel, _events
from vibkit.model.effects import evaluate
from vibkit.model.escalator import EscalatorModel
from vibkit.model.pitch_table import _quintic, build_table, table_applies, table_evaluate, table_spacing
from vibkit.model.scene import load_scene

from support.effects import ALL_EFFECTS, random_state

SIM = Path(__file__).resolve().parents[2] / "sim"


def test_quintic_interpolates_a_quintic_exactly():
    # values, slopes and curvatures of p(u) = 1 - 2u + 3u^2 - u^3 + 0.5u^4 - 0.7u^5 at u = 0.3 and 0.8
    c = np.array([1.0, -2.0, 3.0, -1.0, 0.5, -0.7])
    p = np.polynomial.Polynomial(c)
    u0, u1 = 0.3, 0.8
    q = _quintic(p(u0), p.deriv()(u0), p.deriv(2)(u0), p(u1), p.deriv()(u1), p.deriv(2)(u1), u1 - u0)
    x = np.linspace(0.0, 1.0, 11)
    assert np.polynomial.polynomial.polyval(x, q) == pytest.approx(p(u0 + x * (u1 - u0)), abs=1e-14)


def _model(name, effects=None):
    scene = load_scene(SIM / name)
    if effects is not None:
        scene = replace(scene, effects=effects)
    model = EscalatorModel(scene)
    fm = ForwardModel(model, scene.effects)
    return model, fm, _events(model, fm)[0][0]


def _errors(model, fm, tb, rng, count=400):
    """Largest differences between the table's and the exact right-hand side over random states."""
    p0 = model.guide.p0
    worst = np.zeros(4)
    scale = np.zeros(2)
    for _ in range(count):
        y = random_state(rng, p0)
        exact, fast = np.empty(5), np.empty(5)
        fm.info[:] = 0.0
        fm.info[0] = model.chain.configure(y[0]).delta
        assert evaluate(0.0, y, exact, fm.prm, fm.work.arrays, False) == 0
        d_exact, e_exact = fm.info[0], fm.info[5]
        assert table_evaluate(0.0, y, fast, fm.prm, fm.work.arrays, False, tb) == 0
        worst = np.maximum(
            worst, np.abs([exact[1] - fast[1], exact[3] - fast[3], d_exact - fm.info[0], e_exact - fm.info[5]])
        )
        scale = np.maximum(scale, np.abs([exact[1], exact[3]]))
    return worst, scale


BY_TIME = dict(ALL_EFFECTS, passengers={"mass": [70.0], "step": [3], "board": [0.0], "alight": [5.0]})


@pytest.mark.parametrize(
    "name, effects",
    [
        ("thesis-forward.toml", None),
        ("las-palmas.toml", None),
        ("thesis-passengers.toml", None),
        ("thesis-forward.toml", ALL_EFFECTS),
        ("thesis-forward.toml", BY_TIME),
    ],
    ids=["no-load", "las-palmas", "passengers", "every-effect", "passengers-by-time"],
)
def test_table_right_hand_side_is_the_exact_one(name, effects):
    model, fm, cross = _model(name, effects)
    assert table_applies(model) is None
    tb = build_table(model, fm.prm, cross, table_spacing(1e-7))
    # the tabulated chain keeps its links' length as the exact walk does (1e-13 m)
    assert tb[0][4] <= 5e-13
    worst, scale = _errors(model, fm, tb, np.random.default_rng(7))
    # measured at the default spacing (2 mm): 5.5e-7 m/s^2 on roller 1's acceleration (which reaches
    # 80-120 m/s^2 in these hard contacts), 6e-8 rad/s^2 on the sprocket's, 6e-14 m on delta and
    # 2e-8 J on the contact energy; an 8 mm table errs 50-1000 times more and fails every bound
    assert worst[0] <= 3e-6
    assert worst[1] <= 3e-7
    assert worst[2] <= 3e-13
    assert worst[3] <= 1e-7


def test_finer_table_errs_less():
    """The error falls at least as h^3 with the node spacing (quintics, h^4 in the accelerations)."""
    model, fm, cross = _model("thesis-forward.toml", dict(ALL_EFFECTS, contact={"stiffness": 1.0e6}))
    fm.prm[3][3] = 0  # no contact: the chain's own terms alone
    errs = []
    for h in (8e-3, 4e-3, 2e-3):
        worst, _ = _errors(model, fm, build_table(model, fm.prm, cross, h), np.random.default_rng(3), count=300)
        errs.append(worst[0])
    assert errs[1] <= errs[0] / 8 and errs[2] <= errs[1] / 8


def test_worn_link_is_closed_run_by_run(tmp_path):
    text = (
        (SIM / "thesis-forward.toml")
        .read_text()
        .replace("n_rollers = 159", "n_rollers = 159\nworn_link = 5\nworn_link_pitch = 0.1336")
    )
    path = tmp_path / "worn.toml"
    path.write_text(text)
    worn = load_scene(path)
    assert "pitches differ" in table_applies(EscalatorModel(worn))
    ds = vibkit.simulate(worn, duration=0.2, progress=False)
    assert ds.attrs["solver_closure"].startswith("runs (the links' pitches differ")


@pytest.mark.parametrize("name", ["thesis-forward.toml", "las-palmas.toml"])
def test_table_run_reads_like_the_exact_run(name):
    """What a user reads from a whole run (contact episodes, last contact, ripples, frequencies) is
    the same with the table as with the exact closure, at the default tolerance."""
    scene = load_scene(SIM / name)
    scene = replace(scene, outputs=dict(scene.outputs, variables=("delta", "sprocket_speed", "flank_force")))
    # from rest, so that the chain meets the teeth (started at its running speed, the Las Palmas chain
    # coasts with the sprocket and touches none: nothing to compare)
    scene = replace(scene, sections=dict(scene.sections, run=dict(scene.sections["run"], initial_speed=0.0)))
    runs = {}
    for closure in ("table", "exact"):
        sc = replace(scene, sections=dict(scene.sections, solver=dict(scene.sections["solver"], closure=closure)))
        runs[closure] = vibkit.simulate(sc, progress=False)
    assert runs["table"].attrs["solver_closure"] == "table"
    assert runs["exact"].attrs["solver_closure"] == "exact"
    duration = float(runs["exact"].time[-1])
    s_table, s_exact = summary(runs["table"]), summary(runs["exact"])
    assert compare(s_table, s_exact, 1e-7, 0.005, duration) == {}
    assert s_table["contact_episodes"] == s_exact["contact_episodes"] > 0
    # and the histories themselves: delta within a micrometre, the sprocket speed within 1e-4 rad/s
    assert np.max(np.abs(runs["table"].delta.values - runs["exact"].delta.values)) < 1e-6
    assert np.max(np.abs(runs["table"].sprocket_speed.values - runs["exact"].sprocket_speed.values)) < 1e-4


BY_ROLLER = (
    "roller_radius_by_roller = [[12, 0.033], [90, 0.034]]\nroller_mass_by_roller = [[3, 9.5], [50, 12.0], [120, 6.0]]"
)


def _by_roller_scene(effects=None):
    from vibkit.model.scene import parse_scene

    base = load_scene(SIM / "thesis-forward.toml")
    scene = parse_scene(base.text.replace("n_rollers = 159", "n_rollers = 159\n" + BY_ROLLER), base.source)
    return scene if effects is None else replace(scene, effects=effects)


@pytest.mark.parametrize("effects", [None, ALL_EFFECTS], ids=["no-load", "every-effect"])
def test_rollers_of_their_own_mass_and_radius_keep_the_table(effects):
    """Rollers of different masses and radii leave the configuration repeating after one pitch: the
    table applies, and its right-hand side (each roller's own mass in the generalised mass and in
    gravity's force, its own radius in the contact) is the exact closure's, to the bounds of the
    uniform chain."""
    scene = _by_roller_scene(effects)
    model = EscalatorModel(scene)
    assert len(set(model.mass)) == 4 and len(set(model.radii)) == 3
    assert table_applies(model) is None
    fm = ForwardModel(model, scene.effects)
    tb = build_table(model, fm.prm, _events(model, fm)[0][0], table_spacing(1e-7))
    worst, _ = _errors(model, fm, tb, np.random.default_rng(11))
    assert worst[0] <= 3e-6
    assert worst[1] <= 3e-7
    assert worst[2] <= 3e-13
    assert worst[3] <= 1e-7
    # and not by accident: the same table read with every roller of the first one's mass errs far more
    prm = list(fm.prm)
    prm[4] = np.full_like(fm.prm[4], fm.prm[4][0])
    uniform = ForwardModel.__new__(ForwardModel)
    uniform.model, uniform.effects, uniform.prm, uniform.work = model, fm.effects, tuple(prm), fm.work
    wrong = np.empty(5)
    y = np.array([0.3, 0.4, 0.0, -0.5, 0.0])
    exact = np.empty(5)
    fm.info[:] = 0.0
    fm.info[0] = model.chain.configure(y[0]).delta
    evaluate(0.0, y, exact, fm.prm, fm.work.arrays, False)
    table_evaluate(0.0, y, wrong, uniform.prm, fm.work.arrays, False, tb)
    assert abs(wrong[1] - exact[1]) > 1e3 * worst[0]


def test_rollers_of_their_own_mass_run_like_the_exact_closure():
    """A whole run with rollers of their own mass and radius: the table's history is the exact
    closure's (delta within a micrometre, the sprocket speed within 1e-3 rad/s, 8 s from rest)."""
    scene = _by_roller_scene()
    scene = replace(scene, outputs=dict(scene.outputs, variables=("delta", "sprocket_speed", "flank_force")))
    runs = {c: vibkit.simulate(scene.with_solver(closure=c), duration=8.0, progress=False) for c in ("table", "exact")}
    assert runs["table"].attrs["solver_closure"] == "table"
    assert np.max(np.abs(runs["table"].delta.values - runs["exact"].delta.values)) < 1e-6
    assert np.max(np.abs(runs["table"].sprocket_speed.values - runs["exact"].sprocket_speed.values)) < 1e-3
