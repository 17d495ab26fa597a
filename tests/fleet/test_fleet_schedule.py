"""The scheduling recipe of docs/guide/fleet.md, run as it is written there: the nightly script (with a
``vibkit`` on PATH that runs this checkout) exits 4 and puts the work list in place when a unit is past its
replace limit, and passes a failed scan's status on otherwise; the cron line has five valid time fields;
the systemd service and timer pass ``systemd-analyze verify`` where systemd is installed."""

from __future__ import annotations

import os
import re
import shutil
import stat
import subprocess
import sys
from pathlib import Path

import pandas as pd
import pytest

from vibkit.fleet import FleetDB

from support.fleet import fake

ROOT = Path(__file__).resolve().parents[2]
GUIDE = ROOT / "docs" / "guide" / "fleet.md"


def _blocks(lang):
    return re.findall(rf"^```{lang}\n(.*?)^```", GUIDE.read_text(encoding="utf-8"), flags=re.M | re.S)


def _script():
    (s,) = [b for b in _blocks("sh") if "vibkit-fleet-nightly" in b.splitlines()[1]]
    return s


def _env(tmp_path, db):
    """A PATH whose ``vibkit`` runs this checkout's vibkit with this test's Python."""
    bin_dir = tmp_path / "bin"
    bin_dir.mkdir(exist_ok=True)
    shim = bin_dir / "vibkit"
    shim.write_text(f'#!/bin/sh\nexec "{sys.executable}" -m vibkit "$@"\n')
    shim.chmod(shim.stat().st_mode | stat.S_IXUSR)
    env = {k: v for k, v in os.environ.items() if not k.startswith("VIBKIT_")}
    env.update(
        PATH=f"{bin_dir}{os.pathsep}{env.get('PATH', '')}",
        PYTHONPATH=str(ROOT),
        VISITS=str(tmp_path / "visits"),
        OUT=str(tmp_path / "out"),
        VIBKIT_FLEET_DB=str(db),
    )
    return env


def _history(path, latest):
    with FleetDB(path) as f:
        for i, (years, e) in enumerate([(0.0, latest - 0.6), (0.5, latest - 0.4), (1.0, latest - 0.2), (1.5, latest)]):
            f.insert(fake(i + 1, "E21", years, e))
    return path


@pytest.mark.slow  # six CLI processes and a scan: about a minute on 2 busy cores
@pytest.mark.skipif(shutil.which("sh") is None, reason="needs a POSIX shell")
def test_nightly_script_alerts_and_places_the_work_list(tmp_path):
    script = tmp_path / "vibkit-fleet-nightly"
    script.write_text(_script())
    script.chmod(0o755)
    (tmp_path / "visits").mkdir()
    (tmp_path / "visits" / "units.csv").write_text("file,unit,speed_m_s,date,nominal_pitch_m\n")
    (tmp_path / "out").mkdir()
    past = _history(tmp_path / "past.sqlite", 3.2)
    r = subprocess.run([str(script)], env=_env(tmp_path, past), capture_output=True, text=True, timeout=300)
    assert r.returncode == 4, r.stderr  # the scan found nothing new (1), the unit past 3 % wins: 4
    assert "past the replace limit (3 %): E21" in r.stderr
    work = pd.read_csv(tmp_path / "out" / "work-list.csv")
    assert work["unit"].tolist() == ["E21"] and work.loc[0, "latest_elongation_percent"] == 3.2
    assert sorted(p.name for p in (tmp_path / "out").iterdir()) == ["work-list.csv"]  # no temporary file left
    # under the limit: the work list is written, the scan's status (1: nothing stored) is the job's
    ok = _history(tmp_path / "ok.sqlite", 1.0)
    r = subprocess.run([str(script)], env=_env(tmp_path, ok), capture_output=True, text=True, timeout=300)
    assert r.returncode == 1, r.stderr
    assert pd.read_csv(tmp_path / "out" / "work-list.csv").loc[0, "latest_elongation_percent"] == 1.0
    # no database at all: status fails (1), yesterday's work list stays
    r = subprocess.run(
        [str(script)], env=_env(tmp_path, tmp_path / "none.sqlite"), capture_output=True, text=True, timeout=300
    )
    assert r.returncode == 1
    assert pd.read_csv(tmp_path / "out" / "work-list.csv").loc[0, "latest_elongation_percent"] == 1.0
    assert sorted(p.name for p in (tmp_path / "out").iterdir()) == ["work-list.csv"]


def test_cron_line():
    (block,) = [b for b in _blocks("text") if "/usr/local/bin/vibkit-fleet-nightly" in b]
    (line,) = [ln for ln in block.splitlines() if ln.strip() and not ln.startswith("#") and "=" not in ln]
    fields = line.split()
    field = re.compile(r"^(\*|[0-9]+(-[0-9]+)?)(/[0-9]+)?(,(\*|[0-9]+(-[0-9]+)?)(/[0-9]+)?)*$")
    assert len(fields) == 6 and all(field.match(f) for f in fields[:5]), line
    assert 0 <= int(fields[0]) < 60 and 0 <= int(fields[1]) < 24
    assert fields[5] == _script().splitlines()[1].split()[1]  # the script's own path


def test_systemd_units(tmp_path):
    units = {}
    for b in _blocks("ini"):
        name = Path(b.splitlines()[0].split()[1]).name
        units[name] = "\n".join(b.splitlines()[1:]) + "\n"
    assert set(units) == {"vibkit-fleet.service", "vibkit-fleet.timer"}
    assert "ExecStart=/usr/local/bin/vibkit-fleet-nightly" in units["vibkit-fleet.service"]
    analyze = shutil.which("systemd-analyze")
    if analyze is None:
        pytest.skip("systemd-analyze is not installed")
    script = tmp_path / "vibkit-fleet-nightly"  # the ExecStart binary must exist for verify
    script.write_text(_script())
    script.chmod(0o755)
    for name, text in units.items():
        (tmp_path / name).write_text(text.replace("/usr/local/bin/vibkit-fleet-nightly", str(script)))
    r = subprocess.run(
        [analyze, "verify", str(tmp_path / "vibkit-fleet.service"), str(tmp_path / "vibkit-fleet.timer")],
        capture_output=True,
        text=True,
        timeout=60,
    )
    assert r.returncode == 0 and "vibkit-fleet" not in r.stderr, r.stderr
