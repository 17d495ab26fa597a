"""Spreadsheet workbooks (phyphox's "Excel" export, a sheet saved from a spreadsheet program): named and refused in
one line asking for CSV, never read as binary waveform data or as a zip of several files."""

from __future__ import annotations

import re
import zipfile

import pytest

from vibkit.cli import main
from vibkit.io import RecordingError, read_recording
from vibkit.io.registry import detect_format

OLE2 = b"\xd0\xcf\x11\xe0\xa1\xb1\x1a\xe1"


def _xlsx(path):
    with zipfile.ZipFile(path, "w") as zf:
        zf.writestr("[Content_Types].xml", "<Types/>")
        zf.writestr("xl/workbook.xml", "<workbook/>")
        zf.writestr("xl/worksheets/sheet1.xml", "<worksheet/>")


def _ods(path):
    with zipfile.ZipFile(path, "w") as zf:
        zf.writestr("mimetype", "application/vnd.oasis.opendocument.spreadsheet")
        zf.writestr("content.xml", "<office:document-content/>")


@pytest.mark.parametrize(
    "name, write, kind",
    [
        ("My Experiment 2023-04-16 18-40-30.xls", lambda p: p.write_bytes(OLE2 + b"\x00\x3e" * 256), "Excel 97-2003"),
        ("walk.xlsx", _xlsx, "Excel workbook (.xlsx)"),
        ("walk.dat", _xlsx, "Excel workbook (.xlsx)"),  # told by its xl/ members whatever the suffix
        ("walk.ods", _ods, "OpenDocument spreadsheet"),
    ],
)
def test_a_workbook_is_named_and_refused_asking_for_csv(tmp_path, capsys, name, write, kind):
    p = tmp_path / name
    write(p)
    assert detect_format(p, p.read_bytes()).name == "spreadsheet"
    with pytest.raises(
        RecordingError,
        match=re.escape(p.name) + ": an? " + re.escape(kind) + ".*which vibkit does not read; expected CSV",
    ):
        read_recording(p)
    assert main(["spectrum", str(p)]) != 0
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "expected CSV" in err[0] and "Traceback" not in err[0]


def test_a_zip_of_csv_files_is_no_workbook(tmp_path):
    p = tmp_path / "export.zip"
    with zipfile.ZipFile(p, "w") as zf:
        zf.writestr("Accelerometer.csv", "time,x,y,z\n0,0,0,9.8\n")
    assert detect_format(p, p.read_bytes()).name == "zip"
