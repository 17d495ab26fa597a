"""Phone exports in the layouts of the real ones tried (``benchmarks/results/phone_exports.md``), written by the
tests: Sensor Logger's ``Accelerometer.csv`` has gravity removed and its ``Gravity.csv`` beside it; its earlier
exports write ``time,z,y,x``; a phone's clock repeats a stamp."""

from __future__ import annotations

import zipfile

import numpy as np
import pytest

import vibkit
from vibkit.io import RecordingError
from vibkit.signal.stillness import LEAVE_THRESHOLD, STILL_THRESHOLD, still_spans, walking_level

FS = 100.0
STEP_HZ = 1.9  # a walker's steps per second
AMP = 1.5  # the step's vertical acceleration [m/s^2]
G = 9.80665
TILT = np.deg2rad(20.0)  # the phone's z axis this far from the vertical, towards its y axis


def _walk(seconds=20.0, seed=0):
    """Time [s], the phone's acceleration with gravity removed and gravity, both (3, N) in the phone's axes [m/s^2].

    The step puts ``AMP`` sin(2 pi STEP_HZ t) on the vertical; the phone's z axis is tilted by ``TILT``."""
    rng = np.random.default_rng(seed)
    t = np.arange(0.0, seconds, 1 / FS)
    vertical = AMP * np.sin(2 * np.pi * STEP_HZ * t)
    up = np.array([0.0, np.sin(TILT), np.cos(TILT)])  # the vertical in the phone's axes
    free = up[:, None] * vertical + 0.02 * rng.standard_normal((3, t.size))
    gravity = np.repeat((G * up)[:, None], t.size, axis=1)
    return t, free, gravity


def _sensor_logger_csv(t, xyz, elapsed=True):
    """A Sensor Logger sensor file: Unix epoch in ns, (seconds_elapsed,) then the axes in the order z, y, x."""
    ns = 1_711_795_430_071_476_200 + np.round(t * 1e9).astype(np.int64)
    head = "time,seconds_elapsed,z,y,x" if elapsed else "time,z,y,x"
    rows = [head]
    for i in range(t.size):
        cells = [str(ns[i])] + ([f"{t[i] + 0.07:.9f}"] if elapsed else []) + [f"{v:.9f}" for v in xyz[::-1, i]]
        rows.append(",".join(cells))
    return "\n".join(rows) + "\n"


def _export(folder, t, free, gravity=None, elapsed=True, gyro_t=None):
    folder.mkdir()
    (folder / "Accelerometer.csv").write_text(_sensor_logger_csv(t, free, elapsed))
    gt = t if gyro_t is None else gyro_t
    (folder / "Gyroscope.csv").write_text(_sensor_logger_csv(gt, 0.01 * np.ones((3, gt.size)), elapsed))
    if gravity is not None:
        (folder / "Gravity.csv").write_text(_sensor_logger_csv(t, gravity, elapsed))
    return folder


def _acc(ds):
    return np.vstack([ds[f"acc_{a}"].values for a in "xyz"])


@pytest.mark.parametrize("elapsed", [True, False], ids=["time,seconds_elapsed,z,y,x", "time,z,y,x"])
def test_gravity_added_back_so_a_walk_is_not_taken_for_standing(tmp_path, elapsed):
    """What the phone read, gravity and all: |a| = |g + a_step| ~ g + AMP sin(...), whose walking band holds the
    step at AMP / sqrt(2) r.m.s., as the stillness thresholds were measured on (a phone with gravity)."""
    t, free, gravity = _walk()
    ds = vibkit.read_recording(_export(tmp_path / "walk", t, free, gravity, elapsed))
    np.testing.assert_allclose(_acc(ds), free + gravity, atol=1e-6)
    assert "gravity removed; Gravity.csv (in m/s^2) added back" in ds.attrs["history"]
    level = walking_level(_acc(ds), FS)[int(2 * FS) : -int(2 * FS)]
    assert np.median(level) == pytest.approx(AMP / np.sqrt(2), rel=0.1)
    assert still_spans(walking_level(_acc(ds), FS), FS, min_s=6.0) == []
    assert STILL_THRESHOLD < LEAVE_THRESHOLD < np.median(level)


def test_gravity_removed_and_no_gravity_file_reads_and_says_so(tmp_path):
    """A phone in a pocket, gravity removed, no units in the file and no Gravity.csv: |a| reads about 4 m/s^2 (once
    refused as neither m/s^2 nor g with gravity); read as m/s^2 with gravity removed, said in the history."""
    t, free, _ = _walk()
    free = free * (4.0 / AMP)
    folder = tmp_path / "pocket"
    folder.mkdir()
    (folder / "accelerometer.csv").write_text(
        "\n".join(f"{ti:.3f},{a:.6f},{b:.6f},{c:.6f}" for ti, (a, b, c) in zip(t, free.T)) + "\n"
    )
    (folder / "gyro.csv").write_text("\n".join(f"{ti:.3f},0.01,0.01,0.01" for ti in t) + "\n")
    ds = vibkit.read_recording(folder)
    np.testing.assert_allclose(_acc(ds), free, atol=1e-6)
    assert "acceleration with gravity removed, taken as m/s^2" in ds.attrs["history"]
    assert "no gravity file beside it" in ds.attrs["history"]


@pytest.mark.parametrize("scale, unit", [(1.0, "m/s^2"), (1 / G, "g")])
def test_gravity_in_either_unit_is_told_by_its_steady_part(tmp_path, scale, unit):
    t, free, gravity = _walk()
    folder = tmp_path / "hand"
    folder.mkdir()
    total = (free + gravity) * scale
    (folder / "accelerometer.csv").write_text(
        "\n".join(f"{ti:.3f},{a:.7f},{b:.7f},{c:.7f}" for ti, (a, b, c) in zip(t, total.T)) + "\n"
    )
    (folder / "gyro.csv").write_text("\n".join(f"{ti:.3f},0.01,0.01,0.01" for ti in t) + "\n")
    ds = vibkit.read_recording(folder)
    np.testing.assert_allclose(_acc(ds), free + gravity, atol=1e-4)
    assert f"gravity its steady part, so {unit}" in ds.attrs["history"]


def test_a_steady_part_that_is_no_gravity_is_refused_naming_the_file(tmp_path):
    """Raw counts (2048 a g): steady, but neither 9.81 m/s^2 nor 1 g."""
    t, free, gravity = _walk()
    folder = tmp_path / "counts"
    folder.mkdir()
    counts = np.round((free + gravity) / G * 2048)
    (folder / "accelerometer.csv").write_text(
        "\n".join(f"{ti:.3f},{a:.0f},{b:.0f},{c:.0f}" for ti, (a, b, c) in zip(t, counts.T)) + "\n"
    )
    (folder / "gyro.csv").write_text("\n".join(f"{ti:.3f},0.01,0.01,0.01" for ti in t) + "\n")
    with pytest.raises(RecordingError, match=r"accelerometer\.csv.*its steady part no gravity; expected an acceler"):
        vibkit.read_recording(folder)


def test_a_repeated_stamp_in_one_sensor_file_is_repaired_when_asked(tmp_path):
    """Android clocks repeat a stamp now and then: refused naming the sensor's file and line, and read with
    ``repair_time`` (``--repair-time``), which reaches every file of the export."""
    t, free, gravity = _walk()
    gt = t.copy()
    gt[500] = gt[499]
    folder = _export(tmp_path / "walk", t, free, gravity, gyro_t=gt)
    with pytest.raises(RecordingError, match=r"Gyroscope\.csv, line 502: .*repeats"):
        vibkit.read_recording(folder)
    ds = vibkit.read_recording(folder, repair_time=True)
    assert ds.sizes["time"] == t.size
    assert ds["gyro_x"].values == pytest.approx(0.01)


def _phyphox_rows(t, total, sep, dec):
    def num(v):
        return f"{v:.9E}".replace(".", dec)

    return "\n".join(sep.join(num(v) for v in (ti, *row)) for ti, row in zip(t, total.T)) + "\n"


@pytest.mark.parametrize(
    "data_file, header, sep, dec",
    [
        (
            "Rohdaten.csv",
            '"Zeit (s)";"Beschleunigung x (m/s^2)";"Beschleunigung y (m/s^2)";"Beschleunigung z (m/s^2)"',
            ";",
            ",",
        ),
        (
            "Données brutes.csv",
            '"Temps (s)","Accélération x (m/s^2)","Accélération y (m/s^2)","Accélération z (m/s^2)"',
            ",",
            ".",
        ),
        (
            "Dados brutos.csv",
            '"Tempo (s)";"Aceleração x (m/s^2)";"Aceleração y (m/s^2)";"Aceleração z (m/s^2)"',
            ";",
            ",",
        ),
        (
            "Raw Data.csv",
            '"Time (s)","Acceleration x (m/s^2)","Acceleration y (m/s^2)","Acceleration z (m/s^2)"',
            ",",
            ".",
        ),
    ],
)
def test_a_phyphox_export_in_the_phones_language_reads_as_its_accelerometer(tmp_path, data_file, header, sep, dec):
    """phyphox names its data file after the export set in the phone's language and writes its header in it; the
    zip (beside ``meta/``) is the recording, its one data file sorted by the header's word for acceleration."""
    t, free, gravity = _walk()
    z = tmp_path / "Beschleunigung mit g 2024-05-01 10-00-00.zip"
    with zipfile.ZipFile(z, "w") as zf:
        zf.writestr(data_file, header + "\n" + _phyphox_rows(t, free + gravity, sep, dec))
        zf.writestr("meta/device.csv", f'"property"{sep}"value"\n"deviceModel"{sep}"Pixel 7"\n')
    ds = vibkit.read_recording(z)
    np.testing.assert_allclose(_acc(ds), free + gravity, rtol=1e-8, atol=1e-8)
    assert f"accelerometer {data_file}" in ds.attrs["history"]
