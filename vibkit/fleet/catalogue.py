"""The catalogue of a scan: which unit, speed, date and nominal pitch each recording of a folder has.

The catalogue is a CSV file (``#`` starts a comment line) with these columns, in any order (header
names are case-insensitive):

========================  ========  ============================================================
column                    required  meaning
========================  ========  ============================================================
``file``                  yes       file name, path relative to the scanned folder, or a glob
                                    (``E07/*.csv``); an exact name wins over a glob, else the
                                    first matching line
``unit``                  yes       escalator identifier
``speed_m_s``             yes       chain (step) speed measured on the steps (not the handrail) [m/s]
``date``                  yes       measurement date, ISO 8601 (``2026-11-23``,
                                    ``2026-11-23T10:15:00+01:00``); empty: an ISO date in the
                                    file name (``E22-2026-01-01.csv``), else the recording's
                                    start time; dates without a time zone are UTC
``nominal_pitch_m``       yes       nominal link pitch [m]; empty: the unit's value from another
                                    line of the catalogue or from the database
``speed_sigma_m_s``       no        standard deviation of the speed [m/s] (empty: not stated;
                                    0: an exact speed)
``channel``               no        channel to analyse (default: the first)
``escalator``             no        the unit's escalator profile (TOML, path relative to the
                                    catalogue): an empty ``unit``, ``speed_m_s``,
                                    ``speed_sigma_m_s`` or ``nominal_pitch_m`` cell (or column) is
                                    the profile's (:mod:`vibkit.model.profile`); its
                                    ``chain.n_links`` fills an empty ``n_links`` and its forward
                                    scene gives a tensioner's worn-link signature
``n_links``               no        links in the chain: the scan numbers them and flags worn ones
                                    when the recording covers two loops (empty: the profile's;
                                    none: the links are not scanned)
``marker_s``              no        time [s from the recording's start] at which a marked link
                                    (paint, a tag) passed the sensor: it is link 1, and the same
                                    link can be followed across visits; empty: link 1 is the link
                                    at the sensor at the start (numbers not comparable)
========================  ========  ============================================================
"""

from __future__ import annotations

import csv
import io
import math
import os
import posixpath
import stat
from dataclasses import dataclass

from ..model.profile import load_profile
from ..model.schema import SceneError
from .dates import _iso, parse_date
from .errors import FleetError
from .inputs import check_pitch, check_speed, check_speed_sigma

__all__ = ["CATALOGUE_COLUMNS", "CatalogueRow", "read_catalogue"]

#: required and optional catalogue columns
CATALOGUE_COLUMNS = ("file", "unit", "speed_m_s", "date", "nominal_pitch_m")
CATALOGUE_OPTIONAL = ("speed_sigma_m_s", "channel", "escalator", "n_links", "marker_s")
#: the largest catalogue read [bytes] and its longest line [characters]: bounded before it is parsed
MAX_CATALOGUE_BYTES = 16 * 2**20
MAX_CATALOGUE_LINE = 4096
#: columns a profile (the escalator column) can stand in for
FROM_PROFILE = ("unit", "speed_m_s", "nominal_pitch_m")


@dataclass(frozen=True)
class CatalogueRow:
    """One line of a scan catalogue (see the module docstring for the columns)."""

    line: int
    file: str
    unit: str
    speed_m_s: float
    speed_sigma_m_s: float | None = None
    date: str | None = None
    nominal_pitch_m: float | None = None
    channel: str | None = None
    n_links: int | None = None
    marker_s: float | None = None
    #: the escalator profile (absolute path), whose forward scene gives the link scan its signature
    escalator: str | None = None

    @property
    def is_glob(self) -> bool:
        return any(c in self.file for c in "*?[")


def _number(text, path, line, col, *, lo, hi, unit, hint=""):
    try:
        v = float(text)
    except ValueError:
        raise FleetError(f"{path}, line {line}: column {col}: expected a number [{unit}], got {text!r}") from None
    if not (math.isfinite(v) and lo <= v <= hi) or (lo == 0 and v == 0 and col not in ("speed_sigma_m_s", "marker_s")):
        raise FleetError(f"{path}, line {line}: column {col}: {text!r} is outside {lo:g}-{hi:g} {unit}{hint}")
    return v


def _with_profile(v, spath, line):
    """The row's cells, the empty ones (unit, speed, its sigma, nominal pitch) filled from its profile."""
    where = os.path.join(os.path.dirname(os.path.abspath(spath)), v["escalator"])
    try:
        prof = load_profile(where)
    except (SceneError, OSError) as exc:
        raise FleetError(f"{spath}, line {line}: column escalator: {' '.join(str(exc).split())}") from None
    v = dict(v)
    if not v.get("unit"):
        v["unit"] = prof.unit
    if not v.get("speed_m_s"):
        v["speed_m_s"] = repr(float(prof.speed))
        if not v.get("speed_sigma_m_s"):  # the profile's stated sigma, else the standard's tolerance
            v["speed_sigma_m_s"] = repr(float(prof.speed_sigma[0]))
    if not v.get("nominal_pitch_m"):
        v["nominal_pitch_m"] = repr(float(prof.nominal_pitch))
    if not v.get("n_links") and prof.n_links is not None:
        v["n_links"] = str(int(prof.n_links))
    v["escalator"] = where
    return v


def read_catalogue(path):
    """Read and validate a scan catalogue (CSV); a list of :class:`CatalogueRow`.

    Raises
    ------
    FleetError
        Missing file, missing or unknown columns, a line with too few or too many cells, an empty
        file/unit/speed, a value that is not a number or not plausible, a bad date, or two nominal
        pitches for one unit; the message names the file and the line.
    """
    spath = os.fspath(path)
    try:
        with open(spath, "rb") as fh:
            if not stat.S_ISREG(os.fstat(fh.fileno()).st_mode):
                raise FleetError(
                    f"{spath}: catalogue is not a regular file (a folder, FIFO or device); give a CSV file"
                )
            raw = fh.read(MAX_CATALOGUE_BYTES + 1)
    except FileNotFoundError:
        raise FleetError(f"{spath}: catalogue not found") from None
    except OSError as exc:
        raise FleetError(f"{spath}: catalogue cannot be read: {exc.strerror or exc}") from None
    if len(raw) > MAX_CATALOGUE_BYTES:
        raise FleetError(
            f"{spath}: catalogue is larger than {MAX_CATALOGUE_BYTES // 2**20} MiB, the limit (a line per recording "
            "is some 100 bytes); split it, one catalogue per folder"
        )
    try:
        text = raw.decode("utf-8-sig")
    except UnicodeDecodeError:
        text = raw.decode("cp1252", errors="replace")
    lines = [(i, ln) for i, ln in enumerate(text.splitlines(), 1) if ln.strip() and not ln.lstrip().startswith("#")]
    long = next(((i, len(ln)) for i, ln in lines if len(ln) > MAX_CATALOGUE_LINE), None)
    if long is not None:
        raise FleetError(
            f"{spath}, line {long[0]}: {long[1]} characters, more than the {MAX_CATALOGUE_LINE} a catalogue line "
            "may have (one line per recording: file, unit, speed_m_s, date, nominal_pitch_m)"
        )
    if not lines:
        raise FleetError(
            f"{spath}: catalogue is empty; expected a header line with columns {', '.join(CATALOGUE_COLUMNS)}"
        )
    head_line, head = lines[0]
    delim = ";" if head.count(";") > head.count(",") else ","
    cells = lambda s: next(csv.reader(io.StringIO(s), delimiter=delim, skipinitialspace=True))  # noqa: E731
    header = [c.strip().lower() for c in cells(head)]
    missing = [c for c in CATALOGUE_COLUMNS if c not in header and not ("escalator" in header and c in FROM_PROFILE)]
    if missing:
        raise FleetError(
            f"{spath}, line {head_line}: missing column(s) {', '.join(missing)}; a catalogue has the "
            f"columns {', '.join(CATALOGUE_COLUMNS)} (optional: {', '.join(CATALOGUE_OPTIONAL)})"
        )
    unknown = [c for c in header if c not in CATALOGUE_COLUMNS + CATALOGUE_OPTIONAL]
    if unknown:
        raise FleetError(
            f"{spath}, line {head_line}: unknown column(s) {', '.join(map(repr, unknown))}; known: "
            f"{', '.join(CATALOGUE_COLUMNS + CATALOGUE_OPTIONAL)}"
        )
    if len(set(header)) != len(header):
        raise FleetError(f"{spath}, line {head_line}: a column appears twice")
    rows, nominal = [], {}
    for n, ln in lines[1:]:
        c = [v.strip() for v in cells(ln)]
        if len(c) != len(header):
            raise FleetError(
                f"{spath}, line {n}: {len(c)} cell(s), expected {len(header)} "
                f"({', '.join(header)}); a missing value is an empty cell between commas"
            )
        v = dict(zip(header, c))
        if v.get("escalator"):
            v = _with_profile(v, spath, n)
        for col in ("file", "unit", "speed_m_s"):
            if not v.get(col):
                raise FleetError(f"{spath}, line {n}: column {col} is empty")
        if os.path.isabs(v["file"]) or ".." in v["file"].replace("\\", "/").split("/"):
            raise FleetError(f"{spath}, line {n}: file {v['file']!r} must be relative to the scanned folder")
        speed = _number(v["speed_m_s"], spath, n, "speed_m_s", lo=0.0, hi=10.0, unit="m/s")
        ssig = (
            _number(v["speed_sigma_m_s"], spath, n, "speed_sigma_m_s", lo=0.0, hi=speed, unit="m/s")
            if v.get("speed_sigma_m_s")
            else None
        )
        try:  # the stated ranges (vibkit.fleet.inputs), as for fleet add
            check_speed(speed, "column speed_m_s")
            if ssig is not None:
                check_speed_sigma(ssig, speed, "column speed_sigma_m_s")
        except FleetError as exc:
            raise FleetError(f"{spath}, line {n}: {exc}") from None
        date = None
        if v["date"]:
            try:
                date = _iso(parse_date(v["date"]))
            except FleetError as exc:
                raise FleetError(f"{spath}, line {n}: {exc}") from None
        nom = None
        if v.get("nominal_pitch_m"):
            nom = _number(
                v["nominal_pitch_m"],
                spath,
                n,
                "nominal_pitch_m",
                lo=0.0,
                hi=1.0,
                unit="m",
                hint=" (metres: 0.13333, not 133.33)",
            )
            try:
                check_pitch(nom, "column nominal_pitch_m")
            except FleetError as exc:
                raise FleetError(f"{spath}, line {n}: {exc}") from None
            prev = nominal.get(v["unit"])
            if prev is not None and not math.isclose(prev[0], nom, rel_tol=1e-9):
                raise FleetError(
                    f"{spath}, line {n}: unit {v['unit']!r} has nominal_pitch_m {nom:g} here but "
                    f"{prev[0]:g} on line {prev[1]}"
                )
            nominal.setdefault(v["unit"], (nom, n))
        n_links = None
        if v.get("n_links"):
            try:
                n_links = int(v["n_links"])
            except ValueError:
                raise FleetError(
                    f"{spath}, line {n}: column n_links: expected a whole number of links, got {v['n_links']!r}"
                ) from None
            if not 2 <= n_links <= 100000:
                raise FleetError(f"{spath}, line {n}: column n_links: {n_links} is outside 2-100000 links")
        marker = None
        if v.get("marker_s"):
            marker = _number(v["marker_s"], spath, n, "marker_s", lo=0.0, hi=1e7, unit="s from the recording's start")
        rows.append(
            CatalogueRow(
                n,
                posixpath.normpath(v["file"].replace("\\", "/")),
                v["unit"],
                speed,
                ssig,
                date,
                nom,
                v.get("channel") or None,
                n_links,
                marker,
                v.get("escalator") or None,
            )
        )
    if not rows:
        raise FleetError(f"{spath}: catalogue has a header but no line")
    return rows
