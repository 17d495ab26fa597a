"""``-`` for standard input and output: a recording piped into a command, a result written to stdout.

What is read from stdin is read as the file with the same bytes is (its format sniffed from the
bytes); what is written to ``-o -`` are the bytes the file would hold, and no file named ``-`` is
ever created.
"""

from __future__ import annotations

import io
import json
import os
import sys
from pathlib import Path

import numpy as np
import pytest
import xarray as xr

import vibkit
from vibkit.cli import main
from vibkit.io import write_result

ROOT = Path(__file__).resolve().parents[2]
LEON = ROOT / "data" / "field" / "leon-tensioner.csv"


def _stdin(monkeypatch, data: bytes):
    monkeypatch.setattr(sys, "stdin", io.TextIOWrapper(io.BytesIO(data)))


def _stdout(monkeypatch):
    buf = io.BytesIO()
    monkeypatch.setattr(sys, "stdout", io.TextIOWrapper(buf, write_through=True))
    return buf


def test_read_recording_from_stdin_equals_the_file(monkeypatch):
    _stdin(monkeypatch, LEON.read_bytes())
    piped = vibkit.read_recording("-")
    on_disk = vibkit.read_recording(LEON)
    assert piped.attrs["source_file"] == "<stdin>"
    assert piped.attrs["sha256"] == on_disk.attrs["sha256"]
    xr.testing.assert_identical(piped.drop_attrs(), on_disk.drop_attrs())


def test_netcdf_from_stdin_sniffed_by_its_bytes(monkeypatch, tmp_path):
    ds = xr.Dataset(
        {"a": ("time", np.sin(np.arange(200) * 0.1), {"units": "m/s^2"})},
        coords={"time": ("time", np.arange(200) / 100.0, {"units": "s"})},
    )
    path = write_result(ds, tmp_path / "r.nc")
    _stdin(monkeypatch, Path(path).read_bytes())
    piped = vibkit.read_recording("-")
    assert piped.attrs["reader"] == "vibkit.io.netcdf"
    assert piped.attrs["source_file"] == "<stdin>"
    np.testing.assert_array_equal(piped["a"].values, ds["a"].values)


def test_stdin_errors_name_stdin(monkeypatch):
    _stdin(monkeypatch, b"")
    with pytest.raises(vibkit.io.RecordingError, match=r"^<stdin>: is empty"):
        vibkit.read_recording("-")
    _stdin(monkeypatch, b"\x89HDF\r\n\x1a\nnot really")
    with pytest.raises(vibkit.io.RecordingError, match=r"^<stdin>: cannot read as (netCDF4/)?HDF5") as err:
        vibkit.read_recording("-")
    assert "vibkit-stdin-" not in str(err.value)  # the temporary file is not named


@pytest.mark.parametrize("command", ["pitch", "spectrum"])
def test_command_reads_stdin_like_the_file(command, monkeypatch, capsys):
    assert main([command, str(LEON), "--json"]) in (0, 3)
    from_file = json.loads(capsys.readouterr().out)
    _stdin(monkeypatch, LEON.read_bytes())
    assert main([command, "-", "--json"]) in (0, 3)
    piped = json.loads(capsys.readouterr().out)
    assert piped.pop("file") == "<stdin>"  # named as the reader's messages name it, not "-"
    from_file.pop("file", None)
    assert piped == from_file


@pytest.mark.parametrize("command", [["pitch"], ["spectrum"], ["links", "--links", "159"]])
def test_text_output_names_stdin(command, monkeypatch, capsys):
    _stdin(monkeypatch, LEON.read_bytes())
    main([command[0], "-", *command[1:]])
    out = capsys.readouterr()
    text = out.out + out.err
    assert "<stdin>" in text, text
    assert "-: " not in text, text


def test_simulate_to_stdout_writes_the_result_and_no_file(monkeypatch, tmp_path, capsys):
    monkeypatch.chdir(tmp_path)
    buf = _stdout(monkeypatch)
    assert main(["simulate", "thesis-kinematics", "--duration", "0.05", "-o", "-"]) == 0  # a shipped scene
    data = buf.getvalue()
    assert data.startswith(b"\x89HDF\r\n\x1a\n")  # the netCDF4/HDF5 bytes, and nothing else
    assert "scene     thesis-kinematics" in capsys.readouterr().err  # the summary went to stderr
    assert os.listdir(tmp_path) == []  # no file named '-' (nor a temporary one) left
    (tmp_path / "k.nc").write_bytes(data)
    ds = vibkit.read_recording(tmp_path / "k.nc")
    assert ds["delta"].attrs["units"] == "m"
    assert ds.attrs["Conventions"] == "CF-1.10"


def test_stdout_output_with_json_is_refused(tmp_path, monkeypatch, capsys):
    monkeypatch.chdir(tmp_path)
    rc = main(["simulate", "thesis-kinematics", "--duration", "0.05", "-o", "-", "--json"])
    err = capsys.readouterr().err
    assert rc == 2 and "-o -" in err and "--json" in err  # a usage error
    assert os.listdir(tmp_path) == []


def test_folder_outputs_refuse_stdout(tmp_path, monkeypatch, capsys):
    monkeypatch.chdir(tmp_path)
    scene = ROOT / "sim" / "thesis-kinematics.toml"
    rc = main(["sweep", str(scene), "--vary", "chain.link_pitch=0.13:0.14:2", "-o", "-"])
    err = capsys.readouterr().err
    assert rc == 2 and "-o -" in err and "Zarr" in err  # a usage error, as the options alone say it
    assert os.listdir(tmp_path) == []


def test_ride_reads_stdin_and_takes_a_shipped_scene_name(monkeypatch, capsys):
    phyphox = ROOT / "data" / "field" / "layouts" / "phyphox.csv"
    assert main(["ride", str(phyphox), "--segment", "0.5:3", "--json"]) == 0
    from_file = json.loads(capsys.readouterr().out)
    _stdin(monkeypatch, phyphox.read_bytes())
    assert main(["ride", "-", "--segment", "0.5:3", "--json"]) == 0
    piped = json.loads(capsys.readouterr().out)
    assert piped.pop("source") == "<stdin>"  # as the reader names it
    from_file.pop("source")
    assert piped == from_file


@pytest.mark.slow  # a report simulates the scene
def test_report_from_stdin_to_stdout(monkeypatch, tmp_path, capsys):
    monkeypatch.chdir(tmp_path)
    _stdin(monkeypatch, LEON.read_bytes())
    buf = _stdout(monkeypatch)
    rc = main(["report", "-", "--scene", str(ROOT / "sim" / "leon.toml"), "--duration", "2", "-o", "-"])
    assert rc == 0, capsys.readouterr().err
    assert buf.getvalue().startswith(b"%PDF-") and buf.getvalue().rstrip().endswith(b"%%EOF")
    assert "wrote <stdout> (" in capsys.readouterr().err
    assert os.listdir(tmp_path) == []


def test_a_report_from_stdin_names_it_so(monkeypatch, tmp_path, capsys):
    """`vibkit report - -o FILE` printed "file -" and page 1 said "recording -", where the docs name it <stdin>."""
    _stdin(monkeypatch, LEON.read_bytes())
    assert main(["report", "-", "-o", str(tmp_path / "r.pdf"), "--json"]) == 0
    assert json.loads(capsys.readouterr().out)["summary"]["file"] == "<stdin>"
