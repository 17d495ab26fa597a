"""Sensor Logger's AccelerometerUncalibrated.csv (data/devices/sensor_logger, real iOS file, MIT): 'time'
is Unix epoch ns (UTC, not since boot), and the unit depends on the platform (g on iOS, m/s^2 on
Android), which only the Metadata.csv that the app writes beside it says."""

from __future__ import annotations

import shutil
from pathlib import Path

import pytest

from vibkit.io import read_recording
from vibkit.io.text.units import STANDARD_GRAVITY

F = Path(__file__).resolve().parents[2] / "data" / "devices" / "sensor_logger" / "AccelerometerUncalibrated.csv"
META = (
    "version,device name,recording time,platform,appVersion,device id,sensors,sampleRateMs\n"
    "3,iPhone 12 mini,2022-09-09_13-14-55,{platform},1.10.4,4fb87800,Accelerometer|AccelerometerUncalibrated,10|10"
)


def test_epoch_ns_start_and_no_unit_without_the_metadata():
    ds = read_recording(F)
    assert ds.attrs["start_time"] == "2023-11-11T20:21:49.763077+00:00"  # 1699734109763076400 ns
    assert ds.sizes["time"] == 1000 and ds.attrs["sample_rate_hz"] == pytest.approx(100.0, rel=0.01)
    # line 2: time 1699734109763076400, seconds_elapsed 0.0370..., then z, y, x
    assert [ds[v].values[0] for v in ("z", "y", "x")] == [-0.940948486328125, -0.2747650146484375, 0.0849761962890625]
    assert ds["z"].attrs["units"] == "unknown" and "no Metadata.csv beside the file" in ds.attrs["history"]


@pytest.mark.parametrize("platform, factor, unit", [("ios", STANDARD_GRAVITY, "m/s^2"), ("android", 1.0, "m/s^2")])
def test_the_platform_in_metadata_csv_gives_the_unit(tmp_path, platform, factor, unit):
    shutil.copy(F, tmp_path / F.name)
    (tmp_path / "Metadata.csv").write_text(META.format(platform=platform))
    ds = read_recording(tmp_path / F.name)
    assert ds["z"].attrs["units"] == unit
    assert ds["z"].values[0] == pytest.approx(-0.940948486328125 * factor, rel=1e-12)
    assert f"AccelerometerUncalibrated.csv on {platform} (Metadata.csv beside it)" in ds.attrs["history"]
