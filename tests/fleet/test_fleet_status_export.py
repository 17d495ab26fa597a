"""``vibkit fleet status --format csv|json|table`` and ``--alert LIMIT``: the work list for a spreadsheet
or a CMMS (CSV that pandas reads back equal to the JSON), and the exit status a scheduled job acts on
(4 when a listed unit's latest elongation has reached the limit named, 0 otherwise)."""

from __future__ import annotations

import io
import json
import math

import pandas as pd
import pytest

from vibkit.cli import main
from vibkit.cli.fleet import STATUS_PAST_LIMIT
from vibkit.fleet import FleetDB
from vibkit.fleet.export import RECORD_COLUMNS

from support.fleet import fake

# (unit, [(years, elongation %)]): with --limits 1.5,2,3 U-replace is past replace, U-plan past plan only,
# U-ok under watch; U-one has one visit
UNITS = {
    "U-replace": [(0.0, 2.6), (0.5, 2.8), (1.0, 3.1), (1.5, 3.3)],
    "U-plan": [(0.0, 1.7), (0.5, 1.9), (1.0, 2.1), (1.5, 2.2)],
    "U-ok": [(0.0, 0.2), (0.5, 0.3), (1.0, 0.4), (1.5, 0.5)],
    "U-one": [(1.5, 0.9)],
}


@pytest.fixture(scope="module")
def db(tmp_path_factory):
    path = tmp_path_factory.mktemp("status") / "fleet.sqlite"
    i = 0
    with FleetDB(path) as f:
        for unit, visits in UNITS.items():
            for years, e in visits:
                f.insert(fake(i + 1, unit, years, e))  # i + 1: every 5th visit without an SNR, as in the field
                i += 1
    return str(path)


def _run(capsys, *args):
    code = main(["fleet", "status", "--db", *args])
    out = capsys.readouterr()
    return code, out.out, out.err


def test_csv_reads_back_equal_to_the_json(db, capsys, monkeypatch):
    monkeypatch.setenv("SOURCE_DATE_EPOCH", "1800000000")  # the same 'today' for both outputs
    code, text, _ = _run(capsys, db, "--format", "csv")
    assert code == 0
    code, js, _ = _run(capsys, db, "--json")
    assert code == 0
    units = json.loads(js)["units"]
    got = pd.read_csv(io.StringIO(text))
    assert list(got.columns) == list(RECORD_COLUMNS)
    assert list(got["unit"]) == [u["unit"] for u in units] == ["U-replace", "U-plan", "U-ok", "U-one"]
    for row, u in zip(got.to_dict("records"), units):
        nxt = u["next_limit"] or {}
        want = {k: u.get(k) for k in RECORD_COLUMNS if k in u}
        want.update(
            next_limit_percent=nxt.get("limit_percent"),
            next_limit_status=nxt.get("status"),
            next_limit_date_utc=nxt.get("date_utc"),
            next_limit_earliest_utc=nxt.get("earliest_utc"),
            next_limit_latest_utc=nxt.get("latest_utc"),
            overdue=u["overdue"],
            flags="; ".join(u["flags"]),
            links_statement=u["links_statement"],
        )
        for k in RECORD_COLUMNS:
            w, g = want[k], row[k]
            if w is None or w == "":
                assert isinstance(g, float) and math.isnan(g), (u["unit"], k, g)
            elif isinstance(w, float):
                assert g == w, (u["unit"], k, g, w)  # exact: floats written in their shortest exact form
            else:
                assert g == w, (u["unit"], k, g, w)
    assert got.loc[0, "over_limit_percent"] == 3.0 and got.loc[1, "over_limit_percent"] == 2.0
    assert got["latest_elongation_percent"].tolist() == [3.3, 2.2, 0.5, 0.9]


def test_alert_exit_status(db, capsys):
    code, out, err = _run(capsys, db, "--alert", "replace")
    assert code == STATUS_PAST_LIMIT == 4
    assert "1 unit(s) at or past the replace limit (3 %): U-replace (exit status 4)" in err
    assert "U-replace" in out  # the work list is written all the same
    code, _, err = _run(capsys, db, "--alert", "plan", "--format", "csv")
    assert code == 4 and "U-replace, U-plan" in err
    code, _, err = _run(capsys, db, "--alert", "watch", "--json")
    assert code == 4 and "U-replace, U-plan" in err and "U-ok" not in err
    # under the limit, or no --alert: 0
    assert _run(capsys, db, "--alert", "watch", "--unit", "U-ok", "--unit", "U-one")[0] == 0
    assert _run(capsys, db)[0] == 0
    assert _run(capsys, db, "--alert", "replace", "--limits", "1,2,3.5")[0] == 0  # the limits given are the limits


def test_formats_and_their_conflicts(db, capsys):
    code, out, _ = _run(capsys, db, "--format", "json")
    assert code == 0 and json.loads(out)["schema"] == "vibkit.fleet.status/1"
    code, out, _ = _run(capsys, db, "--format", "table")
    assert code == 0 and out.splitlines()[2].split()[:2] == ["1", "U-replace"]
    code, out, err = _run(capsys, db, "--json", "--format", "csv")
    assert code == 2 and out == "" and "--json and --format csv" in err
    with pytest.raises(SystemExit) as exc:
        main(["fleet", "status", "--db", db, "--format", "xlsx"])
    assert exc.value.code == 2
