"""A roller worn flat (vibkit.model.flat_roller): its dip against the cut circle's geometry, the knock's
period and size against the rolling kinematics, where it acts, and the scene's checks."""

import math
import re
from pathlib import Path

import numpy as np
import pytest

import vibkit
from vibkit.model.flat_roller import HEADS, flat_dip, flat_motion, flat_speed_limit
from vibkit.model.guide import KAPPA, LEN0, PHI0, S0, Guide
from vibkit.model.params import reference_guide
from vibkit.model.scene import load_scene, parse_scene
from vibkit.model.schema import SceneError

SIM = Path(__file__).resolve().parents[2] / "sim"
R, D, V = 0.035, 0.005, 0.5  # roller radius, flat chord [m], chain speed [m/s]
BETA = math.asin(D / (2 * R))
GUIDE = Guide(reference_guide())
TAB, P0 = GUIDE.table, GUIDE.p0


def _support(phi, radius, chord, m=200_001):
    """The cut circle's farthest extent toward the track (direction angle 0), its flat's outward normal at
    angle ``phi`` from it, by brute force over points of its outline."""
    beta = math.asin(chord / (2 * radius))
    ang = np.linspace(beta, 2 * math.pi - beta, m)  # the round part, angles from the flat's normal
    ends = np.array([beta, -beta])
    pts = np.concatenate([np.cos(ang - phi), np.cos(ends - phi)])  # chord points: max at its ends
    return radius * pts.max()


@pytest.mark.parametrize("phi", [-0.3, -BETA, -0.05, -0.01, 0.0, 0.02, 0.06, BETA, 1.0, math.pi])
def test_dip_is_the_cut_circle_resting_on_its_track(phi):
    d, _, _ = flat_dip(np.array([phi]), R, D)
    assert d[0] == pytest.approx(R - _support(phi, R, D), abs=1e-10)


def test_dip_derivatives_and_the_impact():
    phi = np.linspace(-0.2, 0.2, 4001)
    d, d1, d2 = flat_dip(phi, R, D)
    # the derivatives are those of the dip (away from phi = 0 and the edges)
    ok = (np.abs(phi) > 1e-3) & (np.abs(np.abs(phi) - BETA) > 1e-3)
    num1 = np.gradient(d, phi)
    num2 = np.gradient(d1, phi)
    assert np.allclose(d1[ok], num1[ok], atol=1e-4 * R)
    assert np.allclose(d2[ok], num2[ok], atol=1e-3 * R)
    assert d.max() == pytest.approx(R * (1 - math.cos(BETA)), rel=1e-6)
    # the leading edge strikes: the rate reverses from +r sin(beta) to -r sin(beta)
    before, after = flat_dip(np.array([-1e-12, 1e-12]), R, D)[1]
    assert before == pytest.approx(R * math.sin(BETA), rel=1e-9)
    assert after == pytest.approx(-R * math.sin(BETA), rel=1e-9)


def _segment_run(k, v, dt, margin=0.05):
    """A roller at speed v along segment k (fixed segments only: s0 is the arc length there)."""
    start, length = TAB[k, S0], TAB[k, LEN0]
    t = np.arange(0.0, (length - 2 * margin) / v, dt)
    return t, start + margin + v * t


def _knocks(phi):
    """Indices where the flat's angle passes 0 (mod 2 pi): the impacts."""
    turns = np.floor(phi / (2 * math.pi))
    return np.flatnonzero(np.diff(turns) != 0) + 1


@pytest.mark.parametrize("k", [3, 2, 4, 9])  # incline (top run), concave and convex transitions, return incline
def test_knock_period_follows_the_track_curvature(k):
    dt = 1e-4
    t, s0 = _segment_run(k, V, dt)
    pos, vel, acc, phi = flat_motion(TAB, P0, t, s0, np.zeros(t.size), R, D)
    kap = TAB[k, KAPPA]
    # the track is below: on the left of travel on the return run (heading -x)
    heading = math.cos(TAB[k, PHI0]) if kap == 0.0 else math.cos(TAB[k, PHI0] + kap * 0.5 * TAB[k, LEN0])
    side = 1.0 if heading < 0 else -1.0
    period = 2 * math.pi / (V * (1 / R - side * kap))
    hits = t[_knocks(phi)]
    assert hits.size >= 3
    assert np.diff(hits) == pytest.approx(period, abs=2 * dt)
    # the dip points at the track (down), never more than the flat allows
    depth = np.hypot(pos[:, 0], pos[:, 1])
    assert depth.max() <= R * (1 - math.cos(BETA)) * (1 + 1e-9)
    assert depth.max() >= R * (1 - math.cos(BETA - V * dt / R))
    deep = depth > 0.5 * depth.max()
    assert np.all(pos[deep, 1] < 0)


def test_the_knock_reverses_the_velocity_by_2_v_sin_beta():
    # sampled finely, the sensor's filter (0.6 samples) is far shorter than the knock: the true motion
    dt = 1e-5
    t, s0 = _segment_run(3, V, dt)
    pos, vel, acc, phi = flat_motion(TAB, P0, t, s0, np.zeros(t.size), R, D)
    hits = _knocks(phi)
    normal = np.array([math.sin(math.radians(30.0)), -math.cos(math.radians(30.0))])  # toward the incline's track
    vn = vel @ normal
    depth = pos @ normal
    k = 5  # samples each side: 8 filter sigmas
    for j in hits[1:-1]:
        jump = vn[j + k] - vn[j - k - 1]  # across the impact; the pivot's v^2 / r acts over the 2k + 1 samples
        assert jump == pytest.approx(-2 * V * math.sin(BETA), abs=1.2 * (2 * k + 1) * dt * V**2 / R)
        assert depth[j - 2 : j + 2].max() == pytest.approx(R * (1 - math.cos(BETA)), rel=5e-3)  # the cusp, smoothed
    # position, velocity and acceleration are one motion: each the derivative of the one before (away from
    # the impacts and the pivots' ends, where the acceleration jumps by v^2 / r: the filter's 0.6 samples
    # leave them too sharp for differences of the samples)
    smooth = np.ones(t.size, bool)
    ends = round(BETA * R / V / dt)
    for j in hits:
        for c in (j - ends, j, j + ends):
            smooth[max(c - 6, 0) : c + 6] = False
    smooth[:10] = smooth[-10:] = False
    assert np.allclose(np.gradient(pos, t, axis=0)[smooth], vel[smooth], atol=1e-3 * V * math.sin(BETA))
    assert np.allclose(np.gradient(vel, t, axis=0)[smooth], acc[smooth], atol=1e-2 * V**2 / R)
    # ... and across them: the accelerations integrate to the velocity's reversal
    for j in hits[1:-1]:
        w = slice(j - 100, j + 100)
        assert np.trapezoid(acc[w] @ normal, t[w]) == pytest.approx(vn[j + 99] - vn[j - 100], rel=5e-3)


def _dip_transform(f, rate):
    """Fourier transform of one knock's dip D(rate tau) at frequency f, by direct quadrature. [m s]"""
    half = BETA / rate
    tau = np.linspace(-half, half, 20_001)
    d, _, _ = flat_dip(rate * tau, R, D)
    return float(np.trapezoid(d * np.cos(2 * math.pi * f * tau), tau))


@pytest.mark.parametrize("order", [4, 13, 26])
def test_knock_spectrum_is_the_dips_curvature(order):
    """Below the filter's cut-off the knocks' acceleration is a comb of (2 pi f)^2 DIP(f) / T per harmonic
    (DIP the dip's Fourier transform): its line at f_k = k / T has amplitude 2 (2 pi f_k)^2 |DIP(f_k)| / T,
    times the sensor filter's exp(-(2 pi f sigma)^2 / 2)."""
    dt = 1e-3
    t, s0 = _segment_run(3, V, dt)
    _, _, acc, phi = flat_motion(TAB, P0, t, s0, np.zeros(t.size), R, D)
    hits = _knocks(phi)
    a, b = hits[1] - 200, hits[-2] - 200  # whole periods between two knocks' neighbourhoods
    period = 2 * math.pi * R / V
    f = order / period
    an = acc[a:b] @ np.array([math.sin(math.radians(30.0)), -math.cos(math.radians(30.0))])
    n_periods = (t[b] - t[a]) / period
    assert abs(n_periods - round(n_periods)) < 0.01
    c = 2 * abs(np.sum(an * np.exp(-2j * math.pi * f * t[a:b]))) * dt / (t[b] - t[a])
    sigma = 0.6 * dt
    expected = (
        2
        * (2 * math.pi * f) ** 2
        * abs(_dip_transform(f, V / R))
        / period
        * math.exp(-((2 * math.pi * f * sigma) ** 2) / 2)
    )
    assert c == pytest.approx(expected, rel=0.02)


def test_no_dip_on_the_heads_and_the_flat_turns_with_the_wheel():
    for k in HEADS:
        t, s0 = _segment_run(k, V, 1e-3)
        pos, vel, acc, phi = flat_motion(TAB, P0, t, s0, np.zeros(t.size), R, D, phase=0.0)
        assert np.all(pos == 0) and np.all(vel == 0) and np.all(acc == 0)
        assert np.all(phi == 0.0)


def test_speed_limit_is_where_gravity_no_longer_holds_the_pivot():
    v = flat_speed_limit(R, math.radians(30), 1.5)
    assert v**2 / R + v**2 / 1.5 == pytest.approx(9.81 * math.cos(math.radians(30)), rel=1e-12)
    assert 0.5 < v < 0.55


# --- scenes -------------------------------------------------------------------------------------------


def _scene(name, extra, **replace):
    text = load_scene(SIM / name).text.replace("n_rollers = 159", "n_rollers = 159\n" + extra)
    for old, new in replace.items():
        text = re.sub(old, new, text)
    return parse_scene(text, "flat.toml")


@pytest.mark.parametrize(
    "extra, message",
    [
        ("roller_flat_by_roller = [[40, 0.04]]", "shorter than the roller's radius"),
        ("roller_flat_by_roller = [[160, 0.005]]", "integer 1..159"),
        ("roller_flat_by_roller = [[40, 0.005], [40, 0.004]]", "roller 40 is given twice"),
        ("roller_flat_by_roller = [40, 0.005]", "must be pairs"),
    ],
)
def test_scene_refuses_impossible_flats(extra, message):
    with pytest.raises(SceneError, match=re.escape(message)):
        _scene("thesis-forward.toml", extra)


def test_scene_refuses_a_speed_at_which_the_roller_flies():
    with pytest.raises(SceneError, match=r"would fly over its flat.*0\.539 m/s"):
        _scene("thesis-forward.toml", "roller_flat_by_roller = [[40, 0.005]]", **{r"speed = 0\.5 \}": "speed = 0.65 }"})
    with pytest.raises(SceneError, match="would fly over its flat"):
        _scene("thesis-inverse.toml", "roller_flat_by_roller = [[40, 0.005]]", **{r"speed = 0\.5 ": "speed = 0.6 "})


def test_forward_run_gives_the_flat_to_its_roller_alone():
    outs = {
        r"variables = \[[^\]]*\]": 'variables = ["delta", "chain_speed", "roller_position", "roller_velocity", "roller_acceleration"]',
        r"step_accelerometer = 20": "rollers = [40, 80]",
    }
    flat = _scene("thesis-forward.toml", "roller_flat_by_roller = [[40, 0.005]]", **outs)
    round_ = _scene("thesis-forward.toml", "", **outs)
    a = vibkit.simulate(flat, duration=6.0, progress=False)
    b = vibkit.simulate(round_, duration=6.0, progress=False)
    # first order: the chain (and every other roller) moves as with a round roller
    assert np.array_equal(a.delta.values, b.delta.values)
    for name in ("roller_position", "roller_velocity", "roller_acceleration"):
        assert np.array_equal(a[name].sel(roller=80).values, b[name].sel(roller=80).values)
    dip = np.hypot(*(a.roller_position - b.roller_position).sel(roller=40).values.T)
    # through the 3 ms filter of 5 ms outputs the 10 ms dip keeps about half its depth
    assert 0.3 * R * (1 - math.cos(BETA)) < dip.max() <= R * (1 - math.cos(BETA)) * (1 + 1e-9)
    # knocks once a turn of the roller over the track (the run starts from rest: count the last 3 s)
    late = a.time.values > 3.0
    deep = dip > 0.5 * dip.max()
    starts = np.flatnonzero(np.diff(deep.astype(int)) == 1)
    n_late = int(np.sum(late[starts]))
    travelled = float(np.trapezoid(a.chain_speed.values[late], a.time.values[late]))
    assert abs(n_late - travelled / (2 * math.pi * R)) <= 1.5


def test_a_flat_no_output_shows_is_said():
    scene = _scene("thesis-forward.toml", "roller_flat_by_roller = [[40, 0.005]]")
    ds = vibkit.simulate(scene, duration=0.5, progress=False)
    assert "roller(s) 40 worn flat, but no output shows them" in ds.attrs.get("warnings", "")
    shown = _scene(
        "thesis-forward.toml",
        "roller_flat_by_roller = [[40, 0.005]]",
        **{
            r"step_accelerometer = 20": "step_accelerometer = 20\nrollers = [40]",
            r'"accel_step"\]': '"accel_step", "roller_acceleration"]',
        },
    )
    ds = vibkit.simulate(shown, duration=0.5, progress=False)
    assert "worn flat" not in ds.attrs.get("warnings", "")
