"""Scanning a folder of recordings: match each file to its catalogue line, analyse on Dask workers, store.

A recording's date is the catalogue's; where the catalogue has none, an ISO date in the file name
(``E22-2026-01-01.csv``: ``date_source`` "file name"); else the recording's start time.

The workers only analyse (:func:`_analyse_job`); the calling process alone writes, one committed
transaction per :data:`BATCH_ROWS` recordings or :data:`BATCH_S` seconds (:meth:`FleetDB.insert_batch`), so a
killed scan leaves complete rows only and loses at most the last second's analyses.  Where the number of links is known (the
catalogue's ``n_links`` or the escalator profile's), a worker also scans the recording's links
(:mod:`vibkit.fleet.link_scan`), with the catalogue's ``marker_s``; the scan's status is stored with the
measurement, which a failed link scan never costs.
"""

from __future__ import annotations

import fnmatch
import math
import os
import re
import time
from dataclasses import dataclass, field

from ..runtime.cluster import dask_client, dask_pays, default_workers, scheduler_address, warm_workers
from ..runtime.extras import require
from ..runtime.progress import Progress
from .catalogue import read_catalogue
from .dates import _iso, parse_date
from .errors import DuplicateRecordingError, FleetError
from .link_scan import measure_with_links, profile_scene
from .measurement import _file_sha256

__all__ = ["RECORDING_SUFFIXES", "ScanResult", "scan_folder"]

#: a scan stores its analyses in one transaction per this many recordings, or per this many seconds since the oldest
#: one waiting, whichever comes first: a commit (an fsync of the SQLite file) cost as much as the analysis of a
#: small recording, and a killed scan loses at most the last second's analyses (its stored rows are whole)
BATCH_ROWS = 64
BATCH_S = 1.0

#: files a scan analyses in this process before it judges whether the rest pay for a local cluster
#: (:func:`vibkit.runtime.cluster.dask_pays`; the first loads the analysis: the least of their times is the estimate)
FILES_BEFORE_CHOOSING = 2

#: file suffixes a scan treats as recordings
RECORDING_SUFFIXES = (
    ".csv",
    ".txt",
    ".tsv",
    ".dat",
    ".log",
    ".nc",
    ".nc4",
    ".h5",
    ".hdf5",
    ".mseed",
    ".miniseed",
    ".msd",
    ".seed",
    ".sac",
)


@dataclass(frozen=True)
class _Job:
    path: str
    unit: str
    speed_m_s: float
    speed_sigma_m_s: float | None
    nominal_pitch_m: float
    date: str | None
    channel: str | None
    sha256: str
    read_options: dict | None = None
    date_source: str = "given"
    n_links: int | None = None
    marker_s: float | None = None
    scene: str | None = None


def _analyse_job(job):
    """Worker side of a scan: analyse one recording and scan its links; never raises (a failure is a message)."""
    try:
        m, scan = measure_with_links(
            job.path,
            n_links=job.n_links,
            marker_s=job.marker_s,
            scene=job.scene,
            unit=job.unit,
            speed=job.speed_m_s,
            speed_sigma=job.speed_sigma_m_s,
            nominal_pitch=job.nominal_pitch_m,
            date=job.date,
            channel=job.channel,
            read_options=job.read_options,
            date_source=job.date_source,
        )
        return {"ok": True, "measurement": m, "link_scan": scan}
    except (ValueError, OSError) as exc:  # RecordingError and FleetError are ValueErrors
        msg = " ".join(str(exc).split()) or type(exc).__name__
        if not msg.startswith(job.path):
            msg = f"{job.path}: {msg}"
        return {"ok": False, "error": msg}
    except Exception as exc:  # noqa: BLE001 - a bad file must never stop the scan
        return {"ok": False, "error": f"{job.path}: unexpected {type(exc).__name__}: {' '.join(str(exc).split())}"}


@dataclass
class ScanResult:
    """What :meth:`FleetDB.scan` did.

    Attributes
    ----------
    added : list of Measurement
    skipped : list of (str, str)
        Files already stored (same SHA-256), with the reason.
    failed : list of (str, str)
        Files (or catalogue lines) that could not be added, with the reason.
    notes : list of str
    link_scans : dict
        ``{sha256: LinkScan}`` of the added measurements (:mod:`vibkit.fleet.links`).
    """

    added: list = field(default_factory=list)
    skipped: list = field(default_factory=list)
    failed: list = field(default_factory=list)
    notes: list = field(default_factory=list)
    link_scans: dict = field(default_factory=dict)

    def as_dict(self) -> dict:
        return {
            "added": len(self.added),
            "skipped_duplicates": len(self.skipped),
            "failed": len(self.failed),
            "added_files": [m.path for m in self.added],
            "skipped_files": [{"file": p, "reason": r} for p, r in self.skipped],
            "failed_files": [{"file": p, "reason": r} for p, r in self.failed],
            "link_scans": [
                {"file": m.path, **self.link_scans[m.sha256].as_dict()}
                for m in self.added
                if m.sha256 in self.link_scans
            ],
            "notes": list(self.notes),
        }


_NAME_DATE = re.compile(r"(?<![0-9])([0-9]{4}-[0-9]{2}-[0-9]{2})(?![0-9])")


def date_from_name(name):
    """The ISO 8601 date (``YYYY-MM-DD``) in a file name, as UTC text, or None (none, or not a real date)."""
    for m in _NAME_DATE.finditer(os.path.basename(name)):
        try:
            return _iso(parse_date(m.group(1)))
        except FleetError:
            continue
    return None


def _candidate_files(directory, exclude, skipped=None):
    """Recordings under ``directory`` (relative paths); a FIFO, device or socket with a recording's name is
    never opened (reading a FIFO waits forever): its path goes to ``skipped``."""
    out = []
    for root, dirs, files in os.walk(directory):
        dirs[:] = sorted(d for d in dirs if not d.startswith("."))
        for f in sorted(files):
            if f.startswith(".") or os.path.splitext(f)[1].lower() not in RECORDING_SUFFIXES:
                continue
            full = os.path.join(root, f)
            if os.path.abspath(full) in exclude:
                continue
            if not os.path.isfile(full):
                if skipped is not None:
                    skipped.append(full)
                continue
            out.append(os.path.relpath(full, directory).replace(os.sep, "/"))
    return sorted(out)


def _not_a_new_recording(full, db):
    """Why a file no catalogue line describes is no failure (already stored, a catalogue), else None."""
    try:
        old = db.find(_file_sha256(full))
    except OSError:
        return None
    if old is not None:
        return f"already stored as measurement #{old.id} of unit {old.unit!r} (no line of this catalogue names it)"
    try:
        with open(full, encoding="utf-8-sig", errors="replace") as fh:
            head = [c.strip().lower() for c in fh.readline().split(",")]
    except OSError:
        return None
    if "file" in head and "unit" in head:
        return "a catalogue (columns file, unit), not a recording"
    return None


def _match(rel, rows):
    base = rel.rsplit("/", 1)[-1]
    exact = [r for r in rows if not r.is_glob and r.file in (rel, base)]
    if exact:
        return exact[0]
    for r in rows:
        if r.is_glob and (fnmatch.fnmatchcase(rel, r.file) or fnmatch.fnmatchcase(base, r.file)):
            return r
    return None


def scan_folder(
    db,
    directory,
    catalogue,
    *,
    scheduler=None,
    n_workers=None,
    client=None,
    parallel=None,
    on_failure=None,
    progress=False,
    read_options=None,
):
    """Add every recording of a folder that a catalogue describes to ``db``; see :meth:`FleetDB.scan`.

    ``db`` stores the measurements: its ``find``, ``nominal_pitch`` and ``insert`` are called from
    this process only, and the files of ``db.local_files`` (a SQLite file and its ``-wal``/``-shm``
    companions) are not scanned.
    """
    d = os.fspath(directory)
    if not os.path.isdir(d):
        raise FleetError(f"{d}: not a folder; expected the folder of recordings to scan")
    rows = read_catalogue(catalogue)
    res = ScanResult()

    def fail(name, why):
        res.failed.append((name, why))
        if on_failure is not None:
            on_failure(name, why)

    exclude = {os.path.abspath(os.fspath(catalogue)), *getattr(db, "local_files", ())}
    skipped = []
    files = _candidate_files(d, exclude, skipped)
    res.notes += [f"{p}: not a regular file (a FIFO, device or socket); skipped" for p in skipped]
    # a file the catalogue names exactly is a recording whatever its suffix
    named = [
        r.file
        for r in rows
        if not r.is_glob
        and os.path.isfile(os.path.join(d, r.file))
        and os.path.abspath(os.path.join(d, r.file)) not in exclude
    ]
    files = sorted(set(files) | {os.path.normpath(f).replace(os.sep, "/") for f in named})
    unit_nominal = {}
    for r in rows:
        if r.nominal_pitch_m is not None:
            unit_nominal.setdefault(r.unit, r.nominal_pitch_m)
    used = set()
    jobs, seen, scenes = [], {}, {}
    for rel in files:
        full = os.path.join(d, rel)
        r = _match(rel, rows)
        if r is None:
            # a catalogue of new visits leaves out the files stored before, and the folder may hold catalogues
            why = _not_a_new_recording(full, db)
            if why is not None and why.startswith("a catalogue"):
                res.notes.append(f"{full}: {why}; not scanned")
            elif why is not None:
                res.skipped.append((full, why))
            else:
                fail(full, "unknown unit: no catalogue line matches this file")
            continue
        used.add(r.line)
        try:
            sha = _file_sha256(full)
        except OSError as exc:
            fail(full, f"cannot be read: {exc.strerror or exc}")
            continue
        old = db.find(sha)
        if old is not None:
            res.skipped.append((full, f"already stored as measurement #{old.id} of unit {old.unit!r}"))
            continue
        if sha in seen:
            res.skipped.append((full, f"same content (sha256) as {seen[sha]} in this scan"))
            continue
        seen[sha] = full
        nom = r.nominal_pitch_m or unit_nominal.get(r.unit) or db.nominal_pitch(r.unit)
        if nom is None:
            fail(
                full,
                f"unit {r.unit!r} has no nominal pitch (catalogue line {r.line}: fill nominal_pitch_m "
                "on one line of the unit)",
            )
            continue
        scene = _scene_of(r, scenes, res.notes) if r.n_links is not None else None
        date, source = r.date, "given"
        if date is None and date_from_name(rel) is not None:
            date, source = date_from_name(rel), "file name"
        jobs.append(
            _Job(
                os.path.abspath(full),
                r.unit,
                r.speed_m_s,
                r.speed_sigma_m_s,
                nom,
                date,
                r.channel,
                sha,
                read_options,
                source,
                r.n_links,
                r.marker_s,
                scene,
            )
        )
    for r in rows:
        if r.line not in used:
            if r.is_glob:
                res.notes.append(f"catalogue line {r.line}: {r.file!r} matches no recording")
            elif any(r.file in (f, f.rsplit("/", 1)[-1]) for f in files):
                f = next(f for f in files if r.file in (f, f.rsplit("/", 1)[-1]))
                res.notes.append(
                    f"catalogue line {r.line}: {r.file!r} is also on line {_match(f, rows).line}, which is used"
                )
            else:
                fail(os.path.join(d, r.file), f"file not found (catalogue line {r.line})")
    bar = Progress(len(jobs), "fleet scan", enabled=progress)
    pending = []  # (job, measurement, link scan) analysed, not yet stored
    since = [0.0]

    def store():
        """One transaction for the analyses waiting (:meth:`FleetDB.insert_batch`)."""
        batch = list(pending)
        pending.clear()
        if not batch:
            return
        for (job, m, scan), got in zip(batch, db.insert_batch([(m, scan) for _j, m, scan in batch])):
            if isinstance(got, DuplicateRecordingError):
                res.skipped.append((job.path, str(got)))
            elif isinstance(got, FleetError):
                fail(job.path, str(got))
            else:
                res.added.append(got)
                if scan is not None:
                    res.link_scans[m.sha256] = scan

    def take(job, outcome):
        if not outcome["ok"]:
            fail(job.path, outcome["error"])
            return
        if not pending:
            since[0] = time.monotonic()
        pending.append((job, outcome["measurement"], outcome.get("link_scan")))
        if len(pending) >= BATCH_ROWS or time.monotonic() - since[0] >= BATCH_S:
            store()

    try:
        rest = jobs
        here = parallel is False or (parallel is None and client is None and not scheduler_address(scheduler))
        if jobs and here:
            w = n_workers or default_workers()
            fastest = math.inf
            for i, job in enumerate(jobs, 1):
                t0 = time.perf_counter()
                take(job, _analyse_job(job))
                fastest = min(fastest, time.perf_counter() - t0)
                bar.update(i)
                rest = jobs[i:]
                if parallel is None and i >= FILES_BEFORE_CHOOSING and dask_pays(fastest * len(rest), w):
                    break  # the files left end sooner on a local cluster
        if rest:
            _scan_dask(
                rest, take, bar, client=client, scheduler=scheduler, n_workers=n_workers, done=len(jobs) - len(rest)
            )
    finally:
        try:
            store()  # what was analysed is kept, also when the scan is interrupted (Ctrl-C, a lost cluster)
        finally:
            bar.close()
    return res


def _scene_of(row, scenes, notes):
    """The forward scene file of a row's escalator profile, built once per profile in a scan (None without one,
    or with a note when the profile's geometry gives no scene)."""
    if row.escalator is None:
        return None
    if row.escalator not in scenes:
        scenes[row.escalator] = profile_scene(row.escalator, notes)
    return scenes[row.escalator]


def _warm():
    """Worker side, once per worker (:func:`vibkit.runtime.cluster.warm_workers`): the analysis' imports, which
    unpickling this function began (this module's), finished with those its functions import as they run."""
    import scipy.interpolate  # noqa: F401 - the pitch analysis's, imported where they run
    import scipy.ndimage  # noqa: F401
    import scipy.signal  # noqa: F401


def _scan_dask(jobs, take, bar, *, client, scheduler, n_workers, done=0):
    import contextlib

    as_completed = require(
        "distributed", "parallel", "a fleet scan on worker processes (Dask; --workers 0 scans in this process)"
    ).as_completed

    ctx = contextlib.nullcontext(client) if client is not None else dask_client(scheduler, n_workers=n_workers)
    try:
        cl = ctx.__enter__()
    except (OSError, RuntimeError, TimeoutError, ValueError) as exc:
        where = f"the Dask scheduler at {scheduler}" if scheduler else "a local Dask cluster"
        raise FleetError(
            f"cannot start or reach {where}: {' '.join(str(exc).split()) or type(exc).__name__} "
            "(--workers 0 analyses in this process, without Dask)"
        ) from None
    with contextlib.ExitStack() as stack:
        stack.push(ctx)
        warm_workers(cl, _warm)
        futs = {}
        for i, job in enumerate(jobs):
            f = cl.submit(_analyse_job, job, key=f"vibkit-fleet-{job.sha256}-{i}", pure=False)
            futs[f] = job
        for n, f in enumerate(as_completed(list(futs)), 1):
            job = futs.pop(f)
            try:
                outcome = f.result()
            except Exception as exc:  # noqa: BLE001 - a lost worker fails one row, not the scan
                outcome = {
                    "ok": False,
                    "error": f"{job.path}: analysis lost ({type(exc).__name__}: {' '.join(str(exc).split())})",
                }
            f.release()
            take(job, outcome)
            bar.update(done + n)
