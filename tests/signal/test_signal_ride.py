"""Ride metrics: half-cycle peak-to-peak, A95, independence of the sample rate, ride segment."""

import math

import numpy as np
import pytest

from vibkit.diagnose.ride import ride_quality
from vibkit.signal import a95, detect_ride_segment, half_cycle_peaks, peak_to_peak, peak_to_peak_values


def test_sine_gives_every_pk_pk_2a():
    fs, f0, amp = 1000.0, 4.0, 0.37
    t = np.arange(0, 10, 1 / fs)
    v = peak_to_peak_values(amp * np.sin(2 * np.pi * f0 * t + 0.3))
    # sampled peaks miss the true one by at most amp (1 - cos(pi f0 / fs))
    assert v.size == 2 * 10 * 4 - 2
    assert np.all(np.abs(v - 2 * amp) <= 2 * amp * (1 - math.cos(math.pi * f0 / fs)) + 1e-12)
    r = peak_to_peak(amp * np.sin(2 * np.pi * f0 * t + 0.3), fs)
    assert r.max == pytest.approx(2 * amp, rel=1e-4) and r.a95 == pytest.approx(2 * amp, rel=1e-4)
    assert r.rms == pytest.approx(amp / math.sqrt(2), rel=1e-3)


def test_half_cycles_by_hand():
    x = np.array([0.0, 1, 2, -1, -3, 0, 2, 1, -1, 4, -0.5])
    p, i = half_cycle_peaks(x)
    # runs: [0,1,2] (incomplete) [-1,-3,0] [2,1] [-1] [4] [-0.5] (incomplete)
    assert p.tolist() == [-3, 2, -1, 4] and i.tolist() == [4, 6, 8, 9]
    assert peak_to_peak_values(x).tolist() == [5, 3, 5]


def _blocks(amps, cycles_each, fs=800.0, f0=5.0):
    """Sine cycles, ``cycles_each`` whole cycles at each amplitude in turn."""
    n = int(round(fs / f0))
    t = np.arange(n) / fs
    one = np.sin(2 * np.pi * f0 * t + 1e-3)
    return np.concatenate([a * np.tile(one, c) for a, c in zip(amps, cycles_each)])


def test_a95_of_a_known_mixture():
    # 90 % of the cycles at amplitude 1, 10 % at 3: more than 5 % of the pk-pk values are 6 -> A95 = 6
    x = _blocks([1.0, 3.0, 1.0], [45, 10, 45])
    v = peak_to_peak_values(x)
    assert np.mean(np.isclose(v, 6.0, rtol=1e-3)) > 0.05
    assert a95(v) == pytest.approx(6.0, rel=1e-3)
    # 2 % at 3: A95 is the bulk's 2 (the block's boundary values 4 are 2 of ~200)
    x = _blocks([1.0, 3.0, 1.0], [49, 2, 49])
    assert a95(peak_to_peak_values(x)) == pytest.approx(2.0, rel=1e-3)
    assert peak_to_peak(x, 800.0).max == pytest.approx(6.0, rel=1e-3)


def test_a95_is_the_inverted_cdf_quantile():
    v = np.arange(1, 101, dtype=float)  # 95 % do not exceed 95
    assert a95(v) == 95.0
    assert a95(np.r_[v, 1000.0]) == 96.0  # 97 of 101 values <= 96 (96.0 %), 95 of 101 <= 95 (94.1 %)
    with pytest.raises(ValueError, match="empty"):
        a95([])


def test_too_few_half_cycles_is_an_error():
    with pytest.raises(ValueError, match="half-cycles"):
        peak_to_peak(np.ones(100) + 1.0, 100.0)


def test_metrics_independent_of_sample_rate():
    # a band-limited random ride (1-30 Hz), the same continuous signal sampled at four rates
    rng = np.random.default_rng(7)
    freqs = rng.uniform(1.0, 30.0, 40)
    amps = rng.uniform(0.01, 0.1, 40)
    ph = rng.uniform(0, 2 * np.pi, 40)
    out = {}
    for fs in (500.0, 1000.0, 2000.0, 4096.0):
        t = np.arange(0, 30.0, 1 / fs)
        x = (amps[:, None] * np.sin(2 * np.pi * freqs[:, None] * t + ph[:, None])).sum(0)
        out[fs] = ride_quality({"z": x, "x": x}, fs, segment=(4.0, 28.0)).axis("z")
    ref = out[4096.0]
    for _fs, r in out.items():
        for a, b in ((r.weighted, ref.weighted), (r.lowpass, ref.lowpass)):
            assert a.rms == pytest.approx(b.rms, rel=0.01)
            assert a.max == pytest.approx(b.max, rel=0.01)
            assert a.a95 == pytest.approx(b.a95, rel=0.01)


def synthetic_ride(
    fs=500.0, v=0.5, radius=1.5, incline_deg=30.0, incline_len=6.0, landing_s=5.0, noise=0.02, offset=0.003, seed=3
):
    """A step's acceleration (x along travel, z up, gravity and a sensor offset included) on a ride:
    landing, concave transition arc, incline, convex arc, landing; with the exact segment times."""
    th = math.radians(incline_deg)
    t_arc = radius * th / v
    t_inc = incline_len / v
    edges = np.cumsum([landing_s, t_arc, t_inc, t_arc, landing_s])
    t = np.arange(0, edges[-1], 1 / fs)
    phi = np.select(
        [t < edges[0], t < edges[1], t < edges[2], t < edges[3]],
        [0.0 * t, (t - edges[0]) / t_arc * th, th + 0 * t, th - (t - edges[2]) / t_arc * th],
        0.0 * t,
    )
    # centripetal acceleration v^2/R on the arcs, normal to the path (towards the centre)
    on1 = (t >= edges[0]) & (t < edges[1])
    on2 = (t >= edges[2]) & (t < edges[3])
    an = (v * v / radius) * (on1.astype(float) - on2.astype(float))
    ax = -an * np.sin(phi)
    az = an * np.cos(phi) + 9.80665
    rng = np.random.default_rng(seed)
    ax = ax + offset + noise * rng.standard_normal(t.size)
    az = az + offset + noise * rng.standard_normal(t.size)
    # vertical speed v sin(phi) is half its incline value where sin(phi) = sin(th) / 2
    frac = math.asin(math.sin(th) / 2) / th
    start = edges[0] + frac * t_arc
    end = edges[2] + (1 - frac) * t_arc
    return ax, az, start, end


def test_ride_segment_from_vertical_speed():
    fs = 500.0
    ax, az, start, end = synthetic_ride(fs)
    seg = detect_ride_segment(fs, vertical=az, along=ax)
    assert seg.method == "vertical speed"
    assert seg.start_s == pytest.approx(start, abs=0.15) and seg.end_s == pytest.approx(end, abs=0.15)
    assert seg.plateau == pytest.approx(0.5 * math.sin(math.radians(30)), rel=0.05)


def test_ride_segment_from_gravity_component_of_a_tilting_sensor():
    fs = 200.0
    t = np.arange(0, 40, 1 / fs)
    # along-guide sensor: -g sin(phi) ramps in over 3 s at 8 s and out at 30 s
    phi = math.radians(30) * np.clip(np.minimum((t - 8) / 3, (33 - t) / 3), 0, 1)
    along = -9.80665 * np.sin(phi) + 0.05 * np.random.default_rng(0).standard_normal(t.size)
    seg = detect_ride_segment(fs, along=along)
    assert seg.method == "gravity component"
    # half of g sin(30 deg) is reached where sin(phi) = 1/4: 3 s * asin(0.25)/(pi/6) after 8 s
    d = 3 * math.asin(0.25) / math.radians(30)
    assert seg.start_s == pytest.approx(8 + d, abs=0.1) and seg.end_s == pytest.approx(33 - d, abs=0.1)


def test_ride_segment_failure_is_a_clear_message():
    fs = 200.0
    flat = 9.80665 + 0.01 * np.random.default_rng(1).standard_normal(4000)
    with pytest.raises(ValueError, match="no incline found.*--segment"):
        detect_ride_segment(fs, vertical=flat, along=flat - 9.80665)
    with pytest.raises(ValueError, match="too short"):
        detect_ride_segment(fs, vertical=flat[:100])


def test_ride_quality_on_a_synthetic_ride_with_known_vibration():
    fs = 500.0
    ax, az, start, end = synthetic_ride(fs, noise=0.0)
    t = np.arange(az.size) / fs
    amp = 0.1
    az = az + amp * np.sin(2 * np.pi * 8.0 * t)  # 8 Hz step vibration, vertical
    r = ride_quality({"x": ax, "z": az}, fs)
    z = r.axis("z")
    assert z.weighting == "Wk" and r.axis("x").weighting == "Wd"
    # A95 of the weighted z: 2 A |Wk(8 Hz)|; the curvature steps at the ends of the arcs (0.17 m/s^2,
    # abrupt) ring through the weighting and add about 1 %
    from vibkit.signal import frequency_weighting_response

    assert z.weighted.a95 == pytest.approx(2 * amp * abs(frequency_weighting_response(8.0, "Wk")), rel=0.02)
    # 10 Hz channel: Butterworth magnitudes, 4th-order low-pass at 10 Hz, 2nd-order high-pass at 0.4 Hz
    g = 1 / math.sqrt(1 + (8.0 / 10.0) ** 8) / math.sqrt(1 + (0.4 / 8.0) ** 4)
    assert z.lowpass.a95 == pytest.approx(2 * amp * g, rel=0.02)
    assert r.segment.start_s == pytest.approx(start, abs=0.15)


def _peaks_by_groupby(x):
    """Reference: runs of one sign by itertools.groupby (zeros join the run before), incomplete ends dropped."""
    import itertools

    sign, cur = [], 0.0
    for v in x:
        cur = math.copysign(1.0, v) if v != 0 else cur
        sign.append(cur)
    runs, i = [], 0
    for _, g in itertools.groupby(sign):
        n = len(list(g))
        seg = np.abs(x[i : i + n])
        runs.append(i + int(np.argmax(seg)))
        i += n
    first = [r for r in runs[1:-1]]
    if sign and sign[0] == 0.0 and len(runs) > 1:  # leading zeros belong to the first signed run
        first = runs[2:-1] if len(runs) > 2 else []
    return np.asarray(first, dtype=int)


@pytest.mark.parametrize("seed", range(5))
def test_half_cycle_peaks_match_a_plain_reference(seed):
    rng = np.random.default_rng(seed)
    x = np.round(rng.standard_normal(3000) * 1.5) * rng.uniform(0.5, 2, 3000)  # many zeros and ties
    x[:3] = 0.0 if seed % 2 else x[:3]
    _, idx = half_cycle_peaks(x)
    assert np.array_equal(idx, _peaks_by_groupby(x))


def test_a_sensor_turned_over_is_not_an_incline():
    # along-travel gravity component: 30 deg up an incline moves it by g sin 30 = 4.9 m/s^2 (a ride); a sensor
    # turned over moves it by g (a wrist, a phone in a hand): more than the steepest escalator (35 deg) gives
    from vibkit.signal.ride import MAX_TILT, detect_ride_segment

    fs, t = 100.0, np.arange(0, 40, 0.01)
    inside = (t > 10) & (t < 30)
    ride = detect_ride_segment(fs, along=np.where(inside, 9.80665 * np.sin(np.radians(30.0)), 0.0))
    assert ride.method == "gravity component" and abs(ride.start_s - 10) < 0.5 and abs(ride.end_s - 30) < 0.5
    assert 9.80665 * np.sin(np.radians(35.0)) < MAX_TILT < 9.80665
    with pytest.raises(ValueError, match="turned over rather than rode an incline"):
        detect_ride_segment(fs, along=np.where(inside, 9.80665, 0.0))
