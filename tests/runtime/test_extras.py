"""Optional dependencies (extras): where one is not installed, the work that needs it stops with one line
naming the package and the extra that installs it, and everything else works."""

from __future__ import annotations

import sys
from pathlib import Path

import pytest

from vibkit.cli import main
from vibkit.io import RecordingError, read_recording
from vibkit.runtime.extras import EXTRAS, MissingExtraError, require

ROOT = Path(__file__).resolve().parents[2]
MSEED = ROOT / "data" / "field" / "layouts" / "station.mseed"


def _hide(monkeypatch, *modules):
    """As if ``modules`` were not installed (an import of them raises ImportError)."""
    for m in modules:
        for name in [n for n in sys.modules if n == m or n.startswith(m + ".")]:
            monkeypatch.delitem(sys.modules, name)
        monkeypatch.setitem(sys.modules, m, None)


def test_require_names_the_extra(monkeypatch):
    _hide(monkeypatch, "zarr")
    with pytest.raises(MissingExtraError, match=r"^sweep stores needs zarr, which is not installed: "):
        require("zarr", "parallel", "sweep stores")
    with pytest.raises(ValueError, match=r"pip install 'vibkit\[parallel\]'$"):  # a user error: one line, exit 1
        require("zarr", "parallel", "sweep stores")
    assert require("json", "parallel", "x").dumps([1]) == "[1]"
    assert set(EXTRAS) == {"seismic", "parallel", "tdms", "postgres"}


def test_every_extra_is_declared_and_in_the_test_extra():
    import tomllib

    project = tomllib.loads((ROOT / "pyproject.toml").read_text())["project"]
    extras = project["optional-dependencies"]
    base = " ".join(project["dependencies"]).lower()
    for extra, packages in EXTRAS.items():
        assert extra in extras, extra
        for p in packages:
            assert any(r.lower().startswith(p.lower()) for r in extras[extra]), (extra, p)
            assert any(r.lower().startswith(p.lower()) for r in extras["test"]), p  # make test installs it
            assert p.lower() not in base, p  # not a hard dependency


def test_waveform_file_without_obspy(monkeypatch, tmp_path):
    _hide(monkeypatch, "obspy")
    with pytest.raises(RecordingError, match=r"needs obspy, not installed: pip install 'vibkit\[seismic\]'$"):
        read_recording(MSEED)
    assert read_recording(ROOT / "data" / "field" / "leon-tensioner.csv").sizes["time"] > 0  # the rest reads


def test_sweep_store_and_dask_without_them(monkeypatch, tmp_path, capsys):
    from vibkit.runtime.cluster import dask_client
    from vibkit.sweep import open_sweep

    _hide(monkeypatch, "zarr", "distributed")
    with pytest.raises(MissingExtraError, match=r"pip install 'vibkit\[parallel\]'"):
        open_sweep(tmp_path)
    with pytest.raises(MissingExtraError, match=r"needs distributed, .*'vibkit\[parallel\]'"):
        with dask_client():
            pass
    fleet = ROOT / "data" / "fleet-example"
    db = tmp_path / "f.sqlite"
    # a scan given a scheduler needs Dask
    code = main(
        ["fleet", "scan", str(fleet), "--catalogue", str(fleet / "units.csv"), "--db", str(db)]
        + ["--scheduler", "tcp://127.0.0.1:9"]
    )
    err = capsys.readouterr().err
    assert code == 1 and "needs distributed" in err and "--workers 0" in err and "vibkit[parallel]" in err
    assert "Traceback" not in err and not db.exists()
    # nine files never pay for a local cluster: the scan runs in the process, without Dask
    code = main(
        ["fleet", "scan", str(fleet), "--catalogue", str(fleet / "units.csv"), "--db", str(db), "--workers", "2"]
    )
    err = capsys.readouterr().err
    assert code == 0 and "9 added" in err and "Traceback" not in err
