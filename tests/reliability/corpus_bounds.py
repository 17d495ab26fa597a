"""Reliability cases of inputs bounded before they are parsed, refusals that name what to fix, and fleet
databases damaged in their middle: huge files are made sparse (``truncate``) or a few tens of MB at most, so
every case ends in seconds; each either refuses in one line naming the file and the limit, or gives the
known result."""

import os
import random
from pathlib import Path

from corpus import ROOT, Case, scene_text

FLEET = ROOT / "data" / "fleet-example"
VISIT = (FLEET / "E07" / "2024-11-20.csv").read_text(encoding="utf-8")
PROFILE = (FLEET / "escalators" / "E07.toml").read_text(encoding="utf-8")
GOOD = {"rec.csv": VISIT}
PITCH = ["pitch", "{w}/rec.csv", "--speed", "0.5", "--nominal-pitch", "0.13333"]
CATALOGUE = "file,unit,speed_m_s,date,nominal_pitch_m\n"
ADD_NEW = ["fleet", "add", "{w}/rec.csv", "--unit", "E07", "--speed", "0.5", "--nominal-pitch", "0.13333"] + [
    "--date",
    "2026-01-01",
    "--db",
    "{w}/f.sqlite",
]
SCAN = ["fleet", "scan", "{w}/visits", "--catalogue", "{w}/units.csv", "--db", "{w}/f.sqlite", "--workers", "0"]


def _sparse(name, size):
    """A file of ``size`` zero bytes that takes no disk (a hole)."""

    def setup(w: Path):
        with open(w / name, "wb") as fh:
            fh.truncate(size)

    return setup


def _wide_csv(name, columns=1_000_000, rows=30):
    def setup(w: Path):
        row = ",".join(["1"] * columns) + "\n"
        with open(w / name, "w") as fh:
            fh.write(",".join(f"c{i}" for i in range(columns)) + "\n")
            fh.write(row * rows)

    return setup


def _visits(w: Path):
    (w / "visits").mkdir()
    (w / "visits" / "rec.csv").write_text(VISIT)


def _damaged_db(name="f.sqlite", *, damage=True):
    """A fleet database of 300 rows with 4 KiB of random bytes written over a page in its middle."""

    def setup(w: Path):
        from vibkit.fleet import FleetDB, Measurement

        with FleetDB(w / name) as db:
            db.insert_many(
                Measurement(
                    id=None,
                    unit="E01",
                    date_utc="2026-01-01T00:00:00Z",
                    date_unix_s=1767225600.0 + i,
                    date_source="given",
                    speed_m_s=0.5,
                    speed_sigma_m_s=0.0005,
                    nominal_pitch_m=0.13333,
                    channel="a",
                    fundamental_hz=3.75,
                    fundamental_sigma_hz=1e-4,
                    pitch_m=0.13340,
                    pitch_sigma_m=1e-5,
                    elongation_percent=0.05,
                    elongation_sigma_percent=0.01,
                    snr_db=30.0,
                    warnings=(),
                    sha256=f"{i + 1:064x}",
                    path=f"/visit-{i}.csv",
                    size_bytes=1,
                    vibkit_version="0",
                    analysed_utc="2026-01-01T00:00:00Z",
                )
                for i in range(300)
            )
        if not damage:
            return
        size = os.path.getsize(w / name)
        assert size >= 8 * 4096, size
        with open(w / name, "r+b") as fh:
            fh.seek((size // 2) // 4096 * 4096)
            fh.write(random.Random(7).randbytes(4096))

    return setup


def _nested(depth):
    return "[escalator]\nunit = 'E07'\nx = " + "[" * depth + "]" * depth + "\n"


CLOSED_STDOUT = "import sys\nsys.stdout = None  # as Python leaves it when started with stdout closed (>&-)\n"

# a file-size limit (ulimit -f) of 2000 bytes, SIGXFSZ ignored as a shell does not: each write past it fails EFBIG
FSIZE_LIMIT = """
import resource, signal
signal.signal(signal.SIGXFSZ, signal.SIG_IGN)
resource.setrlimit(resource.RLIMIT_FSIZE, (2000, 2000))
"""

# the PDF writer's disk fills after 4 kB (matplotlib writes the PDF itself, not through vibkit's safe output)
PDF_DISK_FULL = """
import errno, os
import matplotlib.backends.backend_pdf as _bp
_orig, _n = _bp.PdfFile.write, [0]
def _write(self, data):
    _n[0] += len(data)
    if _n[0] > 4096:
        raise OSError(errno.ENOSPC, os.strerror(errno.ENOSPC))
    return _orig(self, data)
_bp.PdfFile.write = _write
"""

# the PDF's compressor closed after a failed write raises zlib.error, which hid the full disk
PDF_ZLIB = """
import zlib
import vibkit.diagnose.report as _r
def _fail(*a, **k):
    raise zlib.error("Error -2 while flushing: inconsistent stream state")
_r.write_fleet_report = _fail
"""


def _stored_db(name="f.sqlite"):
    """A sound fleet database of 300 measurements (no analysis: the rows written directly)."""
    return _damaged_db(name, damage=False)


CASES = [
    # ------------------------------------------------------------------ bounded before parsing
    Case(
        "profile nested 10000 deep",
        "bounds",
        PITCH + ["--escalator", "{w}/deep.toml"],
        files={**GOOD, "deep.toml": _nested(10_000)},
        expect_in=("{w}/deep.toml", "32 deep"),
    ),
    Case(
        "scene nested 10000 deep",
        "bounds",
        ["simulate", "{w}/deep.toml", "-o", "{w}/x.nc"],
        files={"deep.toml": "[scene]\nanalysis = 'forward'\nx = " + "{a = " * 10_000 + "1" + "}" * 10_000 + "\n"},
        expect_in=("{w}/deep.toml", "32 deep"),
        absent=("{w}/x.nc",),
    ),
    Case(
        "profile over 1 MiB",
        "bounds",
        PITCH + ["--escalator", "{w}/big.toml"],
        files={**GOOD, "big.toml": PROFILE + "#" + "x" * (1 << 20) + "\n"},
        expect_in=("{w}/big.toml", "a profile is a small TOML file", "1 MiB"),
    ),
    Case(
        "2 GB of zero bytes (pitch)",
        "bounds",
        ["pitch", "{w}/zeros.bin", "--speed", "0.5", "--nominal-pitch", "0.13333"],
        setup=_sparse("zeros.bin", 2 * 10**9),
        expect_in=("{w}/zeros.bin", "64 KiB", "zero bytes"),
        subprocess_only=True,
    ),
    Case(
        "2 GB of zero bytes (fleet add)",
        "bounds",
        ["fleet", "add", "{w}/zeros.mseed", "--unit", "E07", "--speed", "0.5", "--nominal-pitch", "0.13333"]
        + ["--date", "2026-01-01", "--db", "{w}/f.sqlite"],
        setup=_sparse("zeros.mseed", 2 * 10**9),
        expect_in=("{w}/zeros.mseed", "zero bytes"),
        absent=("{w}/f.sqlite",),
        subprocess_only=True,
    ),
    Case(
        "CSV of 30 rows and a million columns",
        "bounds",
        ["pitch", "{w}/wide.csv", "--speed", "0.5", "--nominal-pitch", "0.13333"],
        setup=_wide_csv("wide.csv"),
        expect_in=("{w}/wide.csv, line 1", "1000000 columns", "4096"),
        subprocess_only=True,
    ),
    Case(
        "catalogue of 2 GB without line ends",
        "bounds",
        SCAN,
        setup=lambda w: (_visits(w), _sparse("units.csv", 2 * 10**9)(w)),
        expect_in=("{w}/units.csv", "16 MiB"),
        absent=("{w}/f.sqlite",),
        subprocess_only=True,
    ),
    Case(
        "catalogue line of 200000 characters",
        "bounds",
        SCAN,
        files={"units.csv": CATALOGUE + "rec.csv,E01,0.5,2026-01-01,0.13333" + "," * 200_000 + "\n"},
        setup=_visits,
        expect_in=("{w}/units.csv, line 2", "200034 characters", "4096"),
        absent=("{w}/f.sqlite",),
    ),
    # ------------------------------------------------------------------ catalogue values (regressions)
    Case(
        "catalogue date 05/11/2025",
        "fleet",
        SCAN,
        files={"units.csv": CATALOGUE + "rec.csv,E01,0.5,05/11/2025,0.13333\n"},
        setup=_visits,
        expect_in=("{w}/units.csv, line 2", "ambiguous", "2025-11-05"),
        absent=("{w}/f.sqlite",),
    ),
    Case(
        "catalogue date in the future",
        "fleet",
        SCAN,
        files={"units.csv": CATALOGUE + "rec.csv,E01,0.5,2099-01-01,0.13333\n"},
        setup=_visits,
        expect_in=("{w}/units.csv, line 2", "future"),
        absent=("{w}/f.sqlite",),
    ),
    Case(
        "catalogue nominal_pitch_m 133.33",
        "fleet",
        SCAN,
        files={"units.csv": CATALOGUE + "rec.csv,E01,0.5,2026-01-01,133.33\n"},
        setup=_visits,
        expect_in=("{w}/units.csv, line 2", "nominal_pitch_m", "0.13333"),
        absent=("{w}/f.sqlite",),
    ),
    # ------------------------------------------------------------------ refusals that say what to fix
    Case(
        "pitch --speed-uncertainty 1e308%",
        "messages",
        PITCH + ["--speed-uncertainty", "1e308%"],
        files=GOOD,
        expect="usage",
        expect_in=("--speed-uncertainty", "0-20 %"),
    ),
    Case(
        "fleet add --unit ''",
        "messages",
        ["fleet", "add", "{w}/rec.csv", "--unit", "", "--speed", "0.5", "--nominal-pitch", "0.13333"]
        + ["--db", "{w}/f.sqlite"],
        files=GOOD,
        expect_in=("--unit is empty",),
        absent=("{w}/f.sqlite",),
    ),
    Case(
        "blank VIBKIT_FLEET_DB",
        "messages",
        ["fleet", "status"],
        env={"VIBKIT_FLEET_DB": "  "},
        expect_in=("$VIBKIT_FLEET_DB is blank",),
    ),
    Case(
        "postgresql:// naming nothing",
        "messages",
        ["fleet", "status", "--db", "postgresql://"],
        expect_in=("'postgresql://'", "names no server and no database", "postgresql://user@host/dbname"),
    ),
    Case(
        "postgresql:// with port 99999",
        "messages",
        ["fleet", "status", "--db", "postgresql://tech@host:99999/fleet"],
        expect_in=("Port out of range", "postgresql://user@host/dbname"),
    ),
    Case(
        "scene -o - with stdout closed",
        "messages",
        ["scene", "{w}/e07.toml", "-o", "-"],
        files={"e07.toml": PROFILE},
        prelude=CLOSED_STDOUT,
        expect_in=("-o -", "standard output is closed"),
    ),
    Case(
        "[sprocket] pitch = 133.33",
        "scene",
        ["simulate", "{w}/s.toml", "-o", "{w}/x.nc"],
        files={"s.toml": scene_text("thesis-forward", replace={"[sprocket]\n": "[sprocket]\npitch = 133.33\n"})},
        expect_in=("{w}/s.toml", "'sprocket.pitch'", "did you mean 0.13333 m?"),
        absent=("{w}/x.nc",),
    ),
    Case(
        "profile nominal_pitch = 133.33",
        "scene",
        ["pitch", "{w}/rec.csv", "--escalator", "{w}/mm.toml"],
        files={**GOOD, "mm.toml": PROFILE.replace("nominal_pitch = 0.13333", "nominal_pitch = 133.33")},
        expect_in=("{w}/mm.toml", "'chain.nominal_pitch'", "did you mean 0.13333 m?"),
    ),
    Case(
        "roller_mass = 1e9",
        "scene",
        ["simulate", "{w}/s.toml", "-o", "{w}/x.nc"],
        files={"s.toml": scene_text("thesis-forward", replace={"roller_mass = 8.0": "roller_mass = 1e9"})},
        expect_in=("{w}/s.toml", "'chain.roller_mass'", "0.01-200 kg"),
        absent=("{w}/x.nc",),
    ),
    Case(
        "profile speed_uncertainty = 0",
        "messages",
        ["pitch", "{w}/rec.csv", "--escalator", "{w}/zero.toml"],
        files={**GOOD, "zero.toml": PROFILE.replace("speed_uncertainty = 0.0005", "speed_uncertainty = 0")},
        expect="ok",
        expect_in=("0.5 +- 0 m/s", "stated as exact"),
        note="a stated zero is kept as zero: the elongation's +- is the frequency's alone",
    ),
    Case(
        "fleet add, profile speed_uncertainty = 0",
        "messages",
        ["fleet", "add", "{w}/rec.csv", "--escalator", "{w}/zero.toml", "--date", "2026-01-01", "--db", "{w}/f.sqlite"],
        files={**GOOD, "zero.toml": PROFILE.replace("speed_uncertainty = 0.0005", "speed_uncertainty = 0")},
        expect="ok",
        expect_in=("speed uncertainty stated as 0 m/s",),
        stdout_in=("stored #1 unit E07", "elongation +", "+-", "% (harmonic SNR"),
        outputs=("{w}/f.sqlite",),
        note="stored as a stated 0 (schema 5: not stated is NULL), with the frequency's +-, not warned about as missing",
    ),
    # ------------------------------------------------------------------ a database damaged in its middle
    Case(
        "fleet add, 4 KiB of random bytes mid-database",
        "fleet",
        ["fleet", "add", "{w}/rec.csv", "--unit", "E07", "--speed", "0.5", "--nominal-pitch", "0.13333"]
        + ["--date", "2026-01-01", "--db", "{w}/f.sqlite"],
        files=GOOD,
        setup=_damaged_db(),
        expect_in=("{w}/f.sqlite", "damaged", "left as it is"),
        protect=("{w}/f.sqlite",),
        absent=("{w}/f.sqlite-wal",),
    ),
    Case(
        "fleet migrate from a database with random bytes mid-file",
        "fleet",
        ["fleet", "migrate", "--from", "{w}/f.sqlite", "--to", "{w}/new.sqlite"],
        setup=_damaged_db(),
        expect_in=("{w}/f.sqlite", "damaged"),
        protect=("{w}/f.sqlite",),
        absent=("{w}/new.sqlite",),
    ),
    Case(
        "fleet scan into a database with random bytes mid-file",
        "fleet",
        SCAN,
        files={"units.csv": CATALOGUE + "rec.csv,E07,0.5,2026-01-01,0.13333\n"},
        setup=lambda w: (_visits(w), _damaged_db()(w)),
        expect_in=("{w}/f.sqlite", "damaged"),
        protect=("{w}/f.sqlite",),
    ),
    # ------------------------------------------------------------------ full disks and file-size limits
    Case(
        "fleet add under ulimit -f 2000",
        "output",
        ADD_NEW,
        files=GOOD,
        prelude=FSIZE_LIMIT,
        expect_in=("{w}/f.sqlite", "ulimit -f"),
    ),
    Case(
        "fleet report -o onto a full disk",
        "output",
        ["fleet", "report", "--db", "{w}/f.sqlite", "-o", "{w}/r.pdf"],
        setup=_stored_db(),
        prelude=PDF_DISK_FULL,
        expect_in=("{w}/r.pdf: No space left", "disk is full"),
        protect=("{w}/f.sqlite",),
        absent=("{w}/r.pdf",),
    ),
    Case(
        "fleet report -o, the PDF compressor fails",
        "output",
        ["fleet", "report", "--db", "{w}/f.sqlite", "-o", "{w}/r.pdf"],
        setup=_stored_db(),
        prelude=PDF_ZLIB,
        expect_in=("{w}/r.pdf", "could not be written", "disk full?"),
        protect=("{w}/f.sqlite",),
        absent=("{w}/r.pdf",),
    ),
]
