"""The example files shipped as :mod:`vibkit.datasets`: the repository's data/field and data/fleet-example, by
name, copied into a folder so that the documentation's examples run as written outside the clone."""

from __future__ import annotations

import json
from pathlib import Path

import pytest

import vibkit
import vibkit.datasets as ds
from vibkit.cli import main

ROOT = Path(__file__).resolve().parents[1]
DATA = ROOT / "data"


def _repo_files():
    return sorted(
        p.relative_to(DATA).as_posix()
        for top in ("field", "fleet-example")
        for p in (DATA / top).rglob("*")
        if p.is_file() and "__pycache__" not in p.parts
    )


def test_every_file_of_the_two_folders_and_nothing_else():
    assert list(ds.names()) == _repo_files()
    # the third-party and device files keep their own licences: never shipped
    assert not any(n.startswith(("thirdparty/", "devices/")) for n in ds.names())
    for name in ds.names():
        assert ds.path(name).read_bytes() == (DATA / name).read_bytes()


def test_small_enough_to_ship():
    total = sum(ds.path(n).stat().st_size for n in ds.names())
    assert total < 2_000_000, f"the shipped example files are {total} bytes"


@pytest.mark.parametrize(
    "name, rel",
    [
        ("leon-tensioner", "field/leon-tensioner.csv"),
        ("leon-tensioner.csv", "field/leon-tensioner.csv"),
        ("data/field/leon-tensioner.csv", "field/leon-tensioner.csv"),  # as the documentation writes it
        ("phyphox", "field/layouts/phyphox.csv"),
        ("units", "fleet-example/units.csv"),
        ("E07.toml", "fleet-example/escalators/E07.toml"),
        ("fleet-example", "fleet-example"),
        ("data/fleet-example/", "fleet-example"),
        ("field/layouts", "field/layouts"),
    ],
)
def test_names(name, rel):
    assert ds.path(name) == ds.folder() / rel


def test_unknown_and_ambiguous_names_say_what_to_give():
    with pytest.raises(ValueError, match=r"no shipped dataset 'nope'.*'vibkit datasets list' lists them"):
        ds.path("nope")
    with pytest.raises(ValueError, match=r"'2026-11-23' names 3 files: fleet-example/E07/2026-11-23.csv"):
        ds.path("2026-11-23")


def test_every_file_has_its_provenance():
    for name in ds.names():
        text = ds.provenance(name)
        assert ("NOT original" in text) or ("SYNTHETIC" in text), name
    # and the files say it themselves: the field reconstructions and the fleet in their header lines
    for name in ("field/leon-tensioner.csv", "field/las-palmas-accelerometer.csv", "fleet-example/E07/2024-11-20.csv"):
        head = ds.path(name).read_text(encoding="utf-8")[:400]
        assert "NOT an original recording" in head or "SYNTHETIC" in head, name


def test_a_shipped_recording_reads_as_the_repository_file():
    rec = vibkit.read_recording(ds.path("leon-tensioner"))
    assert float(rec.attrs["chain_speed_m_s"]) == 0.49  # the metadata line the reconstruction states


def test_copy_writes_the_repository_layout_and_never_replaces_other_bytes(tmp_path):
    dest = tmp_path / "data"
    written = ds.copy(dest)
    assert sorted(p.relative_to(dest).as_posix() for p in written) == _repo_files()
    for name in ds.names():
        assert (dest / name).read_bytes() == (DATA / name).read_bytes()
    assert ds.copy(dest) == []  # the same bytes already there: nothing written
    mine = dest / "fleet-example" / "units.csv"
    mine.write_text("my own catalogue\n")
    with pytest.raises(FileExistsError, match=r"units.csv: already exists with other contents; nothing was copied"):
        ds.copy(dest)
    assert mine.read_text() == "my own catalogue\n"
    assert ds.copy(dest, force=True) == [mine]
    assert mine.read_bytes() == (DATA / "fleet-example" / "units.csv").read_bytes()
    assert not list(dest.rglob("*.tmp"))


def test_cli(tmp_path, capsys):
    assert main(["datasets", "path", "leon-tensioner"]) == 0
    assert Path(capsys.readouterr().out.strip()) == ds.path("leon-tensioner")
    assert main(["datasets", "list", "--json"]) == 0
    listed = json.loads(capsys.readouterr().out)
    assert listed["schema"] == "vibkit.datasets/1"
    assert [f["name"] for f in listed["files"]] == _repo_files()
    assert all(f["bytes"] == (DATA / f["name"]).stat().st_size for f in listed["files"])
    assert main(["datasets", "copy", str(tmp_path / "d")]) == 0
    assert f"wrote {len(_repo_files())} of {len(_repo_files())} example files" in capsys.readouterr().err
    (tmp_path / "d" / "field" / "leon-tensioner.csv").write_text("x\n")
    assert main(["datasets", "copy", str(tmp_path / "d")]) == 1
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "leon-tensioner.csv: already exists" in err and "--force" in err
    assert main(["datasets", "path", "nope"]) == 1
    assert "no shipped dataset 'nope'" in capsys.readouterr().err
