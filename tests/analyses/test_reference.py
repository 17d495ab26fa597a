"""The study's formulation (vibkit.analyses.reference) against vibkit's independent-coordinate forward dynamics.

Three levels, from exact to stated:

1. At one instant, with the same physical state (positions and velocities of every roller, delta,
   theta, thetadot), the two formulations are the same constrained mechanics, so the KKT solve of
   the study and vibkit's reduced equation give the same roller accelerations, sprocket
   acceleration and link tensions to rounding (both coordinate maps; with and without contact).
2. Integrated over the first second of ``sim/thesis-forward.toml`` (start from rest, contact
   engagement, acceleration) in vibkit's C1 coordinate map, both converged (ours rtol 1e-10,
   the study's rtol 1e-6, atol 1e-8): agreement at integration accuracy.
3. The faithful port (the study's linear map, its RelTol = AbsTol = MaxStep = 1e-3, Baumgarte
   alpha = beta = 50 1/s): agreement within tolerances set by the study's own approximations
   (see each test), and a closure residual that is small but not zero.
"""

from dataclasses import replace
from pathlib import Path

import numpy as np
import pytest

from vibkit.analyses.forward import ForwardModel, forward_dynamics, initial_state
from vibkit.analyses.reference import STUDY_SETTINGS, StudyFormulation, run_study
from vibkit.model.escalator import EscalatorModel
from vibkit.model.scene import load_scene

SIM = Path(__file__).resolve().parents[2] / "sim"
DURATION = 1.5  # [s]: roller 1 leaves the top tensioner run (s0 = Lt) at about 1.42 s
CONVERGED = 1.0  # [s]
OUTPUTS = ["delta", "chain_speed", "sprocket_speed", "link_tension", "closure_residual", "s0"]


@pytest.fixture(scope="module")
def scene():
    return load_scene(SIM / "thesis-forward.toml")


@pytest.fixture(scope="module")
def fmodel(scene):
    return EscalatorModel(scene)


@pytest.fixture(scope="module")
def ours(fmodel):
    """vibkit's forward dynamics, converged (dopri5 at rtol 1e-10)."""
    return forward_dynamics(fmodel, duration=DURATION, progress=False, rtol=1e-10, atol=1e-12, outputs=OUTPUTS)


@pytest.fixture(scope="module")
def study_converged(scene):
    """The study's equations in vibkit's coordinate, at tolerances far tighter than the study's."""
    return run_study(scene, duration=CONVERGED, rtol=1e-6, atol=1e-8, coordinate_map="vibkit")


@pytest.fixture(scope="module")
def study_faithful(scene):
    """The faithful port: the study's coordinate and its ode15s settings."""
    return run_study(scene, duration=DURATION, **STUDY_SETTINGS)


# -- 1. one instant ------------------------------------------------------------------------------


@pytest.mark.parametrize("coordinate_map", ["study", "vibkit"])
@pytest.mark.parametrize("start, speed, dtheta", [(1.234, 0.5, 0.0), (0.05, 0.3, 0.01), (8.9, 0.5, -0.02)])
def test_same_accelerations_at_an_instant(scene, fmodel, coordinate_map, start, speed, dtheta):
    """Same state -> same roller accelerations and sprocket acceleration, to rounding.

    dtheta turns the sprocket away from the meshed angle, so that teeth press on rollers
    (thousands of N m of contact torque for -0.02 rad)."""
    fm = ForwardModel(fmodel, scene.effects)
    y, d0 = initial_state(fmodel, start=start, speed=speed)
    fm.info[0] = d0
    y[2] += dtheta
    dy = fm.rhs(0.0, y)
    conf = fmodel.chain.configure(float(y[0]))
    mo = fmodel.chain.motion(conf, float(y[1]), float(dy[1]))
    form = StudyFormulation(fmodel, scene.effects, coordinate_map=coordinate_map)
    ys = form.state_from_independent(y)
    obs = form.observe(0.0, ys)
    # the converted state is consistent: C = 0 and dC/dt = 0 to rounding
    assert obs["closure_residual"] < 1e-12
    assert obs["constraint_velocity"] < 1e-12
    np.testing.assert_allclose(obs["roller_position"], conf.position, rtol=0, atol=1e-12)
    np.testing.assert_allclose(obs["roller_velocity"], mo["velocity"], rtol=0, atol=1e-12)
    # rounding scales with the forces (gravity), not with the net acceleration, which can be small
    scale = np.abs(mo["acceleration"]).max() + 9.81
    np.testing.assert_allclose(obs["roller_acceleration"], mo["acceleration"], rtol=0, atol=1e-9 * scale)
    assert obs["sprocket_acceleration"] == pytest.approx(dy[3], rel=1e-9, abs=1e-9)
    if dtheta < 0:
        assert abs(dy[3]) > 10.0  # the contact case really has contact


@pytest.mark.parametrize("coordinate_map", ["study", "vibkit"])
def test_same_link_tensions_at_an_instant(scene, fmodel, coordinate_map):
    """Link tensions 2 lambda L from the study's KKT solve equal vibkit's multiplier recursion
    at the initial state of a run started at 0.5 m/s (gravity and centripetal terms)."""
    sections = dict(scene.sections)
    sections["run"] = {**scene.section("run"), "start": 3.7, "initial_speed": 0.5}
    sc = replace(scene, sections=sections)
    model = EscalatorModel(sc)
    ds = forward_dynamics(model, duration=0.01, progress=False, outputs=["link_tension", "delta", "chain_speed"])
    form = StudyFormulation(model, sc.effects, coordinate_map=coordinate_map)
    obs = form.observe(0.0, form.initial_state(start=3.7, speed=0.5))
    tension = ds.link_tension.values[0]
    assert tension.max() > 1000.0  # a loaded chain: the incline holds it up
    np.testing.assert_allclose(obs["link_tension"], tension, rtol=0, atol=1e-8 * np.abs(tension).max())
    assert obs["delta"] == pytest.approx(float(ds.delta[0]), abs=1e-12)  # two closure solves
    assert obs["chain_speed"] == pytest.approx(0.5, rel=1e-12)


# -- 2. converged runs, same coordinate ---------------------------------------------------------


@pytest.mark.slow
def test_converged_runs_agree(ours, study_converged):
    """Both converged, so they agree to the study run's integration accuracy (rtol 1e-6, atol 1e-8
    on 323 states, with Baumgarte); the differences measured are about 10x below each tolerance:
    delta 5e-9 m (its ripple is 27 um), chain speed 2.3e-6 m/s, sprocket speed 4e-5 rad/s (the
    sprocket rings on each tooth impact), tensions 0.11 N (of 3.5 kN), and they shrink with the
    study run's tolerance (at rtol 1e-7, atol 1e-9: 1.5e-9 m, 6e-7 m/s, 1e-5 rad/s, 0.03 N)."""
    assert study_converged.attrs["coordinate_map"] == "vibkit"
    ours = ours.sel(time=study_converged.time)
    np.testing.assert_allclose(study_converged.delta, ours.delta, rtol=0, atol=1e-7)
    np.testing.assert_allclose(study_converged.chain_speed, ours.chain_speed, rtol=0, atol=2e-5)
    np.testing.assert_allclose(study_converged.sprocket_speed, ours.sprocket_speed, rtol=0, atol=4e-4)
    np.testing.assert_allclose(study_converged.link_tension, ours.link_tension, rtol=0, atol=1.0)
    assert float(study_converged.closure_residual.max()) < 1e-6


def test_the_run_is_not_trivial(ours):
    """The compared runs hold contact engagement and acceleration to 0.44 m/s."""
    assert float(ours.chain_speed[-1]) > 0.3
    assert float(np.abs(ours.link_tension).max()) > 3000.0
    assert float(ours.delta.max() - ours.delta.min()) > 1e-5


# -- 3. the faithful port ----------------------------------------------------------------------


@pytest.mark.slow
def test_faithful_port_agrees_within_stated_tolerances(fmodel, ours, study_faithful):
    """The study's settings (RelTol = AbsTol = MaxStep = 1e-3) and its linear coordinate map.

    Tolerances, each about 10x the difference measured, and what sets it:
    - chain speed 1e-3 m/s (until roller 1 reaches the end of its telescopic run, see the next
      test) and sprocket speed 1e-2 rad/s: the loose tolerances (the same runs in vibkit's map
      differ by 8e-5 m/s and 1.3e-3 rad/s), plus ~1e-4 m/s from the speed jumps of other rollers;
    - delta 2e-6 m (7 % of its 27 um ripple): the link-length error Baumgarte leaves (~0.2 mm on
      a few links, for a few 20 ms time constants after each joint crossing) moves the closure;
    - link tensions 100 N (3 % of 3.5 kN): the Baumgarte forces that pull each crossing roller
      back onto its links (~26 N measured at alpha = beta = 50 1/s).
    """
    s = study_faithful
    assert s.attrs["coordinate_map"] == "study"
    assert s.attrs["solver_method"] == "BDF" and s.attrs["solver_rtol"] == 1e-3
    before = ours.s0.values < fmodel.guide.params.tensioner_length
    np.testing.assert_allclose(s.chain_speed[before], ours.chain_speed[before], rtol=0, atol=1e-3)
    np.testing.assert_allclose(s.sprocket_speed, ours.sprocket_speed, rtol=0, atol=1e-2)
    np.testing.assert_allclose(s.delta, ours.delta, rtol=0, atol=2e-6)
    np.testing.assert_allclose(s.link_tension, ours.link_tension, rtol=0, atol=100.0)


@pytest.mark.slow
def test_speed_jump_of_the_study_coordinate(fmodel, ours, study_faithful):
    """Where roller 1 leaves the telescopic run (s0 = Lt) the study's map changes dr/ds0 from
    sigma = (Lt - delta)/Lt to 1 while s0dot stays continuous, so roller 1's speed jumps by
    v delta / (Lt - delta) (about 0.04 m/s at 0.45 m/s) and Baumgarte pulls it back within a few
    1/alpha = 20 ms. vibkit's chain speed is smooth there. At the first 5 ms sample after the
    crossing at least 30 % of the jump is left (a critically damped decay over <= 5 ms keeps
    e^-0.25 (1 + 0.25) = 97 % of it, less the part the constraint absorbs at once); the
    transient, with its undershoot, stays below the full jump."""
    lt = fmodel.guide.params.tensioner_length
    s0 = ours.s0.values
    j = int(np.argmax(s0 >= lt))
    assert 0 < j < s0.size - 10, "roller 1 must leave the telescopic run inside the run"
    diff = study_faithful.chain_speed.values - ours.chain_speed.values
    v = float(ours.chain_speed[j])
    delta = float(ours.delta[j])
    jump = v * delta / (lt - delta)
    assert 0.3 * jump < diff[j] < jump
    assert np.abs(diff[j:]).max() < jump
    # vibkit's roller-1 speed is continuous there: no step larger than the neighbouring ones
    steps = np.abs(np.diff(ours.chain_speed.values[j - 5 : j + 5]))
    assert steps.max() < 3.0 * np.median(steps) + 1e-4


@pytest.mark.slow
def test_baumgarte_keeps_closure_small_but_not_exact(ours, study_faithful):
    """Baumgarte holds the study's links to a fraction of a millimetre (the study's own fsolve
    tolerance was 1e-4), never to rounding; vibkit's walked closure holds to ~1e-13 m."""
    resid = study_faithful.closure_residual.values
    assert resid[0] < 1e-12  # a closed start
    assert 1e-6 < resid.max() < 1e-3
    assert float(ours.closure_residual.max()) < 1e-11


@pytest.mark.slow
def test_result_layout(study_faithful, ours):
    ds = study_faithful
    for name in ds.data_vars:
        assert ds[name].attrs["units"] and ds[name].attrs["long_name"], name
    for name in ("delta", "chain_speed", "sprocket_speed", "link_tension", "closure_residual"):
        assert ds[name].attrs["units"] == ours[name].attrs["units"]
        assert ds[name].dims == ours[name].dims
    np.testing.assert_array_equal(ds.time, ours.time)
    assert ds.sizes["link"] == 159
    assert ds.attrs["baumgarte_alpha_per_s"] == 50.0
    assert ds.attrs["solver_evaluations"] > 0


# -- bad input -----------------------------------------------------------------------------------


def test_rejects_bad_input(scene, fmodel):
    with pytest.raises(ValueError, match="duration"):
        run_study(scene, duration=0.0)
    with pytest.raises(ValueError, match="rtol"):
        run_study(scene, duration=0.1, rtol=-1.0)
    with pytest.raises(ValueError, match="method"):
        run_study(scene, duration=0.1, method="ode15s")
    with pytest.raises(ValueError, match="forward"):
        run_study(SIM / "thesis-inverse.toml", duration=0.1)
    with pytest.raises(ValueError, match="alpha"):
        StudyFormulation(fmodel, scene.effects, alpha=-1.0)
    with pytest.raises(ValueError, match="coordinate_map"):
        StudyFormulation(fmodel, scene.effects, coordinate_map="linear")
    form = StudyFormulation(fmodel, scene.effects)
    with pytest.raises(ValueError, match="shape"):
        form.rhs(0.0, np.zeros(5))
