"""Where a person carrying a phone stands still: the walking band's hysteresis (enter under the still level, leave
only when walking holds for a step)."""

from __future__ import annotations

import numpy as np
import pytest

from vibkit.signal.stillness import LEAVE_THRESHOLD, STILL_THRESHOLD, still_spans

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
