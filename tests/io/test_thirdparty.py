"""The third-party corpus (data/thirdparty): each file read with no options against what was read by hand.

``expected.json`` holds, per file, the sample rate, the time column and its unit, the channels and their
units as the file or its documentation states them (see SOURCES.md).  vibkit converts units to SI, so a
channel's unit is compared through :func:`vibkit.io.text.units.parse_unit` (``g`` -> ``m/s^2``).  Columns that
count samples (PicoQuake's ``count``) and other clocks (Sensor Logger's ``seconds_elapsed``) are no channels.
"""

from __future__ import annotations

import json
from pathlib import Path

import pytest

from vibkit.io import read_recording
from vibkit.io.text.units import parse_unit

ROOT = Path(__file__).resolve().parents[2] / "data" / "thirdparty"
EXPECTED = json.loads((ROOT / "expected.json").read_text(encoding="utf-8"))

#: files that need an option, and the one line naming the flag that fixes them
NEEDS_A_FLAG = {
    "physicstoolbox_multi_gforce_linacc_gyro_xmoves.csv": "rows come every 66 us to 12.9 ms and are split into bursts at gaps, so the rate inside bursts "
    "(447 Hz) is not the rows' mean rate (441 Hz): --sample-rate 441.17 states it",
}


def _si(unit_text):
    u = parse_unit(unit_text.split(" (")[0])  # 'counts (calib 7.248 nm/count per header)': a note after the unit
    return unit_text if u is None else u.si


def read_facts(name, **options):
    ds = read_recording(ROOT / name, **options)
    chans = {}
    for v in ds.data_vars:
        if v == "segment":
            continue
        a = ds[v].attrs
        name = a.get("trace_id") or a.get("source_name") or v
        chans["".join(name.split()) if "trace_id" in a else name] = (a["units"], a.get("original_units"))
    return ds, chans


def check(name, ds, chans):
    e = EXPECTED[name]
    assert ds.attrs["sample_rate_hz"] == pytest.approx(e["sample_rate_hz"], rel=0.01), name
    assert ds["time"].attrs.get("column") == e["time_column"], name
    assert list(chans) == list(e["channels"]), name
    for ch, unit in e["channels"].items():
        assert chans[ch][0] == _si(unit), (name, ch, chans[ch], unit)


@pytest.mark.parametrize("name", sorted(EXPECTED))
def test_each_file_reads_right_with_no_options_or_with_the_flag_named(name):
    if name in NEEDS_A_FLAG:
        with pytest.raises(AssertionError):
            check(name, *read_facts(name))
        assert "--sample-rate" in NEEDS_A_FLAG[name]
        check(name, *read_facts(name, sample_rate=441.17))
    else:
        check(name, *read_facts(name))


def test_at_least_90_percent_read_right_with_no_options():
    assert (len(EXPECTED) - len(NEEDS_A_FLAG)) / len(EXPECTED) >= 0.9
    assert len(EXPECTED) >= 18


def test_time_units_as_found():
    ds = read_recording(ROOT / "sensorlogger_imu_accelerometer.csv")
    assert EXPECTED["sensorlogger_imu_accelerometer.csv"]["time_unit"] == "ns"
    assert "Unix epoch times in ns" in ds.attrs["history"]
    assert "seconds_elapsed" not in ds and "'seconds_elapsed' is another clock" in ds.attrs["history"]


def test_knet_calibration_gives_the_headers_peak_acceleration():
    # header: 'Max. Acc. (gal) 4.383' = the largest |a - mean| of the record; 1 gal = 0.01 m/s^2
    ds = read_recording(ROOT / "obspy_test.knet")
    a = ds["bo_akt013_ew"].values
    assert ds["bo_akt013_ew"].attrs["units"] == "m/s^2"
    assert abs(a - a.mean()).max() == pytest.approx(4.383e-2, rel=1e-3)
    assert "K-NET header 'Scale Factor'" in ds.attrs["history"]
    raw = read_recording(ROOT / "obspy_test.knet", units="counts")  # the raw counts, for a scale of one's own
    assert raw["bo_akt013_ew"].attrs["units"] == "counts"
    assert abs(raw["bo_akt013_ew"].values - a / 2.384185791015625e-06).max() < 1e-6


def test_physics_toolbox_held_samples_give_the_true_update_rate():
    ds = read_recording(ROOT / "physicstoolbox_multi_gforce_linacc_gyro_daily.csv")
    e = EXPECTED["physicstoolbox_multi_gforce_linacc_gyro_daily.csv"]["update_rate_hz"]["gFx"]
    assert ds["gfx"].attrs["update_rate_hz"] == pytest.approx(e, rel=0.01)
    assert ds.attrs["nyquist_hz"] == pytest.approx(e / 2, rel=0.01)
    assert "held samples" in ds.attrs["history"] and "Nyquist frequency 7.33 Hz" in ds.attrs["history"]
    xm = read_recording(ROOT / "physicstoolbox_multi_gforce_linacc_gyro_xmoves.csv")
    assert "update_rate_hz" not in xm["gfx"].attrs  # gF updates with (nearly) every row there
    assert "update_rate_hz" not in xm.attrs


def test_picoquake_rate_from_its_config_comment():
    ds = read_recording(ROOT / "picoquake_car_vibration.csv")
    assert "header line 4, 'data_rate'" in ds.attrs["history"]
    assert ds["count"].attrs["sample_counter"] == 1 and "count" in ds.coords and "count" not in ds.data_vars
    assert ds["a_x"].attrs["original_units"] == "g" and ds["g_x"].attrs["original_units"] == "deg/s"


def test_held_samples_said_on_the_command_line(capsys):
    from vibkit.cli import main

    main(["spectrum", str(ROOT / "physicstoolbox_multi_gforce_linacc_gyro_daily.csv")])
    err = capsys.readouterr().err
    assert "values held between updates (rows at 43.96 Hz, updates at 14.7 Hz)" in err
    assert "nothing above 7.33 Hz (their Nyquist frequency)" in err
