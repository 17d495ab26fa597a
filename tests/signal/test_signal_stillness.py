"""Where a person carrying a phone stands still: the walking band's hysteresis (enter under the still level, leave
only when walking holds for a step)."""

from __future__ import annotations

import numpy as np
import pytest
from scipy import signal

from vibkit.signal.stillness import LEAVE_THRESHOLD, STILL_THRESHOLD, gravity_removed, still_spans, walking_level

FS = 100.0


def _level(*parts):
    """A walking-band level made of ``(value [m/s^2], seconds)`` parts."""
    return np.concatenate([np.full(int(round(s * FS)), v, dtype=float) for v, s in parts])


def test_a_passenger_shifting_on_a_step_does_not_cut_the_still_span():
    # walk 10 s, stand 10 s, shift (0.33: over the still level, under walking's) 3 s, stand 10 s, walk
    level = _level((1.0, 10), (0.08, 10), (0.33, 3), (0.08, 10), (1.0, 10))
    assert still_spans(level, FS) == [(1000, 3300)]
    # the single threshold cuts it in two
    assert still_spans(level, FS, leave=STILL_THRESHOLD, dwell_s=0.0) == [(1000, 2000), (2300, 3300)]


def test_a_span_ends_where_walking_resumes_not_where_it_first_stirs():
    # stepping off: the level climbs through 0.3 for 2 s before the walk's 0.9
    level = _level((1.0, 10), (0.08, 20), (0.3, 2), (0.9, 10))
    assert still_spans(level, FS) == [(1000, 3200)]


def test_walking_for_a_step_ends_the_span_and_a_shorter_burst_does_not():
    burst = _level((1.0, 10), (0.08, 10), (0.8, 0.3), (0.08, 10), (1.0, 10))
    assert still_spans(burst, FS) == [(1000, 3030)]
    step = _level((1.0, 10), (0.08, 10), (0.8, 0.6), (0.08, 10), (1.0, 10))
    assert still_spans(step, FS) == [(1000, 2000), (2060, 3060)]


def test_a_gap_always_ends_the_span():
    level = _level((1.0, 10), (0.08, 10), (np.inf, 0.1), (0.08, 10), (1.0, 10))
    assert still_spans(level, FS) == [(1000, 2000), (2010, 3010)]
    level[2000:2010] = np.nan
    assert still_spans(level, FS) == [(1000, 2000), (2010, 3010)]


def test_walking_that_never_falls_under_the_still_level_is_no_span():
    # a slow walk whose level stays between the two thresholds: never entered
    level = _level((0.3, 30))
    assert still_spans(level, FS) == []
    assert LEAVE_THRESHOLD > STILL_THRESHOLD


def test_leave_under_the_threshold_is_refused():
    with pytest.raises(ValueError, match="leave 0.1 is under threshold 0.25"):
        still_spans(_level((0.1, 10)), FS, leave=0.1)


def _walk_then_stand(fs=100.0, amp=1.5, step_hz=1.9, seed=1):
    """20 s of walking (``amp`` sin on the vertical, the phone tilted 20 deg), then 20 s standing; (3, N) with gravity
    removed, and gravity, in the phone's axes [m/s^2]."""
    rng = np.random.default_rng(seed)
    t = np.arange(0.0, 40.0, 1 / fs)
    up = np.array([0.0, np.sin(np.deg2rad(20)), np.cos(np.deg2rad(20))])
    vertical = np.where(t < 20.0, amp * np.sin(2 * np.pi * step_hz * t), 0.0)
    free = up[:, None] * vertical + 0.02 * rng.standard_normal((3, t.size))
    return t, free, np.repeat((9.80665 * up)[:, None], t.size, axis=1)


def test_gravity_removed_is_told_by_the_missing_steady_part():
    t, free, gravity = _walk_then_stand()
    assert gravity_removed(free, 100.0) and not gravity_removed(free + gravity, 100.0)
    assert gravity_removed(0.02 + free[:, t >= 20], 100.0)  # lying still, a sensor's bias


@pytest.mark.parametrize("with_gravity", [True, False])
def test_a_walk_reads_as_walking_with_gravity_or_without(with_gravity):
    """With gravity, the band of |a| ~ g + a_vertical holds the step at amp / sqrt(2) r.m.s.; with gravity removed
    |a| is the rectified step (twice its rate, out of the band), so the level is the band of the three axes
    together: the same amp / sqrt(2) for a step along the vertical.  Standing stays under the still level."""
    fs, amp = 100.0, 1.5
    t, free, gravity = _walk_then_stand(fs, amp)
    acc = free + gravity if with_gravity else free
    level = walking_level(acc, fs)
    assert np.median(level[(t > 3) & (t < 17)]) == pytest.approx(amp / np.sqrt(2), rel=0.1)
    assert np.median(level[t > 23]) < STILL_THRESHOLD
    (a, b) = still_spans(level, fs, min_s=6.0)[0]
    assert t[a] == pytest.approx(20.0, abs=1.5) and b == t.size


def test_rectified_magnitude_of_a_gravity_free_walk_would_read_as_standing():
    """Why the band of the three axes: the band of |a| of the same walk with gravity removed stays under the still
    level (the step's energy moved to twice its rate), and the walk would be a ride's still span."""
    t, free, _ = _walk_then_stand()
    sos = signal.butter(4, [0.5, 3.0], "bandpass", fs=100.0, output="sos")
    rect = signal.sosfiltfilt(sos, np.sqrt(np.sum(free**2, axis=0)))
    assert np.sqrt(np.mean(rect[(t > 3) & (t < 17)] ** 2)) < STILL_THRESHOLD
