"""Forward dynamics against analytic truths and the study's published behaviour."""

from dataclasses import replace
from pathlib import Path

import numpy as np
import pytest

import vibkit
from vibkit.model.scene import load_scene

SIM = Path(__file__).resolve().parents[2] / "sim"
R_P = 0.4 / 3 / (2 * np.sin(np.pi / 28))
PITCH = 0.4 / 3
# motor.speed is the chain speed on the straight: the set-point turns the sprocket Z L per turn at it
W_REF = -2 * np.pi * 0.5 / (28 * PITCH)


def variant(*, effects=None, run=None, solver=None, outputs=None):
    scene = load_scene(SIM / "thesis-forward.toml")
    sections = dict(scene.sections)
    if run:
        sections["run"] = {**sections["run"], **run}
    if solver:
        sections["solver"] = {**sections["solver"], **solver}
    out = dict(scene.outputs)
    if outputs:
        out["variables"] = tuple(outputs)
    return replace(scene, sections=sections, effects=effects if effects is not None else scene.effects, outputs=out)


def peak_frequency(x, fs):
    """Dominant frequency by a zero-padded Hann spectrum and parabolic interpolation. [Hz]"""
    x = x - x.mean()
    n = 64 * x.size
    spec = np.abs(np.fft.rfft(x * np.hanning(x.size), n))
    k = int(np.argmax(spec[1:])) + 1
    a, b, c = np.log(spec[k - 1 : k + 2])
    return (k + 0.5 * (a - c) / (a - 2 * b + c)) * fs / n


@pytest.fixture(scope="module")
def startup():
    return vibkit.simulate(
        variant(outputs=["motor_torque", "sprocket_speed", "chain_speed", "closure_residual", "delta"]),
        duration=6.0,
        progress=False,
    )


def test_startup_torque_and_time_to_speed(startup):
    ds = startup
    # initial torque kp * |thetadot_ref| = 600 * 0.8415 = 504.9 N m (the study: about 500 N m, with the
    # pitch-circle set-point 0.5 / R^P = 0.8397 rad/s)
    assert abs(float(ds.motor_torque[0])) == pytest.approx(600 * abs(W_REF), rel=1e-9)
    w = ds.sprocket_speed.values
    t99 = ds.time.values[np.argmax(np.abs(w) >= 0.99 * abs(W_REF))]
    assert 3.0 <= t99 <= 5.0  # the study: 0.5 m/s in about 4 s


def test_closure_at_every_output_step(startup):
    assert float(startup.closure_residual.max()) <= 1e-9


def mean_frequency(x, fs, f0):
    """Average frequency of the component of x near f0 over the record: the unwrapped phase of
    its analytic signal (band-passed +-30 %), end minus start, over 2 pi T. [Hz]"""
    from scipy.signal import butter, hilbert, sosfiltfilt

    sos = butter(4, [0.7 * f0, 1.3 * f0], btype="band", fs=fs, output="sos")
    phase = np.unwrap(np.angle(hilbert(sosfiltfilt(sos, x - x.mean()))))
    trim = int(2 * fs)  # filter end effects
    return (phase[-trim] - phase[trim]) / (2 * np.pi * (x.size - 2 * trim) / fs)


def test_delta_follows_tooth_mesh_frequency():
    """In steady running delta's dominant frequency is Z |thetadot| / (2 pi), within 0.1 %.

    Over a window of T seconds the chain can lead or lag the sprocket by at most the tooth
    backlash (about 6.5 mm), so the two frequencies may differ by 0.0065 / (v T): 0.06 % over 20 s.
    The spectral peak of a 10 s record scatters by about as much, because the undamped chain
    surges within the backlash (frequency modulation), hence the average-phase measure."""
    ds = vibkit.simulate(
        variant(run={"initial_speed": 0.5}, outputs=["delta", "sprocket_speed"]), duration=24.0, progress=False
    )
    steady = ds.time.values >= 2.0
    mesh = 28 * abs(ds.sprocket_speed.values[steady].mean()) / (2 * np.pi)
    f = mean_frequency(ds.delta.values[steady], 1 / 0.005, mesh)
    assert f == pytest.approx(mesh, rel=1e-3)
    assert peak_frequency(ds.delta.values[steady], 1 / 0.005) == pytest.approx(mesh, rel=3e-3)
    # v / L = 3.75 Hz: the set-point is the chain speed (the study's pitch-circle set-point gave 3.742 Hz)
    assert mesh == pytest.approx(0.5 / PITCH, rel=5e-4)


# The converged no-load scene: dopri5 at rtol 1e-10 and 1e-11 here,
# independently, dopri5 1e-9 ... 1e-11, dop853 1e-8 with max_step 2e-3 and cvode-adams 1e-8: the chain
# touches the teeth in 23 episodes during spin-up, the last at t = 7.855 s, then coasts inside the
# backlash without touching a tooth up to 44 s.
CONVERGED_EPISODES = 23
CONVERGED_LAST_CONTACT_S = 7.855


def contact_episodes(ds):
    """Number of contact episodes (runs of output samples with any tooth force) and the last
    time a tooth carries force. [s]"""
    on = (np.abs(ds.contact_force.values) > 0).any(axis=1)
    n = int(on[0]) + int(np.count_nonzero(np.diff(on.astype(int)) == 1))
    return n, float(ds.time.values[np.flatnonzero(on)[-1]]) if on.any() else float("nan")


@pytest.fixture(scope="module")
def no_load():
    """The shipped no-load scene at its shipped solver settings, 44 s."""
    return vibkit.simulate(variant(outputs=["delta", "sprocket_speed", "contact_force"]), progress=False)


def test_default_settings_give_the_converged_contact_history(no_load):
    n, last = contact_episodes(no_load)
    assert n == CONVERGED_EPISODES
    assert last == pytest.approx(CONVERGED_LAST_CONTACT_S, abs=0.05)
    # after spin-up the sprocket turns steadily: ripple below 1e-3 % (converged: 2e-4 %)
    w = no_load.sprocket_speed.sel(time=slice(8.0, None)).values
    assert (w.max() - w.min()) / abs(w.mean()) < 1e-5


def test_link_pass_is_the_set_speed_over_the_pitch(no_load):
    """motor.speed is the chain speed on the straight: delta's link-pass frequency in steady running is
    motor.speed / pitch within 0.05 %, and so is the result's ``link_pass_frequency_hz``.

    From 8 s the chain coasts inside the backlash (about 6.5 mm): over the 36 s left it can lead or
    lag the sprocket by at most 0.0065 / (0.5 x 36) = 0.04 % of its mean advance."""
    steady = no_load.time.values >= 8.0
    f = mean_frequency(no_load.delta.values[steady], 1 / 0.005, 0.5 / PITCH)
    assert f == pytest.approx(0.5 / PITCH, rel=5e-4)
    # the result states the links that passed over its second half: the chain coasting in the backlash, that is
    # delta's own link pass there (measured: 5e-6), within the backlash's bound of the set speed's
    stated = no_load.attrs["link_pass_frequency_hz"]
    assert stated == pytest.approx(0.5 / PITCH, rel=5e-4)
    second = no_load.time.values >= no_load.time.values[no_load.time.size // 2]
    assert mean_frequency(no_load.delta.values[second], 1 / 0.005, stated) == pytest.approx(stated, rel=5e-5)


def test_a_drooping_drive_states_the_speed_it_ran_at():
    """A proportional speed controller droops under a steady drag (rolling resistance 0.002): the result
    states the speed its chain ran at, not the set one. delta's own link pass over the second half is the stated
    ``link_pass_frequency_hz`` (the links that passed there: the run starts from rest) within 0.05 % (the
    phase is read 2 s in from the ends), where the set speed's is 2.9 % off; the stated speed is that link pass times the pitch, and the set
    speed stays in ``speed_set_point_m_s``."""
    effects = {
        "gravity": {"g": 9.81},
        "contact": {"stiffness": 1e6, "exponent": 1.5},
        "motor": {"kp": 600.0, "speed": 0.5},
        "rolling_resistance": {"coefficient": 0.002},
    }
    ds = vibkit.simulate(variant(effects=effects, outputs=["delta"]), duration=16.0, progress=False)
    f_lp = ds.attrs["link_pass_frequency_hz"]
    assert ds.attrs["speed_set_point_m_s"] == 0.5
    assert ds.attrs["chain_speed_m_s"] == pytest.approx(f_lp * PITCH, rel=1e-12)
    t = ds.time.values
    f = mean_frequency(ds.delta.values[t >= t[t.size // 2]], 200.0, f_lp)
    assert f == pytest.approx(f_lp, rel=5e-4)
    assert abs(f / (0.5 / PITCH) - 1) > 0.02


def test_a_chain_that_coasts_is_said_to(tmp_path):
    """The study's no-load scene: once up to speed, gravity on the closed loop does no net work, nothing brakes the
    chain, and the P controller's torque falls to 0: the chain coasts and the teeth carry no load. The result says
    from when, and the contact forces are 0 from then on; with a drag (rolling resistance) the drive works and
    nothing is said."""
    out = ["motor_torque", "contact_force"]
    ds = vibkit.simulate(variant(outputs=out), duration=20.0, progress=False)
    note = ds.attrs.get("notes", "")
    assert note.startswith("the chain coasts from ") and "rolling_resistance or passengers" in note
    since = float(note.split("from ")[1].split(" s on")[0])
    assert 0.0 < since < 10.0
    after = ds.time.values >= since + 0.01
    assert float(abs(ds.motor_torque.values[after]).max()) < 1e-6
    assert float(ds.contact_force.values[after].max()) == 0.0  # no tooth loaded: what the note says
    assert float(ds.contact_force.values[~after].max()) > 0.0  # the start-up did load them
    effects = {**load_scene(SIM / "thesis-forward.toml").effects, "rolling_resistance": {"coefficient": 0.002}}
    dragged = vibkit.simulate(variant(effects=effects, outputs=out), duration=12.0, progress=False)
    assert "notes" not in dragged.attrs
    assert float(abs(dragged.motor_torque.values[-100:]).min()) > 1.0


def test_result_does_not_depend_on_run_length_or_output_step(no_load):
    """The steps never depend on the run's length nor on the output times: a 30 s run is the 44 s
    run up to its last step, and so is a run with a coarser output step. The state is the same bit
    for bit; delta and the contact forces, closed again at each output time from the previous
    output's delta, agree to the closure's rounding."""
    short = vibkit.simulate(
        variant(outputs=["delta", "sprocket_speed", "contact_force"]), duration=30.0, progress=False
    )
    common = short.time.values <= 29.9  # the last step of the short run is cut to end at 30 s
    long_ = no_load.isel(time=slice(0, common.size)).isel(time=common)
    np.testing.assert_array_equal(short.sprocket_speed.values[common], long_.sprocket_speed.values)
    np.testing.assert_allclose(short.delta.values[common], long_.delta.values, rtol=0, atol=1e-12)
    np.testing.assert_allclose(short.contact_force.values[common], long_.contact_force.values, rtol=1e-9, atol=1e-6)
    assert contact_episodes(short) == contact_episodes(no_load)
    coarse = vibkit.simulate(
        variant(run={"output_step": 0.02}, outputs=["delta", "sprocket_speed"]), duration=30.0, progress=False
    )
    keep = coarse.time.values <= 29.9
    fine = no_load.sel(time=coarse.time.values[keep])
    np.testing.assert_array_equal(coarse.sprocket_speed.values[keep], fine.sprocket_speed.values)
    np.testing.assert_allclose(coarse.delta.values[keep], fine.delta.values, rtol=0, atol=1e-12)


def test_conservative_scene_loses_less_than_10_mJ_over_44_s():
    """No motor, no damping, started at 0.5 m/s, at the shipped solver settings: kinetic +
    gravitational + contact energy stays within 0.01 J over 44 s (about 160 J of kinetic energy;
    the whole converged drift inside the backlash is worth about 0.05 J)."""
    ds = vibkit.simulate(
        variant(
            effects={"gravity": {"g": 9.81}, "contact": {"stiffness": 1e6, "exponent": 1.5, "damping": 0.0}},
            run={"initial_speed": 0.5},
            outputs=["energy"],
        ),
        progress=False,
    )
    e = (ds.kinetic_energy + ds.potential_energy + ds.contact_energy).values
    assert np.abs(e - e[0]).max() < 0.01


def test_energy_conserved_without_motor_and_damping():
    """Started at 0.5 m/s with gravity and contact only: kinetic + gravitational + contact energy is
    conserved over 44 s to the integrator tolerance, and the error shrinks with the tolerance."""
    drift = {}
    for rtol, duration in ((1e-6, 44.0), (1e-8, 44.0)):
        ds = vibkit.simulate(
            variant(
                effects={"gravity": {"g": 9.81}, "contact": {"stiffness": 1e6, "exponent": 1.5, "damping": 0.0}},
                run={"initial_speed": 0.5},
                solver={"rtol": rtol, "atol": rtol * 1e-2},
                outputs=["energy", "closure_residual"],
            ),
            duration=duration,
            progress=False,
        )
        e = (ds.kinetic_energy + ds.potential_energy + ds.contact_energy).values
        # relative to the kinetic energy: the potential energy's large constant would flatter the ratio
        drift[rtol] = np.abs(e - e[0]).max() / float(ds.kinetic_energy[0])
        assert float(ds.closure_residual.max()) <= 1e-9
    # measured over 44 s: 1.5e-5 (rtol 1e-6) and 7e-6 (1e-8) of the kinetic energy; steps end on
    # the guide's breakpoints, so no step straddles a curvature jump
    assert drift[1e-6] < 1e-4
    assert drift[1e-8] < drift[1e-6]


def _passenger_run(motor, *, alight=100.0, duration=4.0, outputs=("sprocket_speed", "motor_torque"), mass=160.0):
    effects = {
        "gravity": {"g": 9.81},
        "contact": {"stiffness": 1e6, "exponent": 1.5, "damping": 0.0},
        "motor": motor,
        # 160 kg on step 7 (rollers 19-21, on the incline from t = 0 for 10 s)
        "passengers": {"mass": [mass], "step": [7], "board": [0.0], "alight": [alight]},
    }
    return vibkit.simulate(
        variant(effects=effects, run={"initial_speed": 0.5}, outputs=list(outputs)), duration=duration, progress=False
    )


def test_p_controller_droop_equals_load_torque_over_kp():
    kp = 6000.0
    ds = _passenger_run({"kp": kp, "speed": 0.5, "ki": 0.0})
    late = ds.time.values >= 2.0
    load_torque = 160.0 * 9.81 * np.sin(np.radians(30)) * R_P  # weight along the incline at the pitch radius
    droop = float(ds.sprocket_speed.values[late].mean()) - W_REF  # thetadot_ref < 0: the drop is positive
    assert droop == pytest.approx(load_torque / kp, rel=0.03)


def test_pi_controller_removes_droop():
    ds = _passenger_run({"kp": 6000.0, "ki": 30000.0, "speed": 0.5}, duration=5.0)
    late = ds.time.values >= 3.0
    assert float(ds.sprocket_speed.values[late].mean()) == pytest.approx(W_REF, rel=1e-3)


def test_back_flanks_take_load_when_passenger_steps_off():
    """The study's chapter 7.4: with no friction the chain overruns the sprocket after the load
    leaves, and the rollers strike the back flanks (AB)."""
    ds = _passenger_run(
        {"kp": 6000.0, "speed": 0.5}, alight=2.0, duration=8.0, outputs=("flank_force", "sprocket_speed")
    )
    t = ds.time.values
    loaded = (t > 0.5) & (t < 2.0)
    assert float(ds.back_flank_force.values[loaded].max()) == 0.0
    assert float(ds.drive_flank_force.values[loaded].min()) > 0.0
    assert float(ds.back_flank_force.values[t > 2.0].max()) > 1.0


def test_same_delta_as_the_kinematics():
    """delta is fixed by the closure: the forward dynamics gives the kinematic delta of the chain
    position it reaches (roller 1's s0), to the closure tolerance."""
    from vibkit.model.escalator import EscalatorModel

    sc = variant(run={"initial_speed": 0.5}, outputs=["delta", "s0"])
    ds = vibkit.simulate(sc, duration=1.0, progress=False)
    chain = EscalatorModel(sc).chain
    for j in (0, 57, 133, 200):
        assert float(ds.delta[j]) == pytest.approx(chain.configure(float(ds.s0[j])).delta, abs=1e-12)


def test_passengers_board_and_alight_at_the_landings():
    """model.md section 7: a step boards at the lower landing and alights at the upper landing. The
    schedule is a place on the guide for the step's middle roller, not a time from another run."""
    from vibkit.model.escalator import EscalatorModel

    sc = load_scene(SIM / "thesis-passengers.toml")
    model = EscalatorModel(sc)
    opts = sc.effects["passengers"]
    by_place, board, alight = model.passenger_schedule(opts, 0.0)
    assert by_place
    lower, upper = model.place("lower_landing"), model.place("upper_landing")
    # both places are on the horizontal landings' top runs (curvature 0, at the landing heights)
    for place, _z in ((lower, 0.0), (upper, None)):
        s = model.guide.s0_to_s(place, 0.0)
        assert float(model.guide.curvature(s, 0.0)) == 0.0
    conf = model.chain.configure(0.0)
    p0 = model.guide.p0
    mid3, mid53 = (int(model.step_rollers(st)[1]) for st in opts.step)
    # step 3 is already past the boarding place at t = 0: it carries its passenger from the start
    assert board[0] <= conf.s0[mid3] < alight[0]
    assert board[0] == pytest.approx(lower) and alight[0] == pytest.approx(upper)
    # step 53 (behind roller 1) boards when its middle roller reaches the lower landing, one lap on
    assert conf.s0[mid53] < board[1]
    assert np.mod(board[1], p0) == pytest.approx(lower) and np.mod(alight[1], p0) == pytest.approx(upper)
    # the weight is on the step's three rollers exactly while its middle roller is between the places
    for s0_mid, aboard in (
        (board[0] - 1e-6, False),
        (board[0] + 1e-6, True),
        (alight[0] - 1e-6, True),
        (alight[0] + 1e-6, False),
    ):
        s0 = conf.s0.copy()
        s0[mid3] = s0_mid
        fz = np.zeros(model.n)
        model.passenger_forces(opts, 0.0, 9.81, fz, s0=s0, schedule=(by_place, board, alight))
        assert fz[model.step_rollers(3)].sum() == pytest.approx(-70.0 * 9.81 if aboard else 0.0)


def test_passenger_scene_speed_drop():
    """With the study's two passengers and kp = 6000 N m s the sprocket runs 9 % slow while both
    ride the incline: the P controller's droop is the load torque over kp (not 3 %)."""
    sc = load_scene(SIM / "thesis-passengers.toml")
    ds = vibkit.simulate(replace(sc, outputs={**sc.outputs, "variables": ("sprocket_speed",)}), progress=False)
    t = ds.time.values
    w = ds.sprocket_speed.values
    both = (t > 6.0) & (t < 12.0)
    load = (70.0 + 90.0) * 9.81 * np.sin(np.radians(30.0)) * R_P
    drop = float(np.mean(w[both]) - W_REF) / abs(W_REF)
    assert drop == pytest.approx(load / 6000.0 / abs(W_REF), rel=0.05)
    assert 0.085 < drop < 0.095


def test_contact_candidates_reach_the_tooth_tips():
    """Rollers are searched within the tip corners' radius + r_d: sqrt((R^F + h)^2 + (tip/2)^2) + r_d
    = 0.66574 m for the reference sprocket, not R^F + h + r_d = 0.66543 m."""
    from vibkit.model.effects import FP, pack_parameters
    from vibkit.model.escalator import EscalatorModel

    model = EscalatorModel(load_scene(SIM / "thesis-forward.toml"))
    fp = pack_parameters(model, {})[2]
    root = model.geometry["root_radius"]
    assert fp[FP["reach"]] == pytest.approx(np.hypot(root + 0.070, 0.020) + 0.035, rel=1e-12)
    assert fp[FP["reach"]] == pytest.approx(0.66574, abs=5e-6)


def test_t0_sample_does_not_depend_on_run_length():
    """The start s0 = 0 is a breakpoint of the guide: the right-hand side jumps there, and the t = 0
    outputs are taken on the side the motion goes (as the integrator takes them), not on whichever
    side the closure's last guess led to (las-palmas 9 s and 12 s differed by 2.57 N in
    the link tensions and 12 % in accel_step at t = 0). A run from speed and one from rest."""
    scene = load_scene(SIM / "las-palmas.toml")
    scene = replace(scene, outputs=dict(scene.outputs, variables=("accel_step", "link_tension", "delta")))
    runs = [vibkit.simulate(scene, duration=d, progress=False) for d in (0.3, 0.9)]
    for name in ("accel_step", "link_tension", "delta"):
        np.testing.assert_array_equal(runs[0][name].values[0], runs[1][name].values[0])
    # and it is the one-sided value: the same as a sample a nanometre of travel further on
    assert (
        abs(float(runs[0].accel_step[0]) - float(runs[0].accel_step[1]))
        < 0.05 * abs(float(runs[0].accel_step[1])) + 0.01
    )
    rest = variant(outputs=["accel_step", "link_tension"])
    a, b = (vibkit.simulate(rest, duration=d, progress=False) for d in (0.3, 0.9))
    np.testing.assert_array_equal(a.link_tension.values[0], b.link_tension.values[0])
    np.testing.assert_array_equal(a.accel_step.values[0], b.accel_step.values[0])


def test_flank_forces_from_positions_equal_those_of_the_full_evaluation():
    """Undamped contact: the flank forces taken from the positions alone (the outputs' light path,
    which the convergence check uses) are those of the whole right-hand side."""
    light = vibkit.simulate(variant(outputs=["flank_force", "delta"]), duration=1.5, progress=False)
    full = vibkit.simulate(variant(outputs=["flank_force", "link_tension"]), duration=1.5, progress=False)
    assert float(full.drive_flank_force.max()) > 100.0  # the teeth take the start-up's load
    for name in ("drive_flank_force", "back_flank_force"):
        np.testing.assert_allclose(light[name].values, full[name].values, rtol=1e-9, atol=1e-6)


def test_links_in_compression_are_reported_and_a_preload_removes_them():
    """Without a tensioner preload the spin-up puts links into compression (a roller chain cannot push):
    the result says so; a preload of twice the worst compression keeps every link in tension."""
    bare = vibkit.simulate(variant(outputs=["link_tension"]), duration=0.5, progress=False)
    worst = float(bare.link_tension.min())
    assert worst < -1.0
    assert "go into compression" in bare.attrs["warnings"] and "preload" in bare.attrs["warnings"]
    effects = {**variant().effects, "tensioner": {"preload": -2.0 * worst}}
    held = vibkit.simulate(variant(effects=effects, outputs=["link_tension"]), duration=0.5, progress=False)
    assert float(held.link_tension.min()) > 0.0
    assert "compression" not in held.attrs.get("warnings", "")
    # too small a preload: the advice is the scene's preload plus twice the compression left, never less than it
    # has (a stranger's scene with 3000 N was told "about 700 N or more")
    small = round(-0.2 * worst)
    effects = {**variant().effects, "tensioner": {"preload": small}}
    weak = vibkit.simulate(variant(effects=effects, outputs=["link_tension"]), duration=0.5, progress=False)
    advice = weak.attrs["warnings"]
    assert f"a larger preload ([effects.tensioner] preload, now {small} N, about " in advice
    advised = float(advice.split(f"now {small} N, about ")[1].split(" N")[0])
    assert advised >= small - 2.0 * float(weak.link_tension.min())
    effects = {**variant().effects, "tensioner": {"preload": advised}}
    mended = vibkit.simulate(variant(effects=effects, outputs=["link_tension"]), duration=0.5, progress=False)
    assert float(mended.link_tension.min()) > 0.0


def test_what_the_outputs_cannot_check_is_said(capsys):
    """A stranger's scene listed only delta, as the guide advises, and its 65 links in compression and its 3.3 %
    droop went unsaid. The result names the checks its outputs could not make; `vibkit simulate` prints them."""
    bare = vibkit.simulate(variant(outputs=["delta"]), duration=0.5, progress=False)
    assert "warnings" not in bare.attrs
    unchecked = bare.attrs["unchecked"]
    assert "links in compression: not checked (add link_tension" in unchecked
    assert "drooping speed: not checked (add sprocket_speed" in unchecked
    full = vibkit.simulate(variant(outputs=["link_tension", "sprocket_speed"]), duration=0.5, progress=False)
    assert "unchecked" not in full.attrs and "go into compression" in full.attrs["warnings"]


def test_a_stalled_motor_is_reported():
    """1,440 kg on a step against the P controller of the reference (kp = 600): the chain never gets up
    to speed; the result says so instead of running on silently (started at 0.5 m/s, the speed falls
    by about 70 % within the first seconds)."""
    ds = _passenger_run({"kp": 600.0, "speed": 0.5}, duration=3.0, mass=1440.0)
    assert "the speed droops" in ds.attrs["warnings"] and "cannot hold the speed" in ds.attrs["warnings"]
    ok = _passenger_run({"kp": 6000.0, "ki": 30000.0, "speed": 0.5}, duration=3.0)
    assert "speed" not in ok.attrs.get("warnings", "")


def test_rollers_inside_the_teeth_at_the_start_are_refused(tmp_path):
    """A 101.6 mm chain with the 133.33 mm chain's rollers and teeth starts with 12 mm of roller inside a
    tooth: refused, naming the keys to change, instead of a run reported converged."""
    from vibkit.model.escalator import EscalatorModel
    from vibkit.model.scene import SceneError

    text = (SIM / "thesis-forward.toml").read_text()
    path = tmp_path / "w.toml"
    path.write_text(
        text.replace("link_pitch = 0.13333333333333333", "link_pitch = 0.1016").replace("= 159", '= "fill"')
    )
    scene = load_scene(path)
    assert EscalatorModel(scene).initial_indentation(0.0) == pytest.approx(0.01207, abs=1e-4)
    with pytest.raises(SceneError, match=r"w.toml: .* 12.1 mm inside the sprocket's teeth .*chain.roller_radius"):
        vibkit.simulate(scene, duration=0.1, progress=False)
    assert EscalatorModel(load_scene(SIM / "thesis-forward.toml")).initial_indentation(0.0) == 0.0


def test_set_point_is_the_chain_speed_of_the_mean_link(tmp_path):
    """The motor's reference turns the sprocket Z links per turn: -2 pi v / (Z L_mean), L_mean the mean link
    length, so that a worn link (longer) does not make the chain run faster than motor.speed."""
    from vibkit.model.escalator import EscalatorModel

    model = EscalatorModel(load_scene(SIM / "thesis-forward.toml"))
    assert model.sprocket_speed(0.5) == pytest.approx(W_REF, rel=1e-15)
    text = (SIM / "thesis-forward.toml").read_text().replace("n_rollers = 159", "n_rollers = 159\nworn_link = 5")
    path = tmp_path / "worn.toml"
    path.write_text(text.replace("worn_link = 5", "worn_link = 5\nworn_link_pitch = 0.1436"))
    worn = EscalatorModel(load_scene(path))
    mean = (158 * PITCH + 0.1436) / 159
    assert worn.sprocket_speed(0.5) == pytest.approx(-2 * np.pi * 0.5 / (28 * mean), rel=1e-12)
    assert worn.link_pass_frequency(0.5) == pytest.approx(0.5 / mean, rel=1e-12)


def test_passengers_ride_a_down_escalator_by_place():
    """A down escalator's passengers board at the upper landing and alight at the lower: the scene was refused,
    "passenger 0 alights (t = lower_landing) before boarding (t = upper_landing)" (the places compared as text:
    a stranger's find). Both ride, and where the up drive pulls them up the incline (negative torque) the down
    drive holds them back (positive)."""
    import re

    from vibkit.model.scene import parse_scene

    up = load_scene(SIM / "thesis-passengers.toml")
    text = up.text.replace("speed = 0.5 }", "speed = -0.5 }")
    text = re.sub(r"board = \[[^\]]*\]", 'board = ["upper_landing", "upper_landing"]', text)
    text = re.sub(r"alight = \[[^\]]*\]", 'alight = ["lower_landing", "lower_landing"]', text)
    down = parse_scene(text, "down.toml")
    assert down.effects["passengers"].board == ("upper_landing", "upper_landing")
    torque = {}
    for name, sc in (("up", up), ("down", down)):
        ds = vibkit.simulate(
            replace(sc, outputs=dict(sc.outputs, variables=("motor_torque",))), duration=15.0, progress=False
        )
        t = ds.time.values
        torque[name] = float(ds.motor_torque.values[(t > 10.0) & (t < 15.0)].mean())
    assert torque["up"] < -100.0 and torque["down"] > 100.0, torque
