"""The fleet report's links pages and ``fleet add``'s link scan: the PDF names the flagged links of each unit's
latest visit, which marked link came back worse or is new, and why a unit has no scan; ``fleet add`` scans the
links as ``fleet scan`` does where it knows the number of links, and stores "not run" with the reason where not."""

from __future__ import annotations

import json

import pytest
from fleet.test_fleet_links import ROOT, _scan, _two_visits

from vibkit.cli import main
from vibkit.diagnose.report import write_fleet_report
from vibkit.fleet import FleetDB
from vibkit.fleet.link_scan import NO_LINK_COUNT_ADD
from vibkit.fleet.links import LinkScan

from support.fleet import fake


def _report_texts(db_path, out):
    """Every text of the links pages of the fleet report of ``db_path``, one string per page."""
    with FleetDB(db_path, readonly=True) as db:
        trends, meas = db.status(), db.measurements()
        links = {t.unit: db.links_history(t.unit) for t in trends}
    rep = write_fleet_report(trends, meas, out, links=links)
    return [" | ".join(texts) for title, texts in rep.pages if title == "fleet links"], rep


def test_report_names_the_worse_and_the_new_link_and_why_others_are_not_scanned(tmp_path):
    p = _two_visits(tmp_path / "f.sqlite", [(12, 0.4, 0.05), (70, 0.6, 0.05)], [(12, 0.9, 0.05), (40, 0.3, 0.05)])
    with FleetDB(p) as db:  # E12: a visit never scanned, with its reason
        db.insert(
            fake(3, "E12", 0.0, 1.0), LinkScan.not_run("channel accel: a step accelerometer gives no link number")
        )
    (page,), rep = _report_texts(p, tmp_path / "fleet.pdf")
    assert [t for t, _ in rep.pages][-1] == "fleet links"
    rows = page.split(" | ")
    # link 12 grew 0.4 -> 0.9 mm (+0.500 +- 0.071 mm, to two digits of its sigma): worse, with its excess now, its
    # sigma and its loops
    i = rows.index("12")
    assert rows[i : i + 5] == [
        "12",
        "worse",
        "+0.900 +- 0.050",
        "1,2,3",
        "+0.400 mm on 2023-01-15 -> +0.900 mm: +0.500 +- 0.071 mm",
    ]
    j = rows.index("40")
    assert rows[j : j + 3] == ["40", "new", "+0.300 +- 0.050"]
    assert "not flagged now" in rows[rows.index("70") + 1]
    assert "E12: latest visit not run: channel accel: a step accelerometer gives no link number" in rows


def test_a_link_stored_two_high_before_0_4_5_is_the_same_link_now(tmp_path, capsys):
    """Link 12 stored as 14 by vibkit 0.4.4 (the signature's numbers were two too high then) and as 12 today is
    one link, grown 0.4 -> 0.9 mm: worse, in fleet status and on the report's links page, each saying why."""
    import dataclasses

    p = tmp_path / "f.sqlite"
    with FleetDB(p) as db:
        db.insert(dataclasses.replace(fake(1, "E07", 0.0, 1.0), vibkit_version="0.4.4"), _scan([(14, 0.4, 0.05)]))
        db.insert(fake(2, "E07", 1.0, 1.2), _scan([(12, 0.9, 0.05)], marker=3.0))
    (page,), _ = _report_texts(p, tmp_path / "fleet.pdf")
    rows = page.split(" | ")
    assert rows[rows.index("12") + 1] == "worse" and "14" not in rows
    assert "read two lower" in page.replace(" | ", " ")
    assert main(["fleet", "status", "--db", str(p), "--unit", "E07"]) == 0
    out, err = capsys.readouterr()
    assert "worse" in out and "numbers stored by vibkit 0.4.4 read two lower" in " ".join(err.split())


def test_report_says_unmarked_numbers_cannot_be_matched(tmp_path):
    p = _two_visits(tmp_path / "f.sqlite", [(12, 0.4, 0.05)], [(12, 0.9, 0.05)], markers=(None, None))
    (page,), _ = _report_texts(p, tmp_path / "fleet.pdf")
    assert "cannot be matched with another visit's" in page.replace(" | ", " ")  # the statement, wrapped
    rows = page.split(" | ")
    assert rows[rows.index("12") + 1] == "unmatched" and "worse" not in rows and "new" not in rows


def test_fleet_report_command_draws_the_links_pages(tmp_path, capsys):
    p = _two_visits(tmp_path / "f.sqlite", [(12, 0.4, 0.05)], [(12, 0.9, 0.05)])
    out = tmp_path / "fleet.pdf"
    assert main(["fleet", "report", "--db", str(p), "-o", str(out), "--json"]) == 0
    assert json.loads(capsys.readouterr().out)["pages"][-1] == "fleet links"
    assert out.read_bytes()[:5] == b"%PDF-"
    # without --json: what was written is a message (stderr); standard output carries data only
    assert main(["fleet", "report", "--db", str(p), "-o", str(out), "--force"]) == 0
    cap = capsys.readouterr()
    assert cap.out == "" and cap.err.startswith(f"vibkit fleet report: wrote {out} (")


def test_links_pages_have_no_overlapping_text_and_break_between_units(tmp_path):
    """40 units with 6 flagged links each: several pages, every block whole on its page, nothing overlapping."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    from fleet.test_fleet import _overlaps

    from vibkit.diagnose.report.fleet import FleetContext, fleet_page

    p = tmp_path / "f.sqlite"
    with FleetDB(p) as db:
        for k in range(40):
            u = f"U{k:02d}"
            db.insert(fake(2 * k + 1, u, 0.0, 1.0), _scan([(n, 0.4, 0.05) for n in range(10, 16)]))
            db.insert(fake(2 * k + 2, u, 1.0, 1.2), _scan([(n, 0.9, 0.05) for n in range(10, 16)], marker=2.0))
        trends, meas = db.status(), db.measurements()
        links = {t.unit: db.links_history(t.unit) for t in trends}
    found, pages = [], []

    class Doc:
        def emit(self, fig, title):
            if title == "fleet links":
                found.extend(_overlaps(fig))
                pages.append([t.get_text() for t in fig.texts])
            plt.close(fig)

    by_unit = {}
    for m in meas:
        by_unit.setdefault(m.unit, []).append(m)
    import datetime as dt

    ctx = FleetContext(trends, trends, meas, by_unit, (1.5, 2.0, 3.0), "f.sqlite", dt.datetime(2026, 1, 1), links)
    with matplotlib.rc_context({"font.size": 7, "axes.titlesize": 8}):
        fleet_page(Doc(), ctx)
    assert found == []
    assert len(pages) > 1
    heads = [t for pg in pages for t in pg if t.startswith("U") and ": latest link scan" in t]
    assert sorted(h[:3] for h in heads) == sorted(t.unit for t in trends)  # every unit once
    for pg in pages:  # a block is whole on its page: its head and its six worse links
        assert sum(t == "worse" for t in pg) == 6 * sum(": latest link scan" in t for t in pg)


# ------------------------------------------------------------------------------------------ fleet add
def test_fleet_add_of_a_tensioner_recording_stores_an_ok_scan(tmp_path, capsys):
    """A constructed tensioner recording (40 links, 2.2 loops) whose link 12 deviates: fleet add --links scans it
    as fleet scan does and stores link 12, numbered from the marked link."""
    from cli.test_links_cli import _recording

    rec = _recording(tmp_path / "E30-2026-01-10.nc", 40, 2.2, bump_link=12, bump=2e-7, seed=1)
    db = tmp_path / "f.sqlite"
    args = ["fleet", "add", str(rec), "--unit", "E30", "--speed", "0.5", "--speed-uncertainty", "0.0005"]
    args += ["--nominal-pitch", "0.13333", "--date", "2026-01-10", "--db", str(db), "--links", "40", "--marker", "0.1"]
    assert main(args + ["--json"]) == 0
    d = json.loads(capsys.readouterr().out)["link_scan"]
    assert (d["status"], [f["link"] for f in d["flagged"]], d["numbering"], d["n_links"]) == ("ok", [12], "marker", 40)
    with FleetDB(db, readonly=True) as fdb:
        (m,) = fdb.measurements()
        scan = fdb.link_scans("E30")[m.id]
    assert scan.status == "ok" and [f.link for f in scan.flagged] == [12] and scan.marker_s == pytest.approx(0.1)


def test_fleet_add_without_a_number_of_links_stores_not_run_with_the_reason(tmp_path, capsys):
    from cli.test_links_cli import _recording

    db = tmp_path / "f.sqlite"
    rec = _recording(tmp_path / "tensioner.nc", 40, 2.2, seed=4)  # a tensioner: the count is what is missing
    args = ["fleet", "add", str(rec), "--unit", "E40", "--speed", "0.5", "--speed-uncertainty", "0.1%"]
    assert main(args + ["--nominal-pitch", "0.13333", "--date", "2026-01-01", "--db", str(db)]) == 0
    assert f"links: not run: {NO_LINK_COUNT_ADD}" in capsys.readouterr().out
    rec = ROOT / "data/fleet-example/E07/2026-11-23.csv"  # a step: the step is what stops it, with or without a count
    args = ["fleet", "add", str(rec), "--unit", "E07", "--speed", "0.5", "--speed-uncertainty", "0.1%"]
    assert main(args + ["--nominal-pitch", "0.13333", "--db", str(db)]) == 0
    assert "links: not run: channel" in capsys.readouterr().out
    # the profile gives 159 links, but a step accelerometer gives no link number: not run, saying so
    rec = ROOT / "data/fleet-example/E07/2025-11-19.csv"
    prof = ROOT / "data/fleet-example/escalators/E07.toml"
    assert main(["fleet", "add", str(rec), "--escalator", str(prof), "--db", str(db)]) == 0
    capsys.readouterr()
    with FleetDB(db, readonly=True) as fdb:
        scans = [fdb.link_scans("E07")[m.id] for m in fdb.measurements("E07")]
    assert [(s.status, s.n_links) for s in scans] == [("not run", 159), ("not run", None)]  # by date
    assert "step accelerometer" in scans[0].reason and "step accelerometer" in scans[1].reason


def test_fleet_add_refuses_a_unit_its_profile_contradicts(tmp_path, capsys):
    """A stranger stored a visit with --escalator ES-101's profile under --unit ES-999 without a word: a trend that
    is not the unit's. The contradiction is refused, as --links against the profile's count is."""
    rec = ROOT / "data/fleet-example/E07/2026-11-23.csv"
    prof = ROOT / "data/fleet-example/escalators/E07.toml"
    args = ["fleet", "add", str(rec), "--escalator", str(prof), "--unit", "E99", "--db", str(tmp_path / "f.sqlite")]
    assert main(args) == 1
    assert "--unit E99 contradicts the escalator profile" in capsys.readouterr().err


def test_fleet_add_takes_the_speed_the_file_states(tmp_path, capsys):
    """A stranger's `fleet add` asked for --speed of files that state it (Leon's chain_speed_m_s), which `pitch`
    and `report` take: it takes it too, and says so."""
    db = tmp_path / "f.sqlite"
    rec = ROOT / "data/field/leon-tensioner.csv"
    args = ["fleet", "add", str(rec), "--unit", "LEON", "--nominal-pitch", "133.33mm", "--date", "2020-02-14"]
    assert main(args + ["--db", str(db)]) == 0
    assert "note: speed 0.49 m/s from the chain_speed_m_s of" in capsys.readouterr().err
    with FleetDB(db, readonly=True) as fdb:
        (m,) = fdb.measurements("LEON")
    assert m.speed_m_s == 0.49
