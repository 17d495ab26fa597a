"""The fleet's calendar against a fixed today: a forecast date in the past is OVERDUE in the text, the JSON and
the PDF, a "not before" date that has passed too; every unit with a trend has its forecast drawn."""

import datetime as dt
import json

import matplotlib
import pytest

from vibkit.cli import main
from vibkit.diagnose.report.fleet import fmt_forecast, write_fleet_report
from vibkit.fleet import FleetDB, Measurement

matplotlib.use("Agg")

NOMINAL = 0.13333
START = dt.datetime(2022, 3, 1, tzinfo=dt.timezone.utc)
TODAY = "1796601600"  # 2026-12-07 (SOURCE_DATE_EPOCH)
BEFORE = "1648771200"  # 2022-04-01


def _m(i, years, e, s, unit="E12"):
    t = START.timestamp() + years * 365.25 * 86400
    return Measurement(
        id=None,
        unit=unit,
        date_utc=dt.datetime.fromtimestamp(t, dt.timezone.utc).strftime("%Y-%m-%dT%H:%M:%SZ"),
        date_unix_s=t,
        date_source="given",
        speed_m_s=0.5,
        speed_sigma_m_s=0.001,
        nominal_pitch_m=NOMINAL,
        channel="a",
        fundamental_hz=3.75,
        fundamental_sigma_hz=1e-3,
        pitch_m=NOMINAL * (1 + e / 100),
        pitch_sigma_m=NOMINAL * s / 100,
        elongation_percent=e,
        elongation_sigma_percent=s,
        snr_db=20.0,
        warnings=(),
        sha256=f"{int(unit[1:]):04x}{i:060x}",
        path=f"/{unit}-{i}.csv",
        size_bytes=1,
        vibkit_version="t",
        analysed_utc="2026-01-01T00:00:00Z",
        quality="ok",
        quality_reason="",
        replaced=False,
    )


@pytest.fixture()
def fleet(tmp_path):
    """E12: 0.2 %/year +- 0.3 from 1.0 % (the 1.5 % limit 'not before' 2022-05, long past on 2026-12-07);
    E21: 1 %/year from 1.0 % (the 3 % limit forecast for 2024-03, past too)."""
    ms = [_m(i, y, e, 0.3) for i, (y, e) in enumerate([(0.0, 1.0), (0.25, 1.2), (0.5, 0.9), (0.75, 1.15)])]
    ms += [_m(i, y, 1.0 + y, 0.05, unit="E21") for i, y in enumerate((0.0, 0.5, 1.0, 1.5))]
    db = str(tmp_path / "f.sqlite")
    with FleetDB(db) as f:
        f.insert_many(ms)
    return db


def test_a_not_before_date_that_has_passed_is_overdue_in_text_and_json(fleet, capsys, monkeypatch):
    monkeypatch.setenv("SOURCE_DATE_EPOCH", TODAY)
    assert main(["fleet", "status", "--db", fleet, "--json"]) == 0
    units = {u["unit"]: u for u in json.loads(capsys.readouterr().out)["units"]}
    e12 = units["E12"]["next_limit"]
    assert e12["status"] == "not before" and e12["earliest_utc"] < "2026-12-07"
    assert e12["overdue"] and units["E12"]["overdue"] and units["E21"]["overdue"]
    assert main(["fleet", "status", "--db", fleet]) == 0
    out = capsys.readouterr()
    rows = {ln.split()[1]: ln for ln in out.out.splitlines() if ln.split()[1:2] in (["E12"], ["E21"])}
    assert f"OVERDUE not before {e12['earliest_utc'][:7]}" in rows["E12"]
    assert "OVERDUE 2024-" in rows["E21"]
    assert "OVERDUE" in out.err  # what it means, said once
    # before those dates nothing is overdue
    monkeypatch.setenv("SOURCE_DATE_EPOCH", BEFORE)
    assert main(["fleet", "status", "--db", fleet, "--json"]) == 0
    assert not any(u["overdue"] for u in json.loads(capsys.readouterr().out)["units"])


def test_the_pdf_says_overdue_and_draws_every_units_forecast(fleet, tmp_path, monkeypatch):
    monkeypatch.setenv("SOURCE_DATE_EPOCH", TODAY)
    drawn = {}
    import vibkit.diagnose.report.fleet as fleet_report

    orig = fleet_report._draw_unit

    def spy(ax, tr, ms, limits, ctx):
        orig(ax, tr, ms, limits, ctx)
        drawn[tr.unit] = [h.get_label() for h in ax.get_legend_handles_labels()[0]]

    monkeypatch.setattr(fleet_report, "_draw_unit", spy)
    with FleetDB(fleet) as db:
        trends = db.status()
        ms = db.measurements()
    rep = write_fleet_report(trends, ms, tmp_path / "fleet.pdf")
    text = "\n".join(t for _, texts in rep.pages for t in texts)
    today = dt.datetime(2026, 12, 7, tzinfo=dt.timezone.utc).timestamp()
    e12 = next(t for t in trends if t.unit == "E12").next_limit()
    assert fmt_forecast(e12, today).startswith("OVERDUE not before ")
    assert fmt_forecast(e12, today) in text  # the work list
    assert "E12" in text and "OVERDUE: 1.5 % not before" in text  # the unit's panel title
    assert any(lab.startswith("1.5 % reached not before") for lab in drawn["E12"])  # its forecast drawn
    assert any(lab.startswith("3 % reached 2024-") for lab in drawn["E21"])


def test_a_failed_visit_says_what_to_do():
    from vibkit.diagnose.report.fleet_links import scan_advice
    from vibkit.fleet.links import LinkScan

    failed = LinkScan("failed", reason="the chain of 408 links does not close on its guide", n_links=408)
    advice = scan_advice(failed)
    assert "elongation is stored" in advice and "chain.n_links" in advice and "vibkit links" in advice
    assert "two loops" in scan_advice(LinkScan("too few loops", reason="1.2 loops", n_links=408))
