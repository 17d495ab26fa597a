"""A phone on a step, or held by someone standing on one: read as phone apps export it, its ride placed where its
link-pass line is, and no ride invented from the integral of its noise (a firm's phone files, 120 s in phyphox's layout:
`ride` once reported 10.3 s at -0.069 m/s on an up escalator from noise)."""

import io
import json
import math
import zipfile

import numpy as np
import pytest

import vibkit
from vibkit.cli import main
from vibkit.io import RecordingError
from vibkit.signal.ride import BRIDGE_1PCT, detect_ride_segment, integrated_noise

from ..signal.test_signal_ride import synthetic_ride

G = 9.80665
PHYPHOX_ACC = '"Time (s)","Acceleration x (m/s^2)","Acceleration y (m/s^2)","Acceleration z (m/s^2)"'
META = {
    "meta/device.csv": '"property","value"\n"deviceModel","Pixel 7"\n',
    "meta/time.csv": '"event","experiment time"\n',
}


def _phone_on_a_step(seed, *, f=3.75, duration=120.0, fs=100.0, noise=0.05):
    """A phone lying on a step for a whole ride of a unit (phyphox's layout; its clock jitters by 0.5 ms): the link
    pass with a harmonic on x and z, weak on y, and no vertical motion at all, as a firm's units' phone files have it."""
    rng = np.random.default_rng(seed)
    t = np.sort(np.arange(0.0, duration, 1.0 / fs) + rng.normal(0.0, 5e-4, int(duration * fs)))
    ph = 2 * np.pi * f * t
    x = 0.08 * np.sin(ph) + 0.03 * np.sin(2 * ph + 1) + noise * rng.standard_normal(t.size)
    y = 0.005 * np.sin(ph) + noise * rng.standard_normal(t.size)
    z = G + 0.06 * np.sin(ph + 0.5) + 0.02 * np.sin(2 * ph) + noise * rng.standard_normal(t.size)
    return np.c_[t, x, y, z]


def _csv(header, rows):
    b = io.StringIO()
    b.write(header + "\n")
    np.savetxt(b, rows, delimiter=",", fmt="%.6f")
    return b.getvalue()


def _zip(path, files):
    with zipfile.ZipFile(path, "w") as zf:
        for name, text in files.items():
            zf.writestr(name, text)
    return path


@pytest.mark.parametrize("name", ["Accelerometer.csv", "Raw Data.csv"])
def test_a_phyphox_export_of_one_sensor_reads_as_a_phone(tmp_path, name):
    """phyphox's export of one experiment is its data file beside a ``meta/`` folder (a single-sensor experiment
    names it "Raw Data.csv", its header saying which sensor): one recording of the phone's accelerometer, from the
    zip and from the unpacked folder alike, every sample as written."""
    rows = _phone_on_a_step(0, duration=20.0)
    files = {name: _csv(PHYPHOX_ACC, rows), **META}
    z = _zip(tmp_path / "phyphox.zip", files)
    folder = tmp_path / "unpacked"
    (folder / "meta").mkdir(parents=True)
    for n, text in files.items():
        (folder / n).write_text(text)
    for path in (z, folder):
        ds = vibkit.read_recording(path)
        assert [v for v in ds.data_vars if v != "segment"] == ["acc_x", "acc_y", "acc_z"]
        assert {ds[v].attrs["sensor"] for v in ("acc_x", "acc_y", "acc_z")} == {"accelerometer"}
        assert ds.sizes["time"] == rows.shape[0]
        assert np.allclose(ds["acc_z"].values, rows[:, 3], atol=1e-6)


def test_a_raw_data_file_of_another_sensor_is_no_accelerometer(tmp_path):
    """A "Raw Data.csv" whose header names the gyroscope is not read as an accelerometer."""
    rows = _phone_on_a_step(1, duration=10.0)
    gyro = '"Time (s)","Gyroscope x (rad/s)","Gyroscope y (rad/s)","Gyroscope z (rad/s)"'
    z = _zip(tmp_path / "gyro.zip", {"Raw Data.csv": _csv(gyro, rows), **META})
    with pytest.raises(RecordingError, match="expected exactly one recording"):
        vibkit.read_recording(z)


@pytest.mark.parametrize("seed", [0, 1, 2])
def test_ride_of_a_phone_on_a_step_is_where_its_line_is(tmp_path, capsys, seed):
    """Three units' phone files with the link pass all through and no climb (a firm's phone files): the ride is
    the line's span (all of the record but the second trimmed at each end), placed by the line and said so, with
    no vertical speed read from the integral of the noise (the old detector found 10.3 s at -0.069 m/s)."""
    z = _zip(tmp_path / f"unit{seed}.zip", {"Accelerometer.csv": _csv(PHYPHOX_ACC, _phone_on_a_step(seed)), **META})
    rc = main(["ride", str(z), "--json"])
    out = json.loads(capsys.readouterr().out)
    assert rc == 0
    seg = out["segment"]
    assert seg["method"] == "the link-pass line"
    assert seg["start_s"] <= 2.0 and seg["end_s"] >= 118.0
    assert "3.750 Hz" in seg["note"] and "direction unknown" in seg["note"]
    assert "plateau" not in json.dumps(seg) and "vertical" not in json.dumps(seg)


def test_a_phone_without_a_line_is_refused_naming_its_spans(tmp_path, capsys):
    """A phone record of noise alone (nobody walking, no chain) is no ride: one line naming the still span's
    verdict and the flag that gives a ride by hand, exit 1."""
    rng = np.random.default_rng(9)
    t = np.arange(0.0, 60.0, 0.01)
    a = np.c_[t, 0.05 * rng.standard_normal((t.size, 2)), G + 0.05 * rng.standard_normal(t.size)]
    z = _zip(tmp_path / "noise.zip", {"Accelerometer.csv": _csv(PHYPHOX_ACC, a), **META})
    rc = main(["ride", str(z)])
    err = capsys.readouterr().err
    assert rc == 1 and err.count("\n") == 1
    assert "no escalator ride found" in err and "0.0-60.0 s: no ride" in err and "--segment START:END" in err
    assert "Traceback" not in err


def test_integrated_noise_is_the_random_walk_of_white_noise():
    """White noise of sigma s at fs integrates to a random walk of sigma s sqrt(T / fs) over T: the scale read from
    its spectrum agrees to 10 % (twenty records of 60 s)."""
    rng = np.random.default_rng(3)
    fs, s, dur = 100.0, 0.05, 60.0
    got = [integrated_noise(s * rng.standard_normal(int(fs * dur)), fs) for _ in range(20)]
    assert np.mean(got) == pytest.approx(s * math.sqrt(dur / fs), rel=0.1)


def test_noise_alone_gives_a_step_ride_once_in_a_hundred_records():
    """The vertical-speed detector's false rides on white noise (no floor on the speed, 30-150 s records): at most
    the stated 1 % (Kolmogorov's 1 % point of a Brownian bridge), 400 records; without the noise test the same
    records give a 'ride' every time (the old 0.05 m/s floor alone passed 0.069 m/s of noise)."""
    rng = np.random.default_rng(5)
    fs, n_rec = 100.0, 400
    rides = 0
    for _ in range(n_rec):
        e = 0.05 * rng.standard_normal(int(fs * rng.uniform(30.0, 150.0)))
        try:
            detect_ride_segment(fs, vertical=G + e, min_vertical_speed=0.0)
            rides += 1
        except ValueError as exc:
            assert "noise gives by chance" in str(exc)
    # binomial: 400 records at 1 %, 9 or more false rides has probability 0.02
    assert rides <= 8


def test_a_step_ride_stands_out_of_noise_as_strong_as_a_phones():
    """A step's ride (0.25 m/s up the incline) with a phone's noise (0.05 m/s^2 at 100 Hz, three times the old
    tests' 0.02): still found where it is, its wander threshold well under the plateau."""
    fs = 100.0
    ax, az, start, end = synthetic_ride(fs, noise=0.05, landing_s=10.0, incline_len=10.0)
    seg = detect_ride_segment(fs, vertical=az, along=ax)
    assert seg.method == "vertical speed"
    assert seg.start_s == pytest.approx(start, abs=0.5) and seg.end_s == pytest.approx(end, abs=0.5)
    assert BRIDGE_1PCT * integrated_noise(az, fs) < 0.5 * abs(seg.plateau)
