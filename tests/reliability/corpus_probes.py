"""Reliability cases found by probing every command as a stranger would: databases that are not
vibkit's, outputs it did not create, numbers at the edge of a float, damaged sweep stores, scenes
that leave out the escalator, dates that are not dates, and messages that must name the flag.

Each ends in a result or in one line naming the file or the flag and what was expected (exit
non-zero), and nothing vibkit did not create in that command is written.
"""

import math
import os
import sqlite3
from pathlib import Path

from corpus import ROOT, Case, scene_text, tiny

FLEET = ROOT / "data" / "fleet-example"
VISIT = (FLEET / "E07" / "2024-11-20.csv").read_text(encoding="utf-8")
GOOD = {"rec.csv": VISIT}
ADD = ["fleet", "add", "{w}/rec.csv", "--unit", "E07", "--speed", "0.5", "--nominal-pitch", "0.13333"]
ADD_DB = ADD + ["--db", "{w}/f.sqlite"]


def _signal(n=4000, fs=400.0, f=3.75, bad=None):
    """A link-pass tone with harmonics, one column of numbers and no time (``bad``: a run set to that text)."""
    rows = []
    for i in range(n):
        t = i / fs
        v = sum(math.sin(2 * math.pi * k * f * t) / k for k in (1, 2, 3))
        rows.append(f"{v:.5f}")
    if bad is not None:
        rows[2000:2008] = [bad] * 8
    return "ax\n" + "\n".join(rows) + "\n"


def _timed(bad):
    """The same tone with a time column, eight samples replaced by ``bad`` (``nan``, ``inf``)."""
    lines = _signal(bad=bad).splitlines()[1:]
    return "time,ax\n" + "\n".join(f"{i / 400.0:.4f},{v}" for i, v in enumerate(lines)) + "\n"


NOTIME = {"notime.csv": _signal()}
BIG_RATE = ["--sample-rate", "1e308"]


# ------------------------------------------------------------------------------------------ databases


FOREIGN_DDL = "CREATE TABLE measurement (id INTEGER PRIMARY KEY, sensor TEXT, value REAL);"


def foreign_measurement(name="f.sqlite"):
    """Another program's SQLite database that happens to have a table called ``measurement``."""

    def setup(w: Path):
        con = sqlite3.connect(w / name)
        con.executescript(FOREIGN_DDL)
        con.executemany("INSERT INTO measurement (sensor, value) VALUES (?, ?)", [("t1", 21.5), ("t2", 22.0)])
        con.commit()
        con.close()

    return setup


def vibkit_db(name="main.sqlite", *, pitch=0.13340, date="2026-01-01T00:00:00Z", unix=1767225600.0, visits=1):
    """A fleet database of one unit: ``visits`` rows two minutes apart, then edited by hand (NaN, bad dates)."""

    def setup(w: Path):
        from vibkit.fleet import FleetDB, Measurement

        with FleetDB(w / name) as db:
            for i in range(visits):
                db.insert(
                    Measurement(
                        id=None,
                        unit="E01",
                        date_utc=date,
                        date_unix_s=unix + 120.0 * i,
                        date_source="given",
                        speed_m_s=0.5,
                        speed_sigma_m_s=0.0,
                        nominal_pitch_m=0.13333,
                        channel="a",
                        fundamental_hz=3.75,
                        fundamental_sigma_hz=1e-4,
                        pitch_m=0.13340 + 2e-5 * i,
                        pitch_sigma_m=1e-5,
                        elongation_percent=0.05 + 0.015 * i,
                        elongation_sigma_percent=0.01,
                        snr_db=30.0,
                        warnings=(),
                        sha256=f"{i:064x}",
                        path=f"/v{i}.csv",
                        size_bytes=1,
                        vibkit_version="0",
                        analysed_utc="2026-01-01T00:00:00Z",
                    )
                )
        con = sqlite3.connect(w / name)
        if pitch != 0.13340:  # a value another tool wrote into the row (SQLite turns a float NaN into NULL: text)
            con.execute("UPDATE measurement SET pitch_m = ?, elongation_percent = ?", (pitch, pitch))
        if date != "2026-01-01T00:00:00Z" or unix != 1767225600.0:
            con.execute("UPDATE measurement SET date_utc = ?, date_unix_s = ?", (date, unix))
        con.commit()
        con.close()

    return setup


def scan_folder(fifo=False):
    def setup(w: Path):
        (w / "visits").mkdir()
        (w / "visits" / "2024-11-20.csv").write_text(VISIT, encoding="utf-8")
        if fifo:
            os.mkfifo(w / "visits" / "bad.csv")

    return setup


UNITS = "file,unit,speed_m_s,date,nominal_pitch_m\n*.csv,E07,0.5,,0.13333\n"


# ------------------------------------------------------------------------------------------ sweep stores


def sweep_store(damage):
    """A complete two-run sweep store of the tiny kinematics scene, then one chunk deleted or overwritten."""

    def setup(w: Path):
        from dask.distributed import Client

        import vibkit

        (w / "tiny.toml").write_text(tiny(), encoding="utf-8")
        with Client(processes=False, n_workers=1, threads_per_worker=1, dashboard_address=None) as client:
            vibkit.sweep(
                w / "tiny.toml",
                {"chain.link_pitch": "0.1333,0.1335"},
                output=w / "o.zarr",
                client=client,
                progress=False,
                keep=["delta"],
            )
        chunk = sorted((w / "o.zarr" / "delta").glob("[0-9]*"))[0]
        if damage == "delete":
            chunk.unlink()
        else:
            chunk.write_bytes(b"\x02\x01garbage" * 8)

    return setup


SWEEP_AGAIN = ["sweep", "{w}/tiny.toml", "--vary", "chain.link_pitch=0.1333,0.1335", "--keep", "delta", "-o"]


# ------------------------------------------------------------------------------------------ scenes


def without(section=None, key=None):
    """The tiny kinematics scene with a whole ``[section]`` or one ``section.key`` line removed."""
    lines, out, current = tiny().splitlines(), [], None
    for ln in lines:
        s = ln.strip()
        if s.startswith("["):
            current = s.strip("[]")
        if current == section and key is None:
            continue
        if current == section and key is not None and s.split("=")[0].strip() == key:
            continue
        out.append(ln)
    return "\n".join(out) + "\n"


def _bench_dir(w: Path):
    (w / "mine").mkdir()
    (w / "mine" / "read_quick.md").write_text("my own notes, not vibkit's\n", encoding="utf-8")


CASES = [
    # ------------------------------------------------------------------ a database that is not vibkit's: refused before any write
    Case(
        "fleet add --db with another program's measurement table",
        "lost",
        ADD_DB,
        files=GOOD,
        setup=foreign_measurement(),
        expect_in=("f.sqlite", "not a vibkit fleet"),
        protect=("{w}/f.sqlite",),
        absent=("{w}/f.sqlite-wal",),
    ),
    Case(
        "fleet scan --db with another program's measurement table",
        "lost",
        ["fleet", "scan", "{w}/visits", "--catalogue", "{w}/units.csv", "--db", "{w}/f.sqlite", "--workers", "0"],
        files={"units.csv": UNITS},
        setup=lambda w: (scan_folder()(w), foreign_measurement()(w)),
        expect_in=("f.sqlite", "not a vibkit fleet"),
        protect=("{w}/f.sqlite",),
    ),
    Case(
        "fleet migrate --to another program's database",
        "lost",
        ["fleet", "migrate", "--from", "{w}/main.sqlite", "--to", "{w}/f.sqlite"],
        setup=lambda w: (vibkit_db()(w), foreign_measurement()(w)),
        expect_in=("f.sqlite", "not a vibkit fleet"),
        protect=("{w}/f.sqlite", "{w}/main.sqlite"),
    ),
    Case(
        "fleet migrate --from another program's database",
        "lost",
        ["fleet", "migrate", "--from", "{w}/f.sqlite", "--to", "{w}/new.sqlite"],
        setup=foreign_measurement(),
        expect_in=("f.sqlite", "not a vibkit fleet"),
        protect=("{w}/f.sqlite",),
        absent=("{w}/new.sqlite",),
    ),
    Case(
        "fleet status --db with another program's measurement table",
        "lost",
        ["fleet", "status", "--db", "{w}/f.sqlite"],
        setup=foreign_measurement(),
        expect_in=("f.sqlite", "not a vibkit fleet"),
        protect=("{w}/f.sqlite",),
    ),
    Case(
        "fleet report --db with another program's measurement table",
        "lost",
        ["fleet", "report", "--db", "{w}/f.sqlite", "-o", "{w}/r.pdf"],
        setup=foreign_measurement(),
        expect_in=("f.sqlite", "not a vibkit fleet"),
        protect=("{w}/f.sqlite",),
        absent=("{w}/r.pdf",),
    ),
    Case(
        "fleet add, recording unreadable: no new database",
        "lost",
        ["fleet", "add", "{w}/junk.csv", "--unit", "E07", "--speed", "0.5", "--nominal-pitch", "0.13333"]
        + ["--date", "2026-01-01", "--db", "{w}/f.sqlite"],
        files={"junk.csv": b"\x00\x01\x02binary"},
        expect_in=("junk.csv",),
        absent=("{w}/f.sqlite", "{w}/f.sqlite-wal", "{w}/f.sqlite-journal"),
        note="a failed command leaves no new file",
    ),
    Case(
        "bench -o a folder holding the user's read_quick.md",
        "lost",
        ["bench", "--quick", "--only", "read", "-o", "{w}/mine"],
        setup=_bench_dir,
        expect_in=("mine", "--force"),
        protect=("{w}/mine/read_quick.md",),
        note="refused before any script runs",
    ),
    # ------------------------------------------------------------------ numbers at the edge of a float
    Case(
        "pitch --sample-rate 1e308",
        "limits",
        ["pitch", "{w}/notime.csv", "--speed", "0.5"] + BIG_RATE,
        files=NOTIME,
        expect="usage",
        expect_in=("--sample-rate", "1e308"),
    ),
    Case(
        "spectrum --sample-rate 1e308",
        "limits",
        ["spectrum", "{w}/notime.csv"] + BIG_RATE,
        files=NOTIME,
        expect="usage",
        expect_in=("--sample-rate",),
    ),
    Case(
        "report --sample-rate 1e308",
        "limits",
        ["report", "{w}/notime.csv", "-o", "{w}/r.pdf"] + BIG_RATE,
        files=NOTIME,
        expect="usage",
        expect_in=("--sample-rate",),
        absent=("{w}/r.pdf",),
    ),
    Case(
        "compare --sample-rate 1e308",
        "limits",
        ["compare", "{w}/notime.csv", "{w}/notime.csv"] + BIG_RATE,
        files=NOTIME,
        expect="usage",
        expect_in=("--sample-rate",),
    ),
    Case(
        "fleet add --sample-rate 1e308",
        "limits",
        ["fleet", "add", "{w}/notime.csv", "--unit", "E07", "--speed", "0.5", "--nominal-pitch", "0.13333"]
        + ["--date", "2026-01-01", "--db", "{w}/f.sqlite"]
        + BIG_RATE,
        files=NOTIME,
        expect="usage",
        expect_in=("--sample-rate",),
        absent=("{w}/f.sqlite",),
    ),
    Case(
        "spectrum --sample-rate 1e-300",
        "limits",
        ["spectrum", "{w}/notime.csv", "--sample-rate", "1e-300"],
        files=NOTIME,
        expect="usage",
        expect_in=("--sample-rate",),
    ),
    Case(
        "spectrum --sample-rate 1, below the band",
        "limits",
        ["spectrum", "{w}/notime.csv", "--sample-rate", "1"],
        files=NOTIME,
        expect_in=("--sample-rate", "Nyquist"),
    ),
    Case(
        "sweep --duration 1e308",
        "limits",
        ["sweep", "{w}/tiny.toml", "--vary", "chain.link_pitch=0.1333,0.1335", "--duration", "1e308", "-o"]
        + ["{w}/o.zarr"],
        files={"tiny.toml": tiny()},
        expect_in=("--duration",),
        absent=("{w}/o.zarr",),
    ),
    Case(
        "fleet add --db ''",
        "limits",
        ADD + ["--db", ""],
        files=GOOD,
        expect_in=("--db",),
    ),
    # ------------------------------------------------------------------ rows another tool edited
    Case(
        "fleet status, a row with NaN pitch",
        "fleet",
        ["fleet", "status", "--db", "{w}/main.sqlite"],
        setup=vibkit_db(pitch="NaN"),
        expect_in=("main.sqlite", "pitch_m"),
        protect=("{w}/main.sqlite",),
    ),
    Case(
        "fleet report, a row with NaN pitch",
        "fleet",
        ["fleet", "report", "--db", "{w}/main.sqlite", "-o", "{w}/r.pdf"],
        setup=vibkit_db(pitch="NaN"),
        expect_in=("main.sqlite", "pitch_m"),
        protect=("{w}/main.sqlite",),
        absent=("{w}/r.pdf",),
    ),
    Case(
        "fleet status, a date that is not a date",
        "fleet",
        ["fleet", "status", "--db", "{w}/main.sqlite"],
        setup=vibkit_db(date="last tuesday", unix=1e300),
        expect_in=("main.sqlite", "date"),
        protect=("{w}/main.sqlite",),
    ),
    Case(
        "fleet report, a date that is not a date",
        "fleet",
        ["fleet", "report", "--db", "{w}/main.sqlite", "-o", "{w}/r.pdf"],
        setup=vibkit_db(date="last tuesday", unix=1e300),
        expect_in=("main.sqlite", "date"),
        protect=("{w}/main.sqlite",),
        absent=("{w}/r.pdf",),
    ),
    Case(
        "fleet status, three visits two minutes apart",
        "fleet",
        ["fleet", "status", "--json", "--db", "{w}/main.sqlite"],
        setup=vibkit_db(visits=3),
        expect="ok",
        stdout_in=("30 days",),
        protect=("{w}/main.sqlite",),
        note="no rate and no forecast from visits spanning less than 30 days; the status says so",
    ),
    Case(
        "fleet scan, a FIFO named bad.csv in the folder",
        "fleet",
        ["fleet", "scan", "{w}/visits", "--catalogue", "{w}/units.csv", "--db", "{w}/f.sqlite", "--workers", "0"],
        files={"units.csv": UNITS},
        setup=scan_folder(fifo=True),
        expect="ok",
        expect_in=("bad.csv", "not a regular file"),
        outputs=("{w}/f.sqlite",),
        protect=("{w}/visits/bad.csv",),
        subprocess_only=True,
        note="the FIFO is skipped with a note; the recording beside it is stored",
    ),
    Case(
        "fleet scan, catalogue date 05/11/2025",
        "fleet",
        ["fleet", "scan", "{w}/visits", "--catalogue", "{w}/units.csv", "--db", "{w}/f.sqlite", "--workers", "0"],
        files={"units.csv": "file,unit,speed_m_s,date,nominal_pitch_m\n*.csv,E07,0.5,05/11/2025,0.13333\n"},
        setup=scan_folder(),
        expect_in=("units.csv, line 2", "date", "05/11/2025", "ISO 8601"),
        absent=("{w}/f.sqlite",),
    ),
    Case(
        "report --date 2999-01-01",
        "limits",
        ["report", "{w}/rec.csv", "--speed", "0.5", "--date", "2999-01-01", "-o", "{w}/r.pdf"],
        files=GOOD,
        expect_in=("--date", "2999-01-01"),
        absent=("{w}/r.pdf",),
    ),
    Case(
        "report --date 1850-01-01",
        "limits",
        ["report", "{w}/rec.csv", "--speed", "0.5", "--date", "1850-01-01", "-o", "{w}/r.pdf"],
        files=GOOD,
        expect_in=("--date", "1970-2100"),
        absent=("{w}/r.pdf",),
    ),
    # ------------------------------------------------------------------ damaged sweep stores
    Case(
        "sweep store with a chunk overwritten",
        "sweep",
        SWEEP_AGAIN + ["{w}/o.zarr"],
        setup=sweep_store("overwrite"),
        expect_in=("o.zarr", "delta", "--force"),
        note="the store's checksums name the damaged chunk",
    ),
    Case(
        "sweep store with a chunk deleted",
        "sweep",
        SWEEP_AGAIN + ["{w}/o.zarr"],
        setup=sweep_store("delete"),
        expect_in=("o.zarr", "delta", "missing"),
        note="not read back as fill values",
    ),
    # ------------------------------------------------------------------ scenes name what they leave out
    Case(
        "scene without [chain]",
        "scene",
        ["simulate", "{w}/s.toml", "-o", "{w}/o.nc"],
        files={"s.toml": without("chain")},
        expect_in=("s.toml", "[chain]"),
        absent=("{w}/o.nc",),
    ),
    Case(
        "scene without [guide]",
        "scene",
        ["simulate", "{w}/s.toml", "-o", "{w}/o.nc"],
        files={"s.toml": without("guide")},
        expect_in=("s.toml", "[guide]"),
        absent=("{w}/o.nc",),
    ),
    Case(
        "scene without chain.link_pitch",
        "scene",
        ["simulate", "{w}/s.toml", "-o", "{w}/o.nc"],
        files={"s.toml": without("chain", "link_pitch")},
        expect_in=("s.toml", "chain.link_pitch"),
        absent=("{w}/o.nc",),
    ),
    Case(
        "scene without [guide], [chain] and [sprocket]",
        "scene",
        ["simulate", "{w}/s.toml", "-o", "{w}/o.nc"],
        setup=lambda w: (w / "s.toml").write_text(
            scene_text("thesis-kinematics").split("[guide]")[0]
            + "[kinematics]\nstart = 3.0\nstop = 3.01\nstep = 0.001\n",
            encoding="utf-8",
        ),
        expect_in=("[guide]", "[chain]", "[sprocket]"),
        absent=("{w}/o.nc",),
    ),
    # ------------------------------------------------------------------ messages: the flag or the file, in plain words
    Case(
        "spectrum --band 1e308:inf",
        "messages",
        ["spectrum", "{w}/rec.csv", "--band", "1e308:inf"],
        files=GOOD,
        expect="usage",
        expect_in=("--band",),
    ),
    Case(
        "spectrum --band above Nyquist",
        "messages",
        ["spectrum", "{w}/rec.csv", "--band", "60:80"],
        files=GOOD,
        expect_in=("--band", "Nyquist"),
    ),
    Case(
        "spectrum --harmonics 0",
        "messages",
        ["spectrum", "{w}/rec.csv", "--harmonics", "0"],
        files=GOOD,
        expect="usage",
        expect_in=("--harmonics",),
    ),
    Case(
        "compare --harmonics -3",
        "messages",
        ["compare", "{w}/rec.csv", "{w}/rec.csv", "--harmonics", "-3"],
        files=GOOD,
        expect="usage",
        expect_in=("--harmonics",),
    ),
    Case(
        "spectrum --units furlongs",
        "messages",
        ["spectrum", "{w}/rec.csv", "--units", "furlongs"],
        files=GOOD,
        expect_in=("--units", "furlongs"),
    ),
    Case(
        "spectrum --units ax=g, no column ax",
        "messages",
        ["spectrum", "{w}/rec.csv", "--units", "ax=g"],
        files=GOOD,
        expect_in=("--units", "'ax'"),
    ),
    Case(
        "spectrum --encoding klingon",
        "messages",
        ["spectrum", "{w}/rec.csv", "--encoding", "klingon"],
        files=GOOD,
        expect_in=("--encoding", "klingon"),
    ),
    Case(
        "ride --channels x,y",
        "messages",
        ["ride", "{w}/rec.csv", "--channels", "x,y"],
        files=GOOD,
        expect_in=("--channels",),
    ),
    Case(
        "spectrum of a damaged netCDF file",
        "messages",
        ["spectrum", "{w}/bad.nc"],
        files={"bad.nc": b"CDF\x01garbage and more garbage"},
        expect_in=("bad.nc", "netCDF"),
    ),
    Case(
        "spectrum of a damaged HDF5 file",
        "messages",
        ["spectrum", "{w}/h5.nc"],
        files={"h5.nc": b"\x89HDF\r\n\x1a\n" + b"\x00" * 64},
        expect_in=("h5.nc",),
    ),
    Case(
        "spectrum of a damaged SAC file",
        "messages",
        ["spectrum", "{w}/bad.sac"],
        files={"bad.sac": b"\x00" * 100 + b"garbage"},
        expect_in=("bad.sac",),
    ),
    Case(
        "compare a result without the variable",
        "messages",
        ["compare", "{w}/rec.csv", "{w}/r.nc"],
        files=GOOD,
        setup=lambda w: (
            __import__("xarray")
            .Dataset({"other": ("time", [0.0, 1.0])}, coords={"time": [0.0, 1.0]})
            .to_netcdf(w / "r.nc")
        ),
        expect_in=("r.nc",),
    ),
    # ------------------------------------------------------------------ inf is treated like NaN
    Case(
        "spectrum, a block of NaN",
        "recording",
        ["spectrum", "{w}/nan.csv"],
        files={"nan.csv": _timed("nan")},
        expect="ok",
        expect_in=("8 invalid sample(s)", "interpolated"),
    ),
    Case(
        "spectrum, a block of inf",
        "recording",
        ["spectrum", "{w}/inf.csv"],
        files={"inf.csv": _timed("inf")},
        expect="ok",
        expect_in=("8 invalid sample(s)", "interpolated"),
        note="as the NaN block: interpolated, and the history says so",
    ),
    Case(
        "spectrum, a block of -Infinity",
        "recording",
        ["spectrum", "{w}/inf.csv"],
        files={"inf.csv": _timed("-Infinity")},
        expect="ok",
        expect_in=("8 invalid sample(s)",),
    ),
]
