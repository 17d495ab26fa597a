"""Fleet history (vibkit.fleet, vibkit fleet ...): trends of synthetic units with known elongation rates,
forecasts, duplicates, bad rows, a killed scan, the command line."""

import datetime as dt
import json
import math
import os
import signal
import sqlite3
import subprocess
import sys
import time
from pathlib import Path

import numpy as np
import pytest

import vibkit.runtime.cluster as cluster
from vibkit.cli import main
from vibkit.fleet import (
    DuplicateRecordingError,
    FleetDB,
    FleetError,
    TrendFit,
    fit_trend,
    forecast_limits,
    parse_date,
    read_catalogue,
    resolve_db_path,
)
from vibkit.fleet.trends import SECONDS_PER_YEAR

from support.chain import random_phase_family

ROOT = Path(__file__).resolve().parents[2]
SPEED = 0.5  # m/s
NOMINAL = 0.4 / 3  # m
FS = 200.0  # Hz
DURATION = 20.0  # s
AMPS = (1.0, 0.5, 0.3)  # link-pass harmonics [m/s^2]
NOISE = 1.0  # white noise standard deviation [m/s^2]
T0 = dt.datetime(2023, 1, 15, tzinfo=dt.timezone.utc)


def synth(path, pitch_m, seed, *, start=None, amps=AMPS, duration=DURATION):
    """A recording of a chain of pitch ``pitch_m`` at SPEED: harmonics of v/L plus white noise, CSV."""
    t = np.arange(int(duration * FS)) / FS
    x = random_phase_family(t, SPEED / pitch_m, np.random.default_rng(seed), amps, noise=NOISE)
    with open(path, "w") as fh:
        if start is None:
            fh.write("time_s,accel_m_s2\n")
            fh.writelines(f"{ti:.3f},{xi:.6f}\n" for ti, xi in zip(t, x))
        else:
            fh.write("timestamp,accel_m_s2\n")
            fh.writelines(
                f"{(start + dt.timedelta(seconds=float(ti))).strftime('%Y-%m-%dT%H:%M:%S.%f')[:-3]}Z,{xi:.6f}\n"
                for ti, xi in zip(t, x)
            )
    return path


def crb_elongation_sigma_percent(pitch_m):
    """Cramer-Rao bound of the elongation for the synthetic recordings (harmonic family in white noise).

    var(f) = 12 sigma^2 fs^2 / ((2 pi)^2 N (N^2 - 1) sum k^2 A_k^2)  (a real harmonic family);
    the elongation 100 (L / L0 - 1) with L = v / f has sigma 100 L / L0 * sigma_f / f.
    """
    n = int(DURATION * FS)
    var_f = (
        12 * NOISE**2 * FS**2 / ((2 * np.pi) ** 2 * n * (n**2 - 1) * sum(k**2 * a**2 for k, a in enumerate(AMPS, 1)))
    )
    f = SPEED / pitch_m
    return 100 * pitch_m / NOMINAL * math.sqrt(var_f) / f


# units: (initial elongation [%], rate [%/year]); six visits over 2.5 years
UNITS = {"E-fast": (0.10, 0.5), "E-slow": (0.20, 0.2), "E-flat": (0.50, 0.0), "E-worn": (1.60, 0.3)}
VISITS_YEARS = np.array([0.0, 0.45, 0.9, 1.4, 1.95, 2.5])


def true_elongation(unit, years):
    e0, rate = UNITS[unit]
    return e0 + rate * years


@pytest.fixture(scope="module")
def fleet(tmp_path_factory):
    """A folder of 24 recordings of 4 units, a catalogue, and the database after a (plain-loop) scan."""
    d = tmp_path_factory.mktemp("fleet")
    rec = d / "visits"
    rec.mkdir()
    lines = ["# synthetic fleet: harmonics of v/L plus white noise", "file,unit,speed_m_s,date,nominal_pitch_m"]
    seed = 100
    for unit in UNITS:
        for i, y in enumerate(VISITS_YEARS):
            seed += 1
            pitch = NOMINAL * (1 + true_elongation(unit, y) / 100)
            name = f"{unit}_{i}.csv"
            synth(rec / name, pitch, seed)
            date = (T0 + dt.timedelta(seconds=float(y * SECONDS_PER_YEAR))).isoformat()
            # the nominal pitch on the unit's first line only: the other lines inherit it
            lines.append(f"{name},{unit},{SPEED},{date},{NOMINAL if i == 0 else ''}")
    cat = d / "units.csv"
    cat.write_text("\n".join(lines) + "\n")
    db_path = d / "fleet.sqlite"
    failures = []
    with FleetDB(db_path) as db:
        res = db.scan(rec, cat, parallel=False, on_failure=lambda f, why: failures.append((f, why)))
    assert failures == [] and len(res.added) == 24 and not res.skipped
    return {"dir": rec, "catalogue": cat, "db": db_path}


# ------------------------------------------------------------------------------- pure functions


def test_fit_trend_exact_line_and_analytic_sigma():
    t = T0.timestamp() + np.array([0.0, 0.5, 1.0, 2.0]) * SECONDS_PER_YEAR
    e = 0.25 + 0.8 * (t - t[0]) / SECONDS_PER_YEAR
    s = np.full(4, 0.05)
    fit = fit_trend(t, e, s)
    assert fit.slope_percent_per_year == pytest.approx(0.8, rel=1e-12)
    tau = (t - t.mean()) / SECONDS_PER_YEAR  # equal weights: the reference is the mean time
    assert fit.t_ref_unix_s == pytest.approx(t.mean(), rel=1e-15)
    assert fit.slope_sigma_percent_per_year == pytest.approx(0.05 / math.sqrt(np.sum(tau**2)), rel=1e-12)
    assert fit.elongation_ref_sigma_percent == pytest.approx(0.05 / 2, rel=1e-12)
    assert fit.sigma_scale == 1.0 and fit.chi2_per_dof == pytest.approx(0.0, abs=1e-20)
    assert fit.elongation_at(t[-1]) == pytest.approx(e[-1], rel=1e-12)


def test_fit_trend_weights_and_birge_scaling():
    # a point with a huge sigma does not move the line
    t = np.array([0.0, 1.0, 2.0, 3.0]) * SECONDS_PER_YEAR
    e = np.array([0.0, 1.0, 2.0, 50.0])
    fit = fit_trend(t, e, [0.01, 0.01, 0.01, 1e6])
    assert fit.slope_percent_per_year == pytest.approx(1.0, rel=1e-6)
    # scatter 10x the stated sigma: sigmas scaled by sqrt(chi2 / dof), about 10
    rng = np.random.default_rng(3)
    t = np.linspace(0, 4, 40) * SECONDS_PER_YEAR
    e = 0.5 * t / SECONDS_PER_YEAR + rng.normal(0, 0.1, t.size)
    fit = fit_trend(t, e, np.full(t.size, 0.01))
    assert 7 < fit.sigma_scale < 13
    tau = (t - t.mean()) / SECONDS_PER_YEAR
    assert fit.slope_sigma_percent_per_year == pytest.approx(fit.sigma_scale * 0.01 / math.sqrt(np.sum(tau**2)))
    assert abs(fit.slope_percent_per_year - 0.5) < 3 * fit.slope_sigma_percent_per_year


@pytest.mark.parametrize(
    "t, e, s, match",
    [
        ([0.0], [1.0], [0.1], "at least two"),
        ([0.0, 0.0], [1.0, 1.1], [0.1, 0.1], "different times"),
        ([0.0, 1e8], [1.0, 1.1], [0.1, 0.0], "sigma_percent must be > 0"),
        ([0.0, 1e8], [1.0, np.nan], [0.1, 0.1], "finite"),
        ([0.0, 1e8, 2e8], [1.0, 1.1], [0.1, 0.1], "same length"),
    ],
)
def test_fit_trend_rejects(t, e, s, match):
    with pytest.raises(ValueError, match=match):
        fit_trend(t, e, s)


def _fit(a, sa, b, sb, t_ref=T0.timestamp()):
    return TrendFit(5, t_ref, a, sa, b, sb, 1.0, 1.0)


def _years_after(iso, t_ref=T0.timestamp()):
    return (dt.datetime.fromisoformat(iso).timestamp() - t_ref) / SECONDS_PER_YEAR


def test_forecast_limits_analytic():
    # 1.0 % at t_ref growing 1 %/year: 1.5 % in 0.5 years, 2 % in 1, 3 % in 2
    fc = forecast_limits(_fit(1.0, 0.02, 1.0, 0.1), (1.5, 2.0, 3.0), latest_elongation_percent=1.1)
    assert [f.status for f in fc] == ["forecast"] * 3
    for f, years in zip(fc, (0.5, 1.0, 2.0)):
        assert _years_after(f.date_utc) == pytest.approx(years, abs=1e-6)
    # 2-sigma corners: (L - a - 2 sa) / (b + 2 sb) and (L - a + 2 sa) / (b - 2 sb)
    assert _years_after(fc[1].earliest_utc) == pytest.approx((1.0 - 0.04) / 1.2, abs=1e-6)
    assert _years_after(fc[1].latest_utc) == pytest.approx((1.0 + 0.04) / 0.8, abs=1e-6)
    # reached, not before, none
    fc = forecast_limits(_fit(1.0, 0.02, 0.1, 0.1), (1.5, 2.0, 3.0), latest_elongation_percent=1.6)
    assert fc[0].status == "reached"
    assert fc[1].status == "not before" and fc[1].date_utc is None and fc[1].latest_utc is None
    assert _years_after(fc[1].earliest_utc) == pytest.approx((2.0 - 1.0 - 0.04) / 0.3, abs=1e-6)
    fc = forecast_limits(_fit(1.0, 0.02, -0.5, 0.1), (1.5, 2.0, 3.0))
    assert [f.status for f in fc] == ["none"] * 3
    assert [f.status for f in forecast_limits(None, (1.5, 2.0, 3.0), latest_elongation_percent=2.5)] == [
        "reached",
        "reached",
        "none",
    ]


def test_parse_date():
    assert parse_date("2026-03-01").isoformat() == "2026-03-01T00:00:00+00:00"
    assert parse_date("2026-03-01T10:00:00+01:00").isoformat() == "2026-03-01T09:00:00+00:00"
    assert parse_date("13/03/2026 10:00:00").isoformat() == "2026-03-13T10:00:00+00:00"
    assert parse_date("01/03/2026 10:00:00", ambiguous_ok=True).isoformat() == "2026-03-01T10:00:00+00:00"
    with pytest.raises(FleetError, match=r"ambiguous.*01 March.*03 January.*2026-03-01"):
        parse_date("01/03/2026")  # a person's date: day/month or month/day cannot be told
    assert parse_date("2019-03-12, 10:25:14,500").isoformat() == "2019-03-12T10:25:14.500000+00:00"  # GCDC
    for bad, match in (
        ("12:00:00", "no calendar date"),
        ("yesterday", "ISO 8601"),
        ("2999-01-01", "1970-2100"),
        ("2099-01-01", "future"),
        ("1850-01-01", "1970-2100"),
        ("", "empty"),
        ("9999-12-31T23:59:59-23:59", "1970-2100"),
    ):
        with pytest.raises(FleetError, match=match):
            parse_date(bad)


# ------------------------------------------------------------------------------------ the fleet


def test_rates_within_sigma_and_forecasts(fleet):
    with FleetDB(fleet["db"], create=False) as db:
        assert db.integrity_check() == "ok"
        trends = {t.unit: t for t in db.status()}
        ranked = [t.unit for t in db.status()]
    years = VISITS_YEARS - np.mean(VISITS_YEARS)
    for unit, (_e0, rate) in UNITS.items():
        tr = trends[unit]
        assert tr.n_measurements == 6
        sig = tr.slope_sigma_percent_per_year
        assert abs(tr.slope_percent_per_year - rate) < 3 * sig, unit
        # sigma plausibly sized: the Cramer-Rao bound of each elongation propagated through the fit
        # (the estimator reaches about 1.2x the bound; the Birge factor can only widen it)
        crb = np.mean(
            [crb_elongation_sigma_percent(NOMINAL * (1 + true_elongation(unit, y) / 100)) for y in VISITS_YEARS]
        )
        expected = crb / math.sqrt(np.sum(years**2))
        assert 0.8 * expected < sig < 3.0 * expected, (unit, sig, expected)
        assert tr.latest_elongation_percent == pytest.approx(
            true_elongation(unit, VISITS_YEARS[-1]), abs=4 * tr.latest_elongation_sigma_percent
        )
    # forecasts of the growing units: the true crossing lies in the interval, near the central date
    for unit in ("E-fast", "E-slow"):
        e0, rate = UNITS[unit]
        for f in trends[unit].forecasts:
            assert f.status == "forecast"
            truth = T0.timestamp() + (f.limit_percent - e0) / rate * SECONDS_PER_YEAR
            lo, mid, hi = (dt.datetime.fromisoformat(v).timestamp() for v in (f.earliest_utc, f.date_utc, f.latest_utc))
            assert lo <= truth <= hi, (unit, f)
            assert abs(mid - truth) < max(hi - mid, mid - lo)
    # a flat unit has no significant growth: no forecast date, at most a "not before"
    assert all(f.status in ("not before", "none") for f in trends["E-flat"].forecasts)
    # the worn unit is over 1.5 and 2 % (2.35 % now): ranked first; then the fastest; the flat one last
    worn = trends["E-worn"]
    assert [f.status for f in worn.forecasts][:2] == ["reached", "reached"] and worn.over_limit_percent == 2.0
    assert ranked == ["E-worn", "E-fast", "E-slow", "E-flat"]


def test_rescan_skips_everything(fleet):
    with FleetDB(fleet["db"]) as db:
        res = db.scan(fleet["dir"], fleet["catalogue"], parallel=False)
        assert (len(res.added), len(res.skipped), len(res.failed)) == (0, 24, 0)
        assert len(db.measurements()) == 24


def test_rows_carry_provenance(fleet):
    import vibkit

    with FleetDB(fleet["db"], create=False) as db:
        m = db.measurements("E-fast")[0]
    assert m.date_utc == "2023-01-15T00:00:00Z" and m.date_source == "given"
    assert m.nominal_pitch_m == pytest.approx(NOMINAL, rel=1e-12)  # inherited from the unit's first line
    assert Path(m.path).name == "E-fast_0.csv" and m.vibkit_version == vibkit.__version__
    import hashlib

    assert m.sha256 == hashlib.sha256(Path(m.path).read_bytes()).hexdigest()
    assert m.elongation_percent == pytest.approx(100 * (m.pitch_m / m.nominal_pitch_m - 1), rel=1e-12)
    assert dt.datetime.fromisoformat(m.analysed_utc) <= dt.datetime.now(dt.timezone.utc)


def test_duplicate_refused(fleet, tmp_path, capsys):
    src = fleet["dir"] / "E-slow_2.csv"
    copy = tmp_path / "renamed.csv"
    copy.write_bytes(src.read_bytes())
    with FleetDB(fleet["db"]) as db:
        with pytest.raises(DuplicateRecordingError, match="already stored .*E-slow") as ei:
            db.add(copy, unit="E-other", speed=SPEED, date="2026-01-01", nominal_pitch=NOMINAL)
        assert ei.value.existing.unit == "E-slow"
        n = len(db.measurements())
    assert (
        main(
            [
                "fleet",
                "add",
                str(copy),
                "--unit",
                "E-slow",
                "--speed",
                "0.5",
                "--date",
                "2026-01-01",
                "--db",
                str(fleet["db"]),
            ]
        )
        == 1
    )
    err = capsys.readouterr().err
    assert "already stored (same sha256)" in err and "Traceback" not in err
    with FleetDB(fleet["db"]) as db:
        assert len(db.measurements()) == n


def test_add_date_from_start_time_or_refused(tmp_path, capsys):
    db = tmp_path / "f.sqlite"
    start = dt.datetime(2025, 6, 1, 8, 30, tzinfo=dt.timezone.utc)
    stamped = synth(tmp_path / "stamped.csv", NOMINAL * 1.005, 1, start=start, duration=10.0)
    plain = synth(tmp_path / "plain.csv", NOMINAL * 1.005, 2, duration=10.0)
    assert (
        main(
            [
                "fleet",
                "add",
                str(stamped),
                "--unit",
                "U1",
                "--speed",
                "0.5",
                "--speed-uncertainty",
                "0.05%",
                "--nominal-pitch",
                str(NOMINAL),
                "--db",
                str(db),
                "--json",
            ]
        )
        == 0
    )
    d = json.loads(capsys.readouterr().out)
    assert d["schema"] == "vibkit.fleet.add/1"
    m = d["measurement"]
    assert m["date_utc"] == "2025-06-01T08:30:00Z" and m["date_source"] == "recording start time"
    assert m["elongation_percent"] == pytest.approx(0.5, abs=4 * m["elongation_sigma_percent"])
    # no start time and no --date: refused, asking for --date; a new unit without a nominal pitch too
    assert main(["fleet", "add", str(plain), "--unit", "U1", "--speed", "0.5", "--db", str(db)]) == 1
    assert "--date" in capsys.readouterr().err
    assert (
        main(["fleet", "add", str(plain), "--unit", "U2", "--speed", "0.5", "--date", "2025-01-01", "--db", str(db)])
        == 1
    )
    assert "--nominal-pitch" in capsys.readouterr().err
    # another nominal pitch for a known unit is refused
    assert (
        main(
            [
                "fleet",
                "add",
                str(plain),
                "--unit",
                "U1",
                "--speed",
                "0.5",
                "--date",
                "2025-01-01",
                "--nominal-pitch",
                "0.1335",
                "--db",
                str(db),
            ]
        )
        == 1
    )  # plausible (+0.4 %), but not U1's
    assert "one unit has one nominal pitch" in capsys.readouterr().err
    with FleetDB(db) as fdb:
        assert len(fdb.measurements()) == 1


def test_bad_rows_reported_not_fatal(tmp_path, capsys):
    d = tmp_path / "visits"
    d.mkdir()
    synth(d / "good1.csv", NOMINAL * 1.01, 11, duration=10.0)
    synth(d / "good2.csv", NOMINAL * 1.01, 12, duration=10.0)
    synth(d / "noise.csv", NOMINAL, 13, amps=(), duration=10.0)  # no link-pass
    (d / "garbage.csv").write_text("this is not,a recording\nat,all\n")  # unreadable
    synth(d / "stray.csv", NOMINAL, 14, duration=10.0)  # no catalogue line: unknown unit
    synth(d / "E22-2026-01-01.csv", NOMINAL * 1.01, 15, duration=10.0)  # no date but in its name
    cat = tmp_path / "units.csv"
    cat.write_text(
        "file,unit,speed_m_s,date,nominal_pitch_m\n"
        "good*.csv,U1,0.5,,0.133333\n"  # glob; no date: ...
        "good1.csv,U1,0.5,2025-01-01,\n"  # ... except the exact line wins for good1
        "noise.csv,U2,0.5,2025-01-01,0.133333\n"
        "garbage.csv,U2,0.5,2025-01-01,\n"
        "missing.csv,U3,0.5,2025-01-01,0.1016\n"
        "E22-*.csv,E22,0.5,,0.133333\n"
    )
    db = tmp_path / "f.sqlite"
    # some files failed, others stored: the documented exit code 3, and a summary line
    assert main(["fleet", "scan", str(d), "--catalogue", str(cat), "--db", str(db), "--workers", "0", "--json"]) == 3
    out, err = capsys.readouterr()
    s = json.loads(out)
    assert s["schema"] == "vibkit.fleet.scan/1"
    assert (s["added"], s["skipped_duplicates"], s["failed"]) == (2, 0, 5)
    with FleetDB(db) as fdb:
        (m,) = fdb.measurements("E22")
    assert m.date_utc == "2026-01-01T00:00:00Z" and m.date_source == "file name"
    assert "vibkit fleet scan: 2 added (0 flagged), 0 already stored, 5 failed" in err
    failed = {Path(r["file"]).name: r["reason"] for r in s["failed_files"]}
    assert set(failed) == {"good2.csv", "noise.csv", "garbage.csv", "stray.csv", "missing.csv"}
    assert "no start time" in failed["good2.csv"] and "--date" in failed["good2.csv"]
    assert "no link-pass found" in failed["noise.csv"]
    assert "unknown unit" in failed["stray.csv"]
    assert "file not found (catalogue line 6)" in failed["missing.csv"]
    lines = [ln for ln in err.splitlines() if ln.startswith("vibkit fleet scan: failed:")]
    assert len(lines) == 5 and "Traceback" not in err
    # all failed: exit 1
    cat2 = tmp_path / "bad.csv"
    cat2.write_text("file,unit,speed_m_s,date,nominal_pitch_m\nnoise.csv,U2,0.5,2025-01-01,0.133333\n")
    d2 = tmp_path / "only-noise"
    d2.mkdir()
    (d2 / "noise.csv").write_bytes((d / "noise.csv").read_bytes())
    assert main(["fleet", "scan", str(d2), "--catalogue", str(cat2), "--db", str(db), "--workers", "0"]) == 1
    assert "nothing added" in capsys.readouterr().err


def test_scan_named_file_any_suffix_and_repeated_line(tmp_path):
    d = tmp_path / "visits"
    (d / "E9").mkdir(parents=True)
    synth(d / "E9" / "visit.log.bak", NOMINAL * 1.01, 21, duration=10.0)  # not a recording suffix: named exactly
    synth(d / "E9" / "other.csv", NOMINAL * 1.01, 22, duration=10.0)
    cat = tmp_path / "units.csv"
    cat.write_text(
        "file,unit,speed_m_s,date,nominal_pitch_m\n"
        "./E9/visit.log.bak,E9,0.5,2025-01-01,0.133333\n"
        "E9/other.csv,E9,0.5,2025-02-01,\n"
        "other.csv,E9,0.5,2025-03-01,\n"
    )  # the same file again (by its base name)
    with FleetDB(tmp_path / "f.sqlite") as db:
        res = db.scan(d, cat, parallel=False)
        assert len(res.added) == 2 and not res.failed and not res.skipped
        assert res.notes == ["catalogue line 4: 'other.csv' is also on line 3, which is used"]
        assert [m.date_utc[:10] for m in db.measurements("E9")] == ["2025-01-01", "2025-02-01"]


@pytest.mark.parametrize(
    "text, match",
    [
        ("file,unit,speed_m_s,date\nx.csv,U,0.5,\n", r"line 1: missing column\(s\) nominal_pitch_m"),
        ("# comment\nfile,unit,speed_m_s,date,nominal_pitch_m,colour\n", r"line 2: unknown column\(s\) 'colour'"),
        (
            "file,unit,speed_m_s,date,nominal_pitch_m\na.csv,U,0.5,,0.1333\nb.csv,U,0.5\n",
            r"line 3: 3 cell\(s\), expected 5",
        ),
        (
            "file,unit,speed_m_s,date,nominal_pitch_m\na.csv,U,fast,,0.1333\n",
            "line 2: column speed_m_s: expected a number",
        ),
        ("file,unit,speed_m_s,date,nominal_pitch_m\na.csv,U,0.5,,133.33\n", "line 2: .*not 133.33"),
        ("file,unit,speed_m_s,date,nominal_pitch_m\na.csv,U,0.5,tomorrow,\n", "line 2: date 'tomorrow'"),
        (
            "file,unit,speed_m_s,date,nominal_pitch_m\na.csv,U,0.5,,0.1333\nb.csv,U,0.5,,0.1016\n",
            "line 3: unit 'U' has nominal_pitch_m 0.1016 here but 0.1333 on line 2",
        ),
        ("file,unit,speed_m_s,date,nominal_pitch_m\n/etc/passwd,U,0.5,,0.1333\n", "relative to the scanned folder"),
    ],
)
def test_catalogue_rejected_with_line(tmp_path, text, match):
    cat = tmp_path / "units.csv"
    cat.write_text(text)
    with pytest.raises(FleetError, match=match):
        read_catalogue(cat)


def test_catalogue_optional_columns_and_semicolons(tmp_path):
    cat = tmp_path / "units.csv"
    cat.write_text(
        "File;Unit;Speed_m_s;Date;Nominal_pitch_m;speed_sigma_m_s;channel\na.csv;U;0.5;2025-01-01;0.1333;0.0005;accel\n"
    )
    (r,) = read_catalogue(cat)
    assert (r.file, r.unit, r.speed_m_s, r.speed_sigma_m_s, r.nominal_pitch_m, r.channel) == (
        "a.csv",
        "U",
        0.5,
        0.0005,
        0.1333,
        "accel",
    )
    assert r.date == "2025-01-01T00:00:00Z"


def test_catalogue_takes_unit_speed_and_pitch_from_an_escalator_profile(tmp_path):
    """An escalator column names the unit's profile: the empty cells (and absent columns) are the profile's;
    a cell given wins; the profile's stated speed uncertainty, else the standard's tolerance (2.9 %)."""
    profile = (ROOT / "data" / "fleet-example" / "escalators" / "E07.toml").read_text()
    (tmp_path / "E07.toml").write_text(profile)
    (tmp_path / "rated.toml").write_text(profile.replace("speed_uncertainty", "# speed_uncertainty"))
    cat = tmp_path / "units.csv"
    cat.write_text("file,date,escalator,speed_m_s\na.csv,,E07.toml,\nb.csv,,E07.toml,0.49\nc.csv,,rated.toml,\n")
    a, b, c = read_catalogue(cat)
    assert (a.unit, a.speed_m_s, a.speed_sigma_m_s, a.nominal_pitch_m) == ("E07", 0.5, pytest.approx(0.0005), 0.13333)
    assert b.speed_m_s == 0.49
    assert c.speed_sigma_m_s == pytest.approx(0.05 / math.sqrt(3) * 0.5)
    cat.write_text("file,date,escalator\na.csv,,missing.toml\n")
    with pytest.raises(FleetError, match="line 2: column escalator: .*missing.toml"):
        read_catalogue(cat)


def test_database_location_and_refusals(tmp_path, monkeypatch, capsys):
    monkeypatch.chdir(tmp_path)
    monkeypatch.delenv("VIBKIT_FLEET_DB", raising=False)
    assert resolve_db_path() == "vibkit-fleet.sqlite"
    monkeypatch.setenv("VIBKIT_FLEET_DB", str(tmp_path / "env.sqlite"))
    assert resolve_db_path() == str(tmp_path / "env.sqlite")
    assert resolve_db_path("sqlite:///rel/f.sqlite") == "rel/f.sqlite"
    assert resolve_db_path("sqlite:////abs/f.sqlite") == "/abs/f.sqlite"
    assert resolve_db_path("postgresql://tech@fleet.example/fleet") == "postgresql://tech@fleet.example/fleet"
    for url, match in (("mysql://host/db", "scheme 'mysql' is not supported"), ("sqlite://", "sqlite:///path")):
        with pytest.raises(FleetError, match=match):
            resolve_db_path(url)
    # status without a database: an error, and nothing created
    assert main(["fleet", "status"]) == 1
    assert "no fleet database" in capsys.readouterr().err and not (tmp_path / "env.sqlite").exists()
    # a file that is not a database, and another application's SQLite database: refused, untouched
    notdb = tmp_path / "notes.csv"
    notdb.write_text("a,b\n1,2\n")
    with pytest.raises(FleetError, match="not a SQLite database"):
        FleetDB(notdb)
    other = tmp_path / "other.sqlite"
    con = sqlite3.connect(other)
    con.execute("CREATE TABLE invoices (n INTEGER)")
    con.commit()
    con.close()
    with pytest.raises(FleetError, match="another application .*invoices"):
        FleetDB(other)
    assert main(["fleet", "status", "--db", f"sqlite:///{other}"]) == 1
    assert notdb.read_text() == "a,b\n1,2\n"


def test_cli_status_json_and_report(fleet, tmp_path, capsys):
    db = str(fleet["db"])
    assert main(["fleet", "status", "--db", db, "--json"]) == 0
    d = json.loads(capsys.readouterr().out)
    assert d["schema"] == "vibkit.fleet.status/1" and d["limits_percent"] == [1.5, 2.0, 3.0]
    assert [u["unit"] for u in d["units"]] == ["E-worn", "E-fast", "E-slow", "E-flat"]
    u = d["units"][1]
    assert {
        "slope_percent_per_year",
        "slope_sigma_percent_per_year",
        "latest_elongation_percent",
        "latest_elongation_sigma_percent",
        "forecasts",
        "rank",
    } <= set(u)
    assert u["forecasts"][0]["limit_percent"] == 1.5 and u["forecasts"][0]["status"] == "forecast"
    assert main(["fleet", "status", "--db", db]) == 0
    out = capsys.readouterr().out
    assert out.splitlines()[2].split()[:2] == ["1", "E-worn"] and "reached" in out
    pdf = tmp_path / "fleet.pdf"
    assert main(["fleet", "report", "--db", db, "-o", str(pdf), "--json"]) == 0
    r = json.loads(capsys.readouterr().out)
    assert r["units_drawn"] == 4 and pdf.read_bytes()[:5] == b"%PDF-"
    before = pdf.read_bytes()
    assert main(["fleet", "report", "--db", db, "-o", str(pdf)]) == 1
    assert "--force" in capsys.readouterr().err and pdf.read_bytes() == before
    assert main(["fleet", "report", "--db", db, "-o", str(pdf), "--force"]) == 0
    assert [p.name for p in tmp_path.iterdir() if p.name.startswith(".tmp")] == []


def test_fleet_page_draws_units_and_limits(fleet, tmp_path, monkeypatch):
    from vibkit.diagnose.report import write_fleet_report

    with FleetDB(fleet["db"], create=False) as db:
        trends, meas = db.status(), db.measurements()
    monkeypatch.delenv("SOURCE_DATE_EPOCH", raising=False)
    rep = write_fleet_report(trends[:3], meas, tmp_path / "p.pdf", database="fleet.sqlite", max_units=2)
    (t1, work), (t2, units) = rep.pages
    assert (t1, t2) == ("work list", "fleet units")
    # page 1: the work list, every unit, ranked, with the next limit and its interval
    for row, unit in enumerate(["E-worn", "E-fast", "E-slow"]):
        i = work.index(unit)
        assert work[i - 1] == str(row + 1)
    assert "3 %" in work and "reached on (2-sigma)" in work
    joined = " ".join(units)
    assert "#1 E-worn" in joined and "OVER 2 %" in joined and "#2 E-fast" in joined and "E-slow" not in joined
    assert "1 less urgent unit(s) not drawn" in joined and "1.5 %\nwatch" in joined and "3 %\nreplace" in joined
    assert "measurement (1 sigma)" in joined and "(2-sigma" in joined  # the legend names the interval drawn
    # the report's date is today's, unless SOURCE_DATE_EPOCH asks for reproducible bytes
    assert dt.datetime.now(dt.timezone.utc).strftime("%Y-%m-%d") in " ".join(work)
    monkeypatch.setenv("SOURCE_DATE_EPOCH", "1767225600")
    a = write_fleet_report(trends, meas, tmp_path / "a.pdf").path
    b = write_fleet_report(trends, meas, tmp_path / "b.pdf").path
    assert Path(a).read_bytes() == Path(b).read_bytes()


def _overlaps(fig):
    """Pairs of texts (figure texts, panel titles, limit labels, legends, tick labels) whose boxes overlap."""
    fig.canvas.draw()
    r = fig.canvas.get_renderer()
    boxes = [(f"fig:{t.get_text()[:30]}", t.get_window_extent(r)) for t in fig.texts if t.get_text()]
    for k, ax in enumerate(fig.axes):
        ticks = []
        for axis, (lo, hi) in ((ax.xaxis, ax.get_xlim()), (ax.yaxis, ax.get_ylim())):
            ticks += [t.label1 for t in axis.get_major_ticks() if min(lo, hi) <= t.get_loc() <= max(lo, hi)]
        items = [ax.title, ax._left_title, *ax.texts, *ticks, ax.yaxis.label]
        boxes += [
            (f"ax{k}:{t.get_text()[:30]}", t.get_window_extent(r)) for t in items if t.get_text() and t.get_visible()
        ]
        if ax.get_legend() is not None:
            boxes.append((f"ax{k}:legend", ax.get_legend().get_window_extent(r)))
    fig_box = fig.bbox
    out = [
        name
        for name, b in boxes
        if b.x0 < fig_box.x0 - 1 or b.x1 > fig_box.x1 + 1 or b.y0 < fig_box.y0 - 1 or b.y1 > fig_box.y1 + 1
    ]
    for i in range(len(boxes)):
        for j in range(i + 1, len(boxes)):
            (na, a), (nb, b) = boxes[i], boxes[j]
            if a.width and b.width and a.overlaps(b):
                out.append((na, nb))
    return out


def test_fleet_pages_have_no_overlapping_text(fleet):
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    from vibkit.diagnose.report.fleet import FleetContext, fleet_page

    with FleetDB(fleet["db"], create=False) as db:
        trends, meas = db.status(), db.measurements()
    by_unit = {}
    for m in meas:
        by_unit.setdefault(m.unit, []).append(m)
    found = []

    class Doc:
        def emit(self, fig, title):
            found.extend((title, o) for o in _overlaps(fig))
            plt.close(fig)

    ctx = FleetContext(
        trends,
        trends,
        meas,
        by_unit,
        (1.5, 2.0, 3.0),
        "fleet.sqlite",
        dt.datetime(2026, 11, 23, tzinfo=dt.timezone.utc),
    )
    with matplotlib.rc_context({"font.size": 7, "axes.titlesize": 8}):
        fleet_page(Doc(), ctx)
    assert found == [], found


def test_work_list_cells_hold_their_text(fleet):
    """A unit with long flags: every cell's text ends inside its cell (the flags cut short with '...')."""
    import dataclasses

    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    from vibkit.diagnose.report.fleet import WORK_LIST_FLAGS_WIDTH, FleetContext, work_list_page, work_list_rows

    with FleetDB(fleet["db"], create=False) as db:
        trends, meas = db.status(), db.measurements()
    long = ("no usable measurement: the latest reading was flagged by the operator as taken at another speed",)
    trends = [dataclasses.replace(trends[0], flags=long * 2), *trends[1:]]
    ctx = FleetContext(
        trends, trends, meas, {}, (1.5, 2.0, 3.0), "fleet.sqlite", dt.datetime(2026, 11, 23, tzinfo=dt.timezone.utc)
    )
    found = []

    class Doc:
        def emit(self, fig, title):
            fig.canvas.draw()
            r = fig.canvas.get_renderer()
            (table,) = fig.axes[0].tables
            for (row, col), cell in table.get_celld().items():
                text, box = cell.get_text(), cell.get_window_extent(r)
                if text.get_text() and text.get_window_extent(r).x1 > box.x1 + 0.5:
                    found.append((row, col, text.get_text()))
            plt.close(fig)

    rows = work_list_rows(trends, flags_width=None)
    assert len(rows[0][-1]) > 150  # the flags as status prints them
    work_list_page(Doc(), ctx, work_list_rows(trends, flags_width=WORK_LIST_FLAGS_WIDTH), 1, 1)
    assert found == [], found


def test_cli_add_replaced_starts_a_segment(tmp_path, capsys):
    db = str(tmp_path / "f.sqlite")
    rates = [(0, 1.6), (1, 1.9), (2, 0.2)]  # (years, elongation %): the third after a replacement
    for k, (y, e) in enumerate(rates):
        rec = synth(tmp_path / f"v{k}.csv", NOMINAL * (1 + e / 100), 300 + k, duration=10.0)
        args = [
            "fleet",
            "add",
            str(rec),
            "--unit",
            "R1",
            "--speed",
            "0.5",
            "--nominal-pitch",
            str(NOMINAL),
            "--date",
            (T0 + dt.timedelta(days=365 * y)).date().isoformat(),
            "--db",
            db,
        ]
        assert main(args + (["--replaced"] if k == 2 else [])) == 0
        cap = capsys.readouterr()
        # the stored line's SNR is the harmonics' over the residual's, said once under it (not a peak over the floor)
        assert "(harmonic SNR " in cap.out
        assert "harmonic SNR: the fitted link-pass harmonics' power over the rest" in cap.err
    assert main(["fleet", "status", "--db", db, "--json"]) == 0
    (u,) = json.loads(capsys.readouterr().out)["units"]
    assert len(u["replacements"]) == 1 and "given" in u["replacements"][0]["reason"]
    assert u["n_used"] == 1 and u["slope_percent_per_year"] is None and u["over_limit_percent"] is None
    assert u["latest_elongation_percent"] == pytest.approx(0.2, abs=4 * u["latest_elongation_sigma_percent"])
    with FleetDB(db) as fdb:
        assert [m.replaced for m in fdb.measurements("R1")] == [False, False, True]
    assert main(["fleet", "status", "--db", db]) == 0
    out = capsys.readouterr().out
    assert "chain replaced" in out and "R1" in out


# vibkit.runtime.cluster's local scheduler binds its HTTP server to port 8787 by default (dashboard off): where
# another cluster holds the port, distributed warns and leaks the socket of its first try
@pytest.mark.slow
@pytest.mark.filterwarnings("ignore:Port 8787 is already in use:UserWarning")
@pytest.mark.filterwarnings("ignore::ResourceWarning")
@pytest.mark.filterwarnings("ignore::pytest.PytestUnraisableExceptionWarning")
def test_scan_on_dask_gives_the_plain_loop_numbers(fleet, tmp_path, capsys, monkeypatch):
    cat = tmp_path / "units.csv"
    cat.write_text(f"file,unit,speed_m_s,date,nominal_pitch_m\nE-fast_[0-2].csv,E-fast,{SPEED},2024-01-01,{NOMINAL}\n")
    db = tmp_path / "dask.sqlite"
    # a cluster's start-up that costs nothing: the scan hands the files left after the first two to 2 workers
    monkeypatch.setattr(cluster, "LOCAL_CLUSTER_START_S", 0.0)
    assert (
        main(["fleet", "scan", str(fleet["dir"]), "--catalogue", str(cat), "--db", str(db), "--workers", "2", "--json"])
        == 3
    )  # the other units' files failed
    out, err = capsys.readouterr()
    s = json.loads(out)
    assert (s["added"], s["skipped_duplicates"]) == (3, 0)
    assert s["failed"] == 21  # the other units' files: no catalogue line
    assert all("unknown unit" in r["reason"] for r in s["failed_files"])
    with FleetDB(db) as a, FleetDB(fleet["db"]) as b:
        got = {m.sha256: m.pitch_m for m in a.measurements()}
        ref = {m.sha256: m.pitch_m for m in b.measurements("E-fast")}
    assert got and all(got[k] == ref[k] for k in got)  # bit for bit


@pytest.mark.slow
def test_killed_scan_leaves_complete_rows(tmp_path):
    d = tmp_path / "visits"
    d.mkdir()
    n = 80  # a scan in the process stores its first batch after a second of analyses: many more are left then
    rows = ["file,unit,speed_m_s,date,nominal_pitch_m"]
    for i in range(n):
        synth(d / f"r{i:02d}.csv", NOMINAL * (1 + 0.0002 * i), 1000 + i, duration=10.0)
        rows.append(f"r{i:02d}.csv,U{i % 4},{SPEED},{(T0 + dt.timedelta(days=15 * i)).date()},{NOMINAL}")  # all past
    cat = tmp_path / "units.csv"
    cat.write_text("\n".join(rows) + "\n")
    db = tmp_path / "f.sqlite"
    env = dict(os.environ, PYTHONPATH=str(ROOT))
    proc = subprocess.Popen(
        [
            sys.executable,
            "-m",
            "vibkit",
            "fleet",
            "scan",
            str(d),
            "--catalogue",
            str(cat),
            "--db",
            str(db),
            "--workers",
            "1",
        ],
        stdout=subprocess.DEVNULL,
        stderr=subprocess.DEVNULL,
        env=env,
        start_new_session=True,
    )
    stored = 0
    try:
        deadline = time.monotonic() + 240
        while time.monotonic() < deadline and proc.poll() is None:
            if db.exists():
                try:
                    con = sqlite3.connect(f"file:{db}?mode=ro", uri=True, timeout=1)
                    stored = con.execute("SELECT count(*) FROM measurement").fetchone()[0]
                    con.close()
                except sqlite3.Error:
                    stored = 0
                if stored >= 3:
                    break
            time.sleep(0.02)
    finally:
        if proc.poll() is None:
            os.killpg(proc.pid, signal.SIGKILL)  # the scan and its Dask workers: its own session
        proc.wait(timeout=60)
    assert proc.returncode == -signal.SIGKILL, "the scan ended before it could be killed"
    with FleetDB(db) as fdb:
        assert fdb.integrity_check() == "ok"
        ms = fdb.measurements()
        assert 3 <= len(ms) < n
        for m in ms:  # every row complete and true to its file
            # the catalogue states no speed uncertainty: stored as not stated (None), every other column written
            assert all(
                getattr(m, c) is not None for c in m.__dataclass_fields__ if c not in ("snr_db", "speed_sigma_m_s")
            )
            assert (
                m.speed_sigma_m_s is None
                and len(m.sha256) == 64
                and m.elongation_sigma_percent > 0
                and m.unit.startswith("U")
            )
            import hashlib

            assert hashlib.sha256(Path(m.path).read_bytes()).hexdigest() == m.sha256
        res = fdb.scan(d, cat, parallel=False)
        assert len(res.skipped) == len(ms) and len(res.added) == n - len(ms) and not res.failed
        all_rows = fdb.measurements()
        assert len(all_rows) == n == len({m.sha256 for m in all_rows})


def test_history_name_keeps_the_public_names():
    import vibkit.fleet as fleet
    import vibkit.fleet.history as history

    assert history.__all__ == fleet.__all__
    for name in fleet.__all__ + [
        "SECONDS_PER_YEAR",
        "CATALOGUE_OPTIONAL",
        "RECORDING_SUFFIXES",
        "SCHEMA_VERSION",
        "APPLICATION_ID",
        "unit_trend",
        "rank_units",
    ]:
        assert hasattr(history, name), name
    for name in fleet.__all__:
        assert getattr(history, name) is getattr(fleet, name)


@pytest.mark.parametrize("sub", [[], ["add"], ["scan"], ["status"], ["report"], ["migrate"]])
def test_fleet_help_pages(sub, capsys):
    with pytest.raises(SystemExit) as ei:
        main(["fleet", *sub, "--help"])
    assert ei.value.code == 0 and "usage: vibkit fleet" in capsys.readouterr().out


def test_migrate_from_a_missing_database_names_its_own_flag(tmp_path, run):
    rc, out, err = run("fleet", "migrate", "--from", tmp_path / "none.sqlite", "--to", tmp_path / "t.sqlite")
    assert rc == 1 and "--from names it" in err and "--db" not in err


def test_fleet_add_warns_of_a_sensor_riding_a_step(tmp_path, run):
    """E07's profile puts its sensor on a step: the visit is stored, with the warning `vibkit pitch` gives."""
    from vibkit.diagnose.pitch import STEP_WARNING

    rc, out, err = run(
        "fleet", "add", "data/fleet-example/E07/2026-11-23.csv", "--escalator",
        "data/fleet-example/escalators/E07.toml", "--db", tmp_path / "f.sqlite",
    )  # fmt: skip
    assert rc == 0 and "stored #1" in out and STEP_WARNING in " ".join(err.split())


def test_a_catalogue_of_new_visits_skips_stored_files_and_catalogues(tmp_path, capsys):
    """A stranger's second scan named only the new visit: the files stored before and the catalogues in the folder
    were 13 failures and exit 3. A file stored before is already stored; a catalogue is a note; exit 0."""
    d = tmp_path / "visits"
    d.mkdir()
    synth(d / "v1.csv", NOMINAL * 1.01, 21, duration=10.0)
    synth(d / "v2.csv", NOMINAL * 1.01, 22, duration=10.0)
    first = d / "first.csv"
    first.write_text(f"file,unit,speed_m_s,date,nominal_pitch_m\nv1.csv,U1,{SPEED},2025-01-01,{NOMINAL}\n")
    db = tmp_path / "f.sqlite"
    assert main(["fleet", "scan", str(d), "--catalogue", str(first), "--db", str(db), "--workers", "0"]) == 3
    capsys.readouterr()  # v2.csv had no line yet: a failure, as documented
    second = d / "second.csv"
    second.write_text(f"file,unit,speed_m_s,date,nominal_pitch_m\nv2.csv,U1,{SPEED},2026-01-01,{NOMINAL}\n")
    rc = main(["fleet", "scan", str(d), "--catalogue", str(second), "--db", str(db), "--workers", "0", "--json"])
    out, err = capsys.readouterr()
    s = json.loads(out)
    assert rc == 0 and (s["added"], s["skipped_duplicates"], s["failed"]) == (1, 1, 0), err
    assert "first.csv: a catalogue (columns file, unit), not a recording; not scanned" in err
