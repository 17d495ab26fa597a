"""The simulated ride of a level moving walk: the pallet's time on the top run between the heads (no climb to
find), from its velocity; a pallet that never runs forward on the level is refused in one line."""

import math

import numpy as np
import pytest
import xarray as xr

from vibkit.diagnose.ride import ride_quality_from_simulation
from vibkit.signal.ride import NoIncline, level_run_from_velocity

V, TOP, R, FS = 0.75, 10.0, 0.5, 200.0  # speed [m/s], top run [m], head radius [m], output rate [Hz]


def _stadium(s):
    """Position and velocity direction on a level walk's loop (top run from (0, R) to (TOP, R) heading +x, the
    drive head, the return run back at -R, the tensioner head) at arc length s."""
    p = 2 * TOP + 2 * math.pi * R
    s = s % p
    if s < TOP:
        return (s, R), (1.0, 0.0)
    s -= TOP
    if s < math.pi * R:
        a = s / R  # round the drive head, clockwise from the top
        return (TOP + R * math.sin(a), R * math.cos(a)), (math.cos(a), -math.sin(a))
    s -= math.pi * R
    if s < TOP:
        return (TOP - s, -R), (-1.0, 0.0)
    a = (s - TOP) / R
    return (-R * math.sin(a), -R * math.cos(a)), (-math.cos(a), math.sin(a))


def _simulated(start, seconds, incline_deg=0.0):
    t = np.arange(int(seconds * FS)) / FS
    vel = np.array([_stadium(start + V * ti)[1] for ti in t]) * V
    vel += 1e-4 * np.sin(2 * np.pi * 5.6 * t)[:, None]  # the link pass's ripple, well under the criteria
    acc = np.gradient(vel, t, axis=0)
    ds = xr.Dataset(
        {
            "roller_velocity": (("time", "roller", "axis"), vel[:, None, :]),
            "roller_acceleration": (("time", "roller", "axis"), acc[:, None, :]),
        },
        coords={"time": t, "roller": [2], "axis": ["x", "z"]},
        attrs={
            "step_accelerometer": 1,
            "links_per_step": 3,
            "chain_speed_m_s": V,
            "speed_set_point_m_s": V,
            "incline_deg": incline_deg,
        },
    )
    return t, ds


def test_the_level_walks_ride_is_the_top_run():
    # the pallet starts 3 m before the tensioner head's end on the return run: it reaches the top run after
    # 3 m + half the head, rides 10 m of it, turns round the drive head
    p = 2 * TOP + 2 * math.pi * R
    start = p - math.pi * R - 3.0
    t, ds = _simulated(start, 30.0)
    on_top = (3.0 + math.pi * R) / V
    rq = ride_quality_from_simulation(ds, source="walk")
    # the heads' arcs within 1.1 deg of the level (vertical speed under 2 % of the forward) count: R atan(0.02) / V
    tol = R * math.atan(0.02) / V + 2 / FS
    assert rq.segment.start_s == pytest.approx(on_top, abs=tol)
    assert rq.segment.end_s == pytest.approx(on_top + TOP / V, abs=tol)
    assert "level walk" in rq.segment.note and "no climb" in rq.segment.note
    assert rq.segment.plateau == pytest.approx(V, rel=1e-3)


def test_a_walk_set_to_run_backwards_rides_its_top_run_towards_minus_x():
    vx = -V * np.ones(400)
    seg = level_run_from_velocity(vx, np.zeros(400), FS, backward=True)
    assert (seg.start_s, seg.end_s) == (0.0, 2.0)
    with pytest.raises(NoIncline, match="does not ride the walk's top run"):
        level_run_from_velocity(vx, np.zeros(400), FS)


def test_a_pallet_only_on_the_return_run_is_refused():
    p = 2 * TOP + 2 * math.pi * R
    start = TOP + math.pi * R + 0.5  # on the return run, 9.5 m of it ahead
    _, ds = _simulated(start, 10.0)
    with pytest.raises(NoIncline, match="top run"):
        ride_quality_from_simulation(ds, source="walk")
    assert p > 0
