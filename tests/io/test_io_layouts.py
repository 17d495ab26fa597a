"""Every shipped logger layout read correctly: values, SI units, sample rate, channels, metadata.

Expected values are computed here from the raw file text (split by hand) and
the unit definitions, never taken from the reader.
"""

import hashlib
from pathlib import Path

import numpy as np
import pytest

from vibkit.io import read_recording

LAYOUTS = Path(__file__).resolve().parents[2] / "data" / "field" / "layouts"
G = 9.80665


def rows(path, skip, sep=",", encoding="utf-8", comment=None):
    out = []
    for ln in path.read_text(encoding=encoding).splitlines()[skip:]:
        if not ln.strip() or (comment and ln.startswith(comment)):
            continue
        out.append(ln.split(sep))
    return out


def check_contract(ds, path):
    assert list(ds.sizes) == ["time"]
    assert ds["time"].dtype == np.float64 and ds["time"].attrs["units"] == "s"
    assert np.all(np.diff(ds["time"].values) > 0)
    for name, var in ds.data_vars.items():
        if name == "segment":
            assert var.dtype == np.int32
            continue
        assert var.dtype == np.float64
        assert var.attrs["units"] and var.attrs["long_name"]
        assert var.attrs["quantity"] in ("displacement", "velocity", "acceleration", "other")
    assert ds.attrs["source_file"] == path.name
    assert ds.attrs["sha256"] == hashlib.sha256(path.read_bytes()).hexdigest()
    assert ds.attrs["reader"].startswith("vibkit.io.")
    assert isinstance(ds.attrs["sample_rate_hz"], float) and ds.attrs["sample_rate_hz"] > 0
    assert isinstance(ds.attrs["history"], str) and ds.attrs["history"]
    for v in ds.attrs.values():
        assert isinstance(v, (str, int, float))


def test_phyphox():
    path = LAYOUTS / "phyphox.csv"
    ds = read_recording(path)
    check_contract(ds, path)
    raw = np.array(rows(path, 1), dtype=float)
    np.testing.assert_array_equal(ds["time"].values, raw[:, 0])
    for j, axis in enumerate("xyz", start=1):
        var = ds[f"linear_acceleration_{axis}"]
        np.testing.assert_array_equal(var.values, raw[:, j])
        assert var.attrs["units"] == "m/s^2" and var.attrs["quantity"] == "acceleration"
        assert var.attrs["long_name"] == f"Linear Acceleration {axis}"
    # a phone clock: jittery steps; nominal rate from the time stamps (mean step)
    steps = np.diff(raw[:, 0])
    assert ds.attrs["sample_rate_hz"] == pytest.approx(1 / steps.mean(), rel=1e-9)
    rms = np.sqrt(np.mean((steps / steps.mean() - 1) ** 2))
    assert ds.attrs["time_jitter_rms_percent"] == pytest.approx(100 * rms, rel=1e-6)
    assert "jitter rms" in ds.attrs["history"] and "kept as is" in ds.attrs["history"]


def test_physics_toolbox_g_force_columns_become_m_per_s2():
    path = LAYOUTS / "physics-toolbox.csv"
    ds = read_recording(path)
    check_contract(ds, path)
    raw = np.array(rows(path, 1), dtype=float)
    for j, name in enumerate(["gfx", "gfy", "gfz", "tgf"], start=1):
        np.testing.assert_allclose(ds[name].values, raw[:, j] * G, rtol=1e-15)
        assert ds[name].attrs["units"] == "m/s^2"
    assert float(ds["gfz"].mean()) == pytest.approx(G, abs=0.05)
    assert "column 'gFz' in g -> m/s^2 (x 9.80665)" in ds.attrs["history"]


def test_endaq_timestamps_and_range_annotated_channels():
    path = LAYOUTS / "endaq.csv"
    ds = read_recording(path)
    check_contract(ds, path)
    np.testing.assert_allclose(ds["time"].values, np.arange(1000) / 1000.0, rtol=0, atol=1e-12)
    raw = np.array([r[1:] for r in rows(path, 6)], dtype=float)
    for j, name in enumerate("xyz"):
        np.testing.assert_allclose(ds[name].values, raw[:, j] * G, rtol=1e-15)
    assert ds.attrs["start_time"] == "2021-06-15T10:21:03.000000"
    assert ds.attrs["recorder"] == "S3-D16" and ds.attrs["serial_number"] == "SSN0001234"
    assert ds.attrs["sample_rate_hz"] == 1000.0


def test_gcdc_counts_scaled_from_the_header():
    path = LAYOUTS / "gcdc-x16.csv"
    ds = read_recording(path)
    check_contract(ds, path)
    raw = np.array(rows(path, 0, comment=";"), dtype=float)
    np.testing.assert_array_equal(ds["time"].values, raw[:, 0])
    for j, name in enumerate(["ax", "ay", "az"], start=1):
        np.testing.assert_allclose(ds[name].values, raw[:, j] * G / 2048, rtol=1e-15)
        assert ds[name].attrs["units"] == "m/s^2" and ds[name].attrs["original_units"] == "counts"
    assert float(ds["az"].mean()) == pytest.approx(-G, abs=0.05)  # lying flat: -1 g
    assert ds.attrs["sample_rate_hz"] == 400.0
    assert ds.attrs["start_time"] == "2019-03-12, 10:25:14.000"
    assert ds.attrs["shutdown"] == "switched off"  # the trailing ';' comment line


def test_spanish_spreadsheet():
    path = LAYOUTS / "spanish-spreadsheet.csv"
    ds = read_recording(path)
    check_contract(ds, path)
    raw = np.array([[c.replace(",", ".") for c in r] for r in rows(path, 7, ";", "cp1252")], dtype=float)
    np.testing.assert_allclose(ds["time"].values, raw[:, 0] * 1e-3, rtol=1e-15)
    np.testing.assert_allclose(ds["aceleracion"].values, raw[:, 1] * G, rtol=1e-15)
    np.testing.assert_allclose(ds["desplazamiento"].values, raw[:, 2] * 1e-3, rtol=1e-15)
    assert ds["aceleracion"].attrs["long_name"] == "Aceleración"
    assert ds["desplazamiento"].attrs["quantity"] == "displacement"
    assert ds.attrs["velocidad_m_s"] == 0.49
    assert ds.attrs["fecha"] == "12/03/2019"
    assert ds.attrs["sample_rate_hz"] == 500.0
    for decision in (
        "encoding cp1252",
        "delimiter ';' detected",
        "decimal comma detected",
        "time column 'Tiempo (ms)' in ms -> s (x 0.001)",
        "column 'Aceleración (g)' in g -> m/s^2 (x 9.80665)",
    ):
        assert decision in ds.attrs["history"]


def test_no_time_column_sample_rate_from_header():
    path = LAYOUTS / "no-time-column.txt"
    ds = read_recording(path)
    check_contract(ds, path)
    raw = np.array(rows(path, 3, "\t"), dtype=float)
    np.testing.assert_array_equal(ds["acc_z"].values, raw[:, 1])
    np.testing.assert_allclose(ds["time"].values, np.arange(len(raw)) / 2050.0, rtol=1e-15)
    assert ds.attrs["sample_rate_hz"] == 2050.0
    assert "no time column; time = sample index / 2050 Hz" in ds.attrs["history"]


def test_miniseed_written_with_obspy():
    obspy = pytest.importorskip("obspy")
    path = LAYOUTS / "station.mseed"
    ds = read_recording(path)
    check_contract(ds, path)
    st = obspy.read(str(path))
    assert sorted(ds.data_vars) == ["vk_esc01_00_hnx", "vk_esc01_00_hny", "vk_esc01_00_hnz"]
    for tr in st:
        var = ds[tr.id.replace(".", "_").lower()]
        np.testing.assert_array_equal(var.values, tr.data.astype(float))
        assert var.attrs["units"] == "counts" and var.attrs["trace_id"] == tr.id
    np.testing.assert_allclose(ds["time"].values, np.arange(1000) / 200.0, atol=1e-12)
    assert "no physical units; values kept in counts" in ds.attrs["history"]
    assert ds.attrs["reader"] == "vibkit.io.seismic" and ds.attrs["station"] == "ESC01"


@pytest.mark.parametrize(
    "line, start",
    [
        ("# start: 2026-09-01T06:00:00Z", "2026-09-01T06:00:00+00:00"),
        ("# Datum: 2026-09-01T06:00:00Z", "2026-09-01T06:00:00+00:00"),
        ("# recorded: 2026-09-01 06:00", "2026-09-01T06:00:00"),
        ("Start: 04.05.2026 07:30:00", "2026-05-04T07:30:00"),  # German day.month.year
        ("# date: 2026/05/04", "2026-05-04T00:00:00"),
        ("# Start time: 2026-09-01T06:00:00Z", "2026-09-01T06:00:00+00:00"),
        ("# date: 25/04/2026", "2026-04-25T00:00:00"),  # a day above 12: day/month
        ("Fecha de inicio: 04/25/2026 07:30", "2026-04-25T07:30:00"),  # month/day
        ("# start: 04.05.26 07:30", "2026-05-04T07:30:00"),  # a two-digit year
    ],
)
def test_a_start_stated_above_the_data_is_the_recordings_start(tmp_path, line, start):
    """A stranger's files stated their start under keys other than 'start_time' (start, Datum, recorded), and
    the report said "not stated in the file" and the fleet refused them. Any key that names a start, with a date
    it can read, is the start, and the history names the line."""
    import vibkit

    p = tmp_path / "rec.csv"
    rows = "".join(f"{i * 0.005:.3f},{0.001 * (i % 7):.4f}\n" for i in range(400))
    p.write_text(f"{line}\ntime (s),disp (mm)\n{rows}")
    rec = vibkit.read_recording(p)
    assert rec.attrs["start_time"] == start
    assert "from metadata line 1" in rec.attrs["history"]


def test_a_slashed_day_month_start_is_not_guessed(tmp_path):
    import vibkit

    p = tmp_path / "rec.csv"
    rows = "".join(f"{i * 0.005:.3f},{0.001 * (i % 7):.4f}\n" for i in range(400))
    p.write_text(f"# start: 04/05/2026\ntime (s),disp (mm)\n{rows}")
    rec = vibkit.read_recording(p)
    assert rec.attrs.get("start_time") is None  # 4 May or April 5th: not guessed
    assert "may be day/month or month/day: not read as the start (give the date: --date)" in rec.attrs["history"]


@pytest.mark.parametrize(
    "names, row", [("t [s],disp [mm],acc [g]", "{t:.3f},{x:.5f}"), ("t [s],disp [mm]", "{t:.3f},{x:.5f},0.001")]
)
def test_a_header_of_more_or_fewer_names_than_fields_is_refused(tmp_path, names, row):
    """A stranger's logger file named three columns and wrote two (or named two and wrote three): the names were
    kept as a metadata line, the columns became channel_0 ..., and the time ramp a channel `links` analysed."""
    import vibkit

    rows = "".join(row.format(t=i * 0.005, x=31.76 + 0.001 * (i % 7)) + "\n" for i in range(400))
    p = tmp_path / "rec.csv"
    p.write_text(f"# Logger DL-7\nSample rate: 200 Hz\n{names}\n{rows}")
    n_names = names.count(",") + 1
    with pytest.raises(
        vibkit.io.RecordingError, match=rf"line 4: expected {n_names} fields \(as in the header on line 3"
    ):
        vibkit.read_recording(p)
