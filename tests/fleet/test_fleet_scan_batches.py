"""A scan stores its analyses in batches, one transaction each, with the filter designs it reuses cached: every
stored number is the one a scan of one transaction per recording, designing every filter afresh, stores; a batch
refuses its bad rows one by one, and a batch that fails as a whole is stored row by row."""

import datetime as dt
import sqlite3

import numpy as np
import pytest
import scipy.signal

import vibkit.datasets
import vibkit.fleet.scan as scan_mod
import vibkit.signal._checks as checks
from vibkit.fleet import FleetDB
from vibkit.fleet.errors import DuplicateRecordingError, FleetError

from support.chain import random_phase_family

SPEED = 0.5  # [m/s]
NOMINAL = 0.4 / 3  # [m]
FS = 200.0  # [Hz]


def _synth(path, pitch, seed, duration=12.0):
    t = np.arange(int(duration * FS)) / FS
    x = random_phase_family(t, SPEED / pitch, np.random.default_rng(seed))
    np.savetxt(path, np.column_stack([t, x]), delimiter=",", header="time_s,accel_m_s2", comments="", fmt="%.6f")


@pytest.fixture(scope="module")
def synthetic(tmp_path_factory):
    """Six recordings of three units; one file twice (a duplicate in the same scan)."""
    d = tmp_path_factory.mktemp("visits")
    lines = ["file,unit,speed_m_s,date,nominal_pitch_m"]
    for i in range(6):
        _synth(d / f"v{i}.csv", NOMINAL * (1 + 0.002 * i), 40 + i)
        lines.append(f"v{i}.csv,U{i % 3},{SPEED},{dt.date(2025, 1, 1 + i)},{NOMINAL}")
    (d / "copy.csv").write_bytes((d / "v0.csv").read_bytes())
    lines.append(f"copy.csv,U0,{SPEED},2025-02-01,{NOMINAL}")
    cat = d.parent / "synthetic-units.csv"
    cat.write_text("\n".join(lines) + "\n")
    return d, cat


def _rows(db):
    """Every stored column but the row id and the time of the analysis, by file; the link scans by file."""
    ms = db.measurements()
    scans = db.link_scans()
    rows = {m.sha256: {k: v for k, v in m.as_dict().items() if k not in ("id", "analysed_utc")} for m in ms}
    links = {m.sha256: scans[m.id].as_dict() if m.id in scans else None for m in ms}
    return rows, links


def _scan(tmp_path, name, folder, cat):
    with FleetDB(tmp_path / name) as db:
        res = db.scan(folder, cat, parallel=False)
        return res, _rows(db)


@pytest.mark.parametrize("which", ["example fleet", "synthetic"])
def test_stored_rows_equal_those_of_one_transaction_per_file_and_fresh_designs(tmp_path, monkeypatch, synthetic, which):
    if which == "example fleet":
        folder = vibkit.datasets.path("fleet-example")
        cat = folder / "units.csv"
    else:
        folder, cat = synthetic
    after, (rows, links) = _scan(tmp_path, "after.sqlite", folder, cat)
    # before: one transaction per recording, every anti-alias filter designed afresh
    monkeypatch.setattr(scan_mod, "BATCH_ROWS", 1)
    monkeypatch.setattr(checks, "_decimation_sos", checks._decimation_sos.__wrapped__)
    before, (rows0, links0) = _scan(tmp_path, "before.sqlite", folder, cat)
    assert len(after.added) == len(before.added) == len(rows) >= 6
    assert [p for p, _w in after.skipped] == [p for p, _w in before.skipped]
    assert [p for p, _w in after.failed] == [p for p, _w in before.failed] == []
    assert rows.keys() == rows0.keys()
    for sha, row in rows.items():
        for col, value in row.items():
            assert value == rows0[sha][col], (row["path"], col)  # exact: the same arithmetic
    assert links == links0
    if which == "synthetic":
        assert len(after.skipped) == 1 and "same content" in after.skipped[0][1]


def test_decimation_filter_designed_once_is_the_fresh_design():
    x = np.random.default_rng(3).standard_normal(6000)
    checks._decimation_sos.cache_clear()
    for _ in range(2):  # designed, then taken from the cache
        y, fs, q = checks.decimate_for_band(x, 200.0, 7.5, oversample=5.0)
        cutoff = 0.8 * 200.0 / (2.0 * q)
        sos = scipy.signal.butter(8, cutoff, btype="low", fs=200.0, output="sos")
        ref = scipy.signal.sosfiltfilt(sos, x, padtype="even", padlen=min(x.size - 1, int(6.0 * 200.0 / cutoff)))
        assert (q, fs) == (5, 40.0)
        np.testing.assert_array_equal(y, ref[::q])
    assert checks._decimation_sos.cache_info().hits >= 1


def _measurement(tmp_path, synthetic, i, **change):
    from dataclasses import replace

    from vibkit.fleet.measurement import analyse_recording

    folder, _cat = synthetic
    m = analyse_recording(folder / f"v{i}.csv", unit=f"U{i % 3}", speed=SPEED, nominal_pitch=NOMINAL, date="2025-01-01")
    return replace(m, **change)


@pytest.fixture(params=["sqlite", "postgresql"])
def store_url(request, tmp_path):
    if request.param == "sqlite":
        return tmp_path / "batch.sqlite"
    return request.getfixturevalue("new_pg_url")()


def test_batch_refuses_bad_rows_one_by_one(tmp_path, synthetic, store_url):
    a = _measurement(tmp_path, synthetic, 0)
    b = _measurement(tmp_path, synthetic, 1)
    other_pitch = _measurement(tmp_path, synthetic, 2, unit="U1", nominal_pitch_m=0.135)
    with FleetDB(store_url) as db:
        got = db.insert_batch([(a, None), (b, None), (a, None), (other_pitch, None)])
        assert got[0].id is not None and got[1].id is not None and got[0].pitch_m == a.pitch_m
        assert isinstance(got[2], DuplicateRecordingError)
        assert isinstance(got[3], FleetError) and "nominal pitch" in str(got[3])
        stored = db.measurements()
        assert sorted(m.sha256 for m in stored) == sorted([a.sha256, b.sha256])
        assert set(db.link_scans()) == {m.id for m in stored}  # each row with its (not run) link scan
        assert db.insert_batch([]) == []


def test_batch_failing_as_a_whole_is_stored_row_by_row(tmp_path, synthetic, monkeypatch):
    ms = [_measurement(tmp_path, synthetic, i) for i in range(3)]
    with FleetDB(tmp_path / "f.sqlite") as db:
        store = db._store
        real = store._insert_row

        def flaky(values):  # the second file's row cannot be written (a disk error, say)
            if ms[1].sha256 in values:
                raise sqlite3.OperationalError("disk I/O error")
            return real(values)

        monkeypatch.setattr(store, "_insert_row", flaky)
        got = db.insert_batch([(m, None) for m in ms])
        assert got[0].sha256 == ms[0].sha256 and got[2].sha256 == ms[2].sha256
        assert isinstance(got[1], FleetError) and "disk I/O error" in str(got[1])
        stored = db.measurements()
        assert sorted(m.sha256 for m in stored) == sorted([ms[0].sha256, ms[2].sha256])
        assert set(db.link_scans()) == {m.id for m in stored}
        assert db.integrity_check() == "ok"


def test_a_scan_hands_the_files_left_to_a_cluster_where_that_pays(tmp_path, synthetic, monkeypatch):
    """With a start-up of no cost the rule sends the files left after the first two to the cluster's workers, which
    warm up first; the stored rows are those of the scan in this process."""
    import contextlib

    from distributed import Client

    import vibkit.runtime.cluster as cluster

    folder, cat = synthetic
    _res, (rows0, links0) = _scan(tmp_path, "here.sqlite", folder, cat)
    monkeypatch.setattr(cluster, "LOCAL_CLUSTER_START_S", 0.0)
    sent = []
    with Client(processes=False, n_workers=2, threads_per_worker=1, dashboard_address=":0") as c:
        monkeypatch.setattr(scan_mod, "dask_client", lambda scheduler=None, n_workers=None: contextlib.nullcontext(c))
        real = scan_mod._scan_dask
        monkeypatch.setattr(scan_mod, "_scan_dask", lambda jobs, *a, **k: sent.extend(jobs) or real(jobs, *a, **k))
        with FleetDB(tmp_path / "there.sqlite") as db:
            res = db.scan(folder, cat, n_workers=2)
            rows, links = _rows(db)
        # every worker holds the warm-up plugin (it ran as the plugin was registered)
        warm = c.run(lambda dask_worker: [n for n in dask_worker.plugins if n.startswith("vibkit-warm-")])
    assert len(sent) == len(res.added) - 2 > 0  # all but the first two files (the copy is no job: skipped)
    assert len(warm) == 2 and all(len(v) == 1 for v in warm.values())
    assert rows == rows0 and links == links0
