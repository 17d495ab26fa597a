"""Trends that reject the impossible (vibkit.fleet.segments, vibkit.fleet.trends): synthetic units with
known elongation rates, plus flagged points, outliers, chain replacements and shortening chains."""

import datetime as dt
import math

import numpy as np
import pytest

from vibkit.fleet import Measurement
from vibkit.fleet.quality import measurement_quality
from vibkit.fleet.segments import screen_unit
from vibkit.fleet.trends import SECONDS_PER_YEAR, rank_units, unit_trend

T0 = dt.datetime(2022, 3, 1, tzinfo=dt.timezone.utc).timestamp()
SIGMA = 0.05  # % per measurement


def meas(i, years, e, s=SIGMA, *, unit="U", quality=None, replaced=False):
    t = T0 + years * SECONDS_PER_YEAR
    q, why = measurement_quality(e, s) if quality is None else (quality, "given")
    return Measurement(
        id=i,
        unit=unit,
        date_utc=dt.datetime.fromtimestamp(t, dt.timezone.utc).isoformat(),
        date_unix_s=t,
        date_source="given",
        speed_m_s=0.5,
        speed_sigma_m_s=0.001,
        nominal_pitch_m=0.13333,
        channel="a",
        fundamental_hz=3.75,
        fundamental_sigma_hz=1e-3,
        pitch_m=0.13333 * (1 + e / 100),
        pitch_sigma_m=1e-5,
        elongation_percent=e,
        elongation_sigma_percent=s,
        snr_db=20.0,
        warnings=(),
        sha256=f"{i:064x}",
        path=f"/r{i}.csv",
        size_bytes=1,
        vibkit_version="t",
        analysed_utc="2026-01-01T00:00:00Z",
        quality=q,
        quality_reason=why,
        replaced=replaced,
    )


def line_unit(e0, rate, years, *, seed, start_id=1, unit="U", s=SIGMA):
    rng = np.random.default_rng(seed)
    return [meas(start_id + k, y, e0 + rate * y + rng.normal(0, s), s, unit=unit) for k, y in enumerate(years)]


YEARS = np.linspace(0.0, 3.0, 7)


def test_quality_window_and_resolution():
    assert measurement_quality(0.8, 0.05) == ("ok", "")
    assert measurement_quality(52.0, 0.3)[0] == "implausible"  # the 1.5 s spreadsheet
    assert measurement_quality(-5.8, 0.3)[0] == "implausible"  # a chain 5.8 % shorter than new
    assert measurement_quality(-0.9, 0.05)[0] == "ok" and measurement_quality(5.9, 0.05)[0] == "ok"
    assert measurement_quality(1.0, 0.51)[0] == "inconclusive"  # cannot tell 1.5 % from 2 %
    assert measurement_quality(1.0, 0.49)[0] == "ok"
    assert measurement_quality(1.0, 0.05, decision="inconclusive")[0] == "inconclusive"


def test_issue_example_flags_instead_of_a_minus_112_percent_trend():
    # 3.8 % and -5.8 % and 52 %: the two impossible points are flagged, no trend is forecast
    ms = [meas(1, 0.0, 3.8, 0.1), meas(2, 0.5, -5.8, 0.3), meas(3, 1.0, 52.0, 0.4)]
    tr = unit_trend("E22", ms)
    assert tr.slope_percent_per_year is None and tr.rate_verdict == "too few"
    assert [f["quality"] for f in tr.flagged] == ["implausible", "implausible"]
    assert tr.latest_elongation_percent == 3.8 and tr.n_used == 1
    assert [f.status for f in tr.forecasts] == ["reached", "reached", "reached"]
    assert "2 implausible measurement(s) left out" in tr.flags and "latest measurement" in " ".join(tr.flags)


def test_a_unit_without_a_usable_measurement_says_so_once_and_marks_its_elongation():
    """Every visit inconclusive: one flag says there is nothing to trend and why, and the work list's elongation
    (the column of the latest usable measurement) shows the latest one marked as flagged."""
    from vibkit.diagnose.report.fleet import fmt_elongation

    ms = [meas(k, 0.5 * k, 0.3, 2.9) for k in (1, 2, 3)]  # sigma 2.9 %: cannot tell 1.5 % from 2 %
    tr = unit_trend("E12", ms)
    assert tr.n_used == 0 and tr.latest_verdict == "inconclusive"
    assert tr.flags == ("no usable measurement (3 inconclusive)",)
    assert fmt_elongation(tr).endswith("(flagged)")
    assert not fmt_elongation(unit_trend("E07", [meas(1, 0.0, 1.7, 0.1)])).endswith("(flagged)")


def test_flagged_points_left_out_of_the_fit():
    ms = line_unit(0.4, 0.5, YEARS, seed=1)
    clean = unit_trend("U", ms)
    bad = ms + [meas(99, 1.2, 0.2, 0.8), meas(98, 1.7, 1.9, 0.05, quality="inconclusive")]
    tr = unit_trend("U", bad)
    assert tr.slope_percent_per_year == clean.slope_percent_per_year and tr.n_used == 7
    assert dict(tr.point_labels)[99] == "inconclusive" and dict(tr.point_labels)[98] == "inconclusive"
    assert abs(tr.slope_percent_per_year - 0.5) < 3 * tr.slope_sigma_percent_per_year


@pytest.mark.parametrize("jump", [+0.6, -0.45])
def test_outlier_beyond_5_sigma_is_marked_and_left_out(jump):
    # a unit growing 0.5 %/year measured 7 times with sigma 0.05 %; one visit off by 9-12 sigma
    ms = line_unit(0.4, 0.5, YEARS, seed=2)
    k = 3
    m = ms[k]
    ms[k] = meas(m.id, YEARS[k], m.elongation_percent + jump)
    tr = unit_trend("U", ms)
    assert [o["id"] for o in tr.outliers] == [m.id] and dict(tr.point_labels)[m.id] == "outlier"
    assert tr.n_used == 6 and abs(tr.slope_percent_per_year - 0.5) < 3 * tr.slope_sigma_percent_per_year
    assert tr.rate_verdict == "growing" and tr.replacements == ()
    assert any("outlier" in f for f in tr.flags)
    if jump > 0:
        assert tr.outliers[0]["deviation_sigma"] > 5


def test_no_outlier_within_5_sigma():
    ms = line_unit(0.4, 0.5, YEARS, seed=3)
    ms[3] = meas(ms[3].id, YEARS[3], ms[3].elongation_percent + 4 * SIGMA)  # 4 sigma: kept
    tr = unit_trend("U", ms)
    assert tr.outliers == () and tr.n_used == 7


def test_drop_starts_a_new_segment_and_the_new_chain_rate_is_recovered():
    # old chain: 1.2 % + 0.5 %/year for 2 years; replaced; new chain: 0.05 % + 0.3 %/year for 2.5 years
    old = line_unit(1.2, 0.5, np.linspace(0, 2.0, 5), seed=4)
    new_years = 2.2 + np.linspace(0, 2.5, 6)
    rng = np.random.default_rng(5)
    new = [meas(100 + k, y, 0.05 + 0.3 * (y - 2.2) + rng.normal(0, SIGMA)) for k, y in enumerate(new_years)]
    tr = unit_trend("U", old + new)
    assert len(tr.replacements) == 1 and tr.replacements[0]["id"] == 100
    assert tr.segment_start_utc == new[0].date_utc and "fell from" in tr.replacements[0]["reason"]
    assert tr.n_used == 6 and abs(tr.slope_percent_per_year - 0.3) < 3 * tr.slope_sigma_percent_per_year
    assert tr.rate_verdict == "growing" and tr.outliers == ()
    assert {lab for i, lab in tr.point_labels if i < 100} == {"earlier segment"}
    # fitted across the replacement the rate would be negative: the segment is what prevents it
    assert tr.over_limit_percent is None and tr.latest_elongation_percent < 1.0


def test_lone_low_point_is_an_outlier_not_a_replacement():
    ms = line_unit(1.0, 0.4, YEARS, seed=6)
    ms[3] = meas(ms[3].id, YEARS[3], 0.2)  # the next visit is back on the old line
    tr = unit_trend("U", ms)
    assert tr.replacements == () and [o["id"] for o in tr.outliers] == [ms[3].id]
    assert abs(tr.slope_percent_per_year - 0.4) < 3 * tr.slope_sigma_percent_per_year


@pytest.mark.parametrize("seed", range(5))
def test_lone_high_point_is_an_outlier_not_a_replacement(seed):
    # 0.3 %/year, visits every 0.4 years, one visit 0.6 % (8.5 combined sigmas) too high: the step down after
    # it is not a chain replacement
    years = np.arange(7) * 0.4
    ms = line_unit(0.5, 0.3, years, seed=20 + seed)
    ms[3] = meas(ms[3].id, years[3], ms[3].elongation_percent + 0.6)
    tr = unit_trend("U", ms)
    assert tr.replacements == () and [o["id"] for o in tr.outliers] == [ms[3].id]
    assert tr.n_used == 6 and abs(tr.slope_percent_per_year - 0.3) < 3 * tr.slope_sigma_percent_per_year


def test_replaced_flag_starts_a_segment_without_a_drop():
    # a used chain fitted: no drop, but the technician said so (fleet add --replaced)
    old = line_unit(0.5, 0.6, np.linspace(0, 2.0, 5), seed=7)
    new = line_unit(1.8, 0.2, 2.3 + np.linspace(0, 2.0, 5), seed=8, start_id=50)
    new = [
        meas(
            m.id,
            (m.date_unix_s - T0) / SECONDS_PER_YEAR,
            1.8
            + 0.2 * ((m.date_unix_s - T0) / SECONDS_PER_YEAR - 2.3)
            + (m.elongation_percent - 1.8 - 0.2 * (m.date_unix_s - T0) / SECONDS_PER_YEAR),
            replaced=(k == 0),
        )
        for k, m in enumerate(new)
    ]
    tr = unit_trend("U", old + new)
    assert [r["id"] for r in tr.replacements] == [50] and "given" in tr.replacements[0]["reason"]
    assert tr.n_used == 5 and abs(tr.slope_percent_per_year - 0.2) < 3 * tr.slope_sigma_percent_per_year


def test_shortening_chain_is_implausible_not_forecast():
    # -0.4 %/year with sigma 0.1 %, visits every 3 months: each step is within the measurement error (no
    # replacement), the rate is about -8 sigma
    years = np.arange(9) * 0.25
    rng = np.random.default_rng(9)
    ms = [meas(k + 1, y, 1.4 - 0.4 * y + rng.normal(0, 0.1), 0.1) for k, y in enumerate(years)]
    tr = unit_trend("U", ms)
    assert tr.replacements == () and tr.outliers == ()
    assert tr.rate_verdict == "implausible"
    assert tr.slope_percent_per_year + 3 * tr.slope_sigma_percent_per_year < 0
    assert [f.status for f in tr.forecasts] == ["implausible"] * 3
    assert all(f.date_utc is None and f.earliest_utc is None for f in tr.forecasts)
    assert any("does not shorten" in f for f in tr.flags)


def test_flat_unit_within_noise_is_not_implausible():
    years = np.arange(9) * 0.25
    rng = np.random.default_rng(10)
    ms = [meas(k + 1, y, 0.8 + rng.normal(0, 0.1), 0.1) for k, y in enumerate(years)]
    tr = unit_trend("U", ms)
    assert tr.rate_verdict in ("flat", "growing") and tr.rate_verdict != "implausible"
    assert abs(tr.slope_percent_per_year) < 3 * tr.slope_sigma_percent_per_year


def test_a_rate_below_zero_by_two_to_three_sigma_is_flat_and_flagged_for_a_check():
    """Two visits a year apart, 0.32 % then 0.17 % (sigma 0.05 % each): -0.15 +- 0.071 %/year, 2.1 sigma below
    zero: flat, with a note asking for a check; -0.10 %/year (1.4 sigma) gets no note."""
    doubtful = unit_trend("U", [meas(1, 0.0, 0.32), meas(2, 1.0, 0.17)])
    assert doubtful.rate_verdict == "flat"
    assert doubtful.slope_percent_per_year == pytest.approx(-0.15, abs=1e-3)
    assert any("below zero by 2.1 sigma" in f and "does not shorten" in f for f in doubtful.flags), doubtful.flags
    within = unit_trend("U", [meas(1, 0.0, 0.32), meas(2, 1.0, 0.22)])  # -0.10: 1.4 sigma
    assert within.rate_verdict == "flat" and not any("below zero" in f for f in within.flags)


def test_work_list_order():
    units = {
        "over": line_unit(2.1, 0.1, YEARS, seed=11, unit="over", start_id=1),  # 2.4 % now: past 2 %
        "soon": line_unit(0.3, 0.3, YEARS, seed=12, unit="soon", start_id=100),  # 1.5 % after 4 years
        "later": line_unit(0.2, 0.1, YEARS, seed=13, unit="later", start_id=200),  # 1.5 % after 13 years
        "flat": line_unit(0.5, 0.0, YEARS, seed=14, unit="flat", start_id=300),
        "short": [meas(400 + k, y, 1.2 - 0.3 * y, 0.05, unit="short") for k, y in enumerate(np.arange(9) * 0.25)],
    }
    ranked = rank_units([unit_trend(u, ms) for u, ms in units.items()])
    assert [t.unit for t in ranked] == ["over", "soon", "later", "short", "flat"]
    assert [t.rank for t in ranked] == [1, 2, 3, 4, 5]
    soon = ranked[1]
    nxt = soon.next_limit()
    assert nxt.limit_percent == 1.5 and nxt.status == "forecast"
    truth = T0 + (1.5 - 0.3) / 0.3 * SECONDS_PER_YEAR
    lo, hi = (dt.datetime.fromisoformat(v).timestamp() for v in (nxt.earliest_utc, nxt.latest_utc))
    assert lo <= truth <= hi
    d = soon.as_dict()
    assert d["next_limit"]["limit_percent"] == 1.5 and d["rate_verdict"] == "growing" and d["flags"] == []


def test_screen_unit_labels_every_point():
    ms = line_unit(0.4, 0.5, YEARS, seed=15) + [meas(77, 1.0, 9.0)]
    scr = screen_unit(ms)
    assert set(scr.labels) == {m.id for m in ms} and scr.labels[77] == "implausible"
    assert math.isclose(len(scr.used), 7)


@pytest.mark.parametrize("rate, spacing", [(0.0, 0.25), (0.3, 0.4)])
def test_few_false_alarms_on_clean_units(rate, spacing):
    # 300 units of 8 visits with nothing wrong: at most 1 % get a replacement, an outlier or an implausible rate
    # (expected: 7 steps x P(z > 4 sigma) = 2e-4 replacements a unit; outliers at 5 sigma rarer still)
    alarms = 0
    for s in range(300):
        tr = unit_trend("U", line_unit(0.5, rate, np.arange(8) * spacing, seed=5000 + s))
        alarms += bool(tr.replacements or tr.outliers or tr.rate_verdict == "implausible")
    assert alarms <= 3


def test_an_outlier_found_by_its_drop_says_how_many_sigmas():
    """+0.32, +1.16, -0.02 %: the middle visit rose and the next fell back; it is left out, with how far it rose
    in combined sigmas (the JSON said null)."""
    ms = [meas(1, 0.0, 0.32, 0.1), meas(2, 0.5, 1.16, 0.1), meas(3, 1.0, -0.02, 0.1)]
    tr = unit_trend("S14", ms)
    (o,) = tr.outliers
    assert o["date_utc"] == ms[1].date_utc and o["deviation_sigma"] == pytest.approx(0.84 / np.hypot(0.1, 0.1))
