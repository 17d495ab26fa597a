"""Link-pitch estimation against recordings of known pitch (synthetic and the shipped field cases)."""

import numpy as np
import pytest

from vibkit.diagnose.pitch import elongation_verdict, estimate_pitch
from vibkit.signal import crb_harmonic

from support.chain import family as _family
from support.recording import recording


def _rec(t, x, seg=None, units="m/s^2"):
    return recording(
        {"acc": x}, t=t, units=units, var_attrs={"long_name": "acc", "quantity": "acceleration"}, segment=seg
    )


@pytest.mark.parametrize("pitch", [0.1016, 0.13333, 0.13546, 0.1384])
def test_known_pitch_recovered_within_sigma(pitch):
    rng = np.random.default_rng(1)
    v, fs = 0.5, 500.0
    t = np.arange(int(20 * fs)) / fs
    x = _family(t, v / pitch, [1.0, 0.5, 0.2]) + 0.2 * rng.standard_normal(t.size)
    est = estimate_pitch(_rec(t, x), speed=v)
    assert abs(est.pitch_m - pitch) < 4 * est.pitch_sigma_m + 1e-9
    assert est.pitch_sigma_m < 1e-4 * pitch  # sub-bin: bin width alone would be 0.05 Hz / 3.7 Hz = 1.3 %
    assert est.hypotheses[0].chosen and est.hypotheses[0].name == "f is the link pass"


def test_speed_sigma_propagates_and_warns():
    t = np.arange(8000) / 400.0
    x = _family(t, 3.75, [1.0, 0.3]) + 0.05 * np.random.default_rng(2).standard_normal(t.size)
    est = estimate_pitch(_rec(t, x), speed=0.5, speed_sigma=0.005)  # 1 % speed
    rel = est.pitch_sigma_m / est.pitch_m
    assert rel == pytest.approx(np.hypot(0.01, est.fundamental_sigma_hz / est.fundamental_hz), rel=1e-9)
    assert any("speed's uncertainty" in w for w in est.warnings)
    assert any("by construction" in n for n in est.notes)
    # a speed measured well enough for the verdict is not suspected of being the motor's
    est = estimate_pitch(_rec(t, x), speed=0.5, speed_sigma=0.0005)  # 0.1 %
    assert not any("speed's uncertainty" in w for w in est.warnings)
    assert not any("by construction" in n for n in est.notes)
    assert any("by construction" in n for n in estimate_pitch(_rec(t, x), speed=0.5).notes)  # not stated


def test_dominant_second_harmonic_no_octave_error():
    t = np.arange(10000) / 500.0
    x = _family(t, 3.75, [0.2, 1.0, 0.15]) + 0.02 * np.random.default_rng(3).standard_normal(t.size)
    est = estimate_pitch(_rec(t, x), speed=0.5, band=(2.0, 8.0))
    assert est.fundamental_hz == pytest.approx(3.75, abs=1e-3)


def test_mains_hum_and_resonance_nearby_do_not_capture():
    rng = np.random.default_rng(4)
    fs = 1000.0
    t = np.arange(int(20 * fs)) / fs
    x = (
        _family(t, 3.9, [0.3, 0.16, 0.09, 0.05])
        + 2.0 * np.cos(2 * np.pi * 50 * t)  # hum, much stronger
        + 0.4 * np.cos(2 * np.pi * 5.3 * t) * (1 + 0.1 * np.cos(2 * np.pi * 0.2 * t))  # structural mode in band
        + 0.05 * rng.standard_normal(t.size)
    )
    est = estimate_pitch(_rec(t, x), speed=0.52)
    assert est.fundamental_hz == pytest.approx(3.9, abs=2e-3)
    assert est.pitch_m == pytest.approx(0.52 / 3.9, rel=1e-3)


def test_low_snr():
    rng = np.random.default_rng(5)
    t = np.arange(30 * 200) / 200.0
    x = _family(t, 3.54, [1.0, 0.2]) + 3.0 * rng.standard_normal(t.size)  # -12 dB per sample
    est = estimate_pitch(_rec(t, x), speed=0.49)
    assert abs(est.fundamental_hz - 3.54) < 5 * est.fundamental_sigma_hz
    assert est.fundamental_sigma_hz < 0.01


def test_speed_drift_between_bursts_widens_sigma():
    rng = np.random.default_rng(6)
    fs = 500.0
    ts, xs, ss = [], [], []
    for i, f in enumerate([3.70, 3.75, 3.80]):  # speed drifts by +-1.3 % between bursts
        t = 10.0 * i + np.arange(int(4 * fs)) / fs
        ts.append(t)
        xs.append(_family(t, f, [1.0, 0.3]) + 0.05 * rng.standard_normal(t.size))
        ss.append(np.full(t.size, i))
    est = estimate_pitch(_rec(np.concatenate(ts), np.concatenate(xs), np.concatenate(ss)), speed=0.5)
    assert len(est.per_burst) == 3
    assert [b["fundamental_hz"] for b in est.per_burst] == pytest.approx([3.70, 3.75, 3.80], abs=2e-3)
    assert est.fundamental_hz == pytest.approx(3.75, abs=0.01)
    assert abs(est.fundamental_hz - 3.75) < 3 * est.fundamental_sigma_hz  # widened to cover the drift
    assert any("scatter" in w for w in est.warnings)


def test_irregular_sampling_resampled():
    rng = np.random.default_rng(7)
    dt = 1 / 400.0
    t = np.cumsum(dt * (1 + 0.05 * rng.uniform(-1, 1, 8000)))
    x = _family(t, 3.9, [1.0, 0.4]) + 0.02 * rng.standard_normal(t.size)
    est = estimate_pitch(_rec(t, x), speed=0.52)
    assert est.fundamental_hz == pytest.approx(3.9, abs=2e-3)
    # said in a note; a warning only when the resampling changes the estimate beyond its sigma
    assert any("resampled" in n for n in est.notes) and not any("resampled" in w for w in est.warnings)


def test_field_cases():
    import vibkit

    leon = estimate_pitch(vibkit.read_recording("data/field/leon-tensioner.csv"), speed=0.49, nominal_pitch=0.4 / 3)
    assert leon.fundamental_hz == pytest.approx(3.54, abs=0.005)  # published
    assert leon.pitch_m == pytest.approx(0.1384, abs=2e-4)  # published 0.49 / 3.54
    assert leon.elongation_percent == pytest.approx(100 * (0.49 / 3.54 / (0.4 / 3) - 1), abs=0.2)
    assert leon.verdict == "replace"
    lp = estimate_pitch(vibkit.read_recording("data/field/las-palmas-accelerometer.csv"), speed=0.52)
    assert len(lp.per_burst) == 6
    assert lp.fundamental_hz == pytest.approx(3.9, abs=0.005)


@pytest.mark.parametrize(
    "e, verdict", [(0.5, "ok"), (1.6, "watch"), (2.5, "plan replacement"), (3.0, "replace"), (-2.0, "check speed")]
)
def test_verdicts(e, verdict):
    assert elongation_verdict(e) == verdict


@pytest.mark.parametrize(
    "kw, msg",
    [
        ({"speed": 0.0}, "speed"),
        ({"speed": 0.5, "speed_sigma": -1}, "speed_sigma"),
        ({"speed": 0.5, "channel": "nope"}, "channel"),
        ({"speed": 0.5, "limits_percent": (3, 2, 1)}, "limits"),
        ({"speed": 0.5, "band": (6.0, 2.0)}, "band"),
    ],
)
def test_bad_input(kw, msg):
    t = np.arange(2000) / 200.0
    with pytest.raises(ValueError, match=msg):
        estimate_pitch(_rec(t, np.sin(2 * np.pi * 3.75 * t)), **kw)


def test_an_elongation_that_is_another_catalogue_pitch_is_noted():
    """E07's step accelerometer reads 135.6 mm: +1.70 % of its nominal 133.33 mm (watch), and within 0.1 % of the
    catalogue's 135.46 mm, which a new chain of that pitch would read.  The note says both readings; Leon's
    +3.8 % (138.4 mm, 2.2 % from any catalogue pitch) gets no such note."""
    from vibkit import read_recording

    e07 = estimate_pitch(
        read_recording("data/fleet-example/E07/2026-11-23.csv"), speed=0.5, speed_sigma=5e-4, nominal_pitch=0.13333
    )
    assert e07.verdict == "watch"
    assert any("within 0.1 % of the catalogue pitch 135.46 mm" in n for n in e07.notes), e07.notes
    leon = estimate_pitch(
        read_recording("data/field/leon-tensioner.csv"), speed=0.49, speed_sigma=4.9e-4, nominal_pitch=0.13333
    )
    assert leon.verdict == "replace" and not any("catalogue pitch" in n for n in leon.notes)


def test_a_four_link_step_passes_at_a_quarter_of_the_link_pass():
    """Steps of 4 links (101.6 mm chains): the step-pass hypotheses divide by 4, not 3."""
    x = _family(np.arange(12000) / 200.0, 3.75)
    est = estimate_pitch(recording({"x": x}, 200.0), speed=0.5, links_per_step=4)
    names = [h.name for h in est.hypotheses]
    assert "f is the step pass (4 links)" in names and "step pass expected at f/4" in names
    step = next(h for h in est.hypotheses if h.name == "step pass expected at f/4")
    assert step.frequency_hz == pytest.approx(est.fundamental_hz / 4)
    with pytest.raises(ValueError, match="links_per_step"):
        estimate_pitch(recording({"x": x}, 200.0), speed=0.5, links_per_step=0)


def test_a_sensor_riding_a_step_is_warned_that_its_sigma_does_not_cover_its_bias():
    """A step's link pass reads up to about 1 % off the chain's (it turns half a cycle at each head): a profile
    whose sensor rides a step, or vibkit's simulated ``accel_step``, gets the warning; a tensioner does not."""
    from vibkit import read_recording
    from vibkit.diagnose.pitch import STEP_WARNING

    rec = read_recording("data/fleet-example/E07/2026-11-23.csv")
    kw = dict(speed=0.5, speed_sigma=5e-4, nominal_pitch=0.13333)
    assert STEP_WARNING in estimate_pitch(rec, on_step=True, **kw).warnings
    assert STEP_WARNING not in estimate_pitch(rec, **kw).warnings  # a channel named "accel", no profile
    t = np.arange(12000) / 200.0
    step = recording({"accel_step": _family(t, 3.75)}, 200.0)
    assert STEP_WARNING in estimate_pitch(step, speed=0.5).warnings
    assert STEP_WARNING not in estimate_pitch(step, speed=0.5, on_step=False).warnings


def test_a_fast_recorder_states_the_recorded_noise_s_sigma():
    """A 1 kHz record is decimated for the detection and the fits (by 6 for a 2.5-6 Hz band); the low-pass keeps
    about 0.8 of the new band's white noise, which the fits read as their noise.  The spectral sigma must still be
    the Cramer-Rao bound of the noise as recorded (the 200 Hz record of the same signal, not decimated, states it),
    not sqrt(0.8) = 0.89 of it (0.82-0.86 before).  At 420 Hz the spectral fit decimates once more (210 -> 105 Hz)
    and restates its own sigma: only the last decimation shapes the noise it fits, so the first must not be counted
    twice (1.16 of the bound when it was)."""
    ratios = {200.0: [], 420.0: [], 1000.0: []}
    amps = [1.0, 0.5, 0.3, 0.2]
    for fs in ratios:
        t = np.arange(int(60 * fs)) / fs
        for seed in range(3):
            rng = np.random.default_rng(seed)
            x = _family(t, 3.75, amps) + 3.0 * rng.standard_normal(t.size)
            est = estimate_pitch(_rec(t, x), speed=0.5)
            (row,) = est.per_burst
            ratios[fs].append(row["spectral_sigma_hz"] / crb_harmonic(t.size, fs, amps, 3.0))
    for fs, r in ratios.items():
        assert np.median(r) == pytest.approx(1.0, abs=0.08), (fs, r)
