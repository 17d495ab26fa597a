"""The reader table: every shipped file is read by the entry expected of it, in a fixed order, and by name.

Each file under data/ that vibkit ships is listed here with the format entry that must read it and,
for a logger's layout, the history line its profile writes; a file added to data/ without a line here
fails :func:`test_every_shipped_file_is_listed`.
"""

from __future__ import annotations

from pathlib import Path

import pytest

from vibkit.io import RecordingError, format_names, read_recording
from vibkit.io.registry import FORMATS, detect_format, get_format
from vibkit.io.text.loggers import PROFILES

DATA = Path(__file__).resolve().parents[2] / "data"
READER_ATTR = {
    "netcdf": "vibkit.io.netcdf",
    "seismic": "vibkit.io.seismic",
    "text": "vibkit.io.csv",
    "e4": "vibkit.io.devices.e4",
    "actigraph": "vibkit.io.devices.actigraph",
    "lvm": "vibkit.io.lvm",
    "gzip": "vibkit.io.devices.actigraph",  # the one shipped .gz holds an ActiGraph export
}

#: file -> (format entry, text the history must hold: the logger profile's decision, or None)
SHIPPED = {
    "field/las-palmas-accelerometer.csv": ("text", "sample rate 2050 Hz (header line 10, 'Sample rate')"),
    "field/leon-tensioner.csv": ("text", "sample rate 200 Hz (header line 13, 'Sample rate')"),
    "field/layouts/endaq.csv": ("text", "'(100g)' read as a 100 g sensor range, values in g"),
    "field/layouts/gcdc-x16.csv": ("text", "column names from header line 9 ('Headers')"),
    "field/layouts/no-time-column.txt": ("text", "time = sample index / 2050 Hz"),
    "field/layouts/phyphox.csv": ("text", None),
    "field/layouts/physics-toolbox.csv": ("text", "'gFz' is a g-force column (Physics Toolbox), values in g"),
    "field/layouts/spanish-spreadsheet.csv": ("text", "'Frecuencia de muestreo'"),
    "field/layouts/station.mseed": ("seismic", None),
    **{
        f"fleet-example/{e}/{d}.csv": ("text", None)
        for e in ("E07", "E12", "E21")
        for d in ("2024-11-20", "2025-11-19", "2026-11-23")
    },
    "thirdparty/obspy_BI008_MEMA-04823.evt": ("seismic", None),
    "thirdparty/obspy_acc.gse": ("seismic", None),
    "thirdparty/obspy_gaps.mseed": ("seismic", None),
    "thirdparty/obspy_seism.sac": ("seismic", None),
    "thirdparty/obspy_slist.ascii": ("seismic", None),
    "thirdparty/obspy_test.knet": ("seismic", None),
    "thirdparty/obspy_tspair.ascii": ("seismic", None),
    "thirdparty/obspy_two_channels.mseed": ("seismic", None),
    "thirdparty/phyphox_elevator_linear_acc.csv": ("text", None),
    "thirdparty/phyphox_pendulum_acc_with_g.csv": ("text", None),
    "thirdparty/phyphox_rollercoaster_acc_with_g.csv": ("text", None),
    "thirdparty/phyphox_walking_linear_accelerometer.csv": ("text", None),
    "thirdparty/physicstoolbox_multi_gforce_linacc_gyro_daily.csv": ("text", "Physics Toolbox Sensor Suite export"),
    "thirdparty/physicstoolbox_multi_gforce_linacc_gyro_xmoves.csv": ("text", "Physics Toolbox Sensor Suite export"),
    "thirdparty/picoquake_car_vibration.csv": ("text", "PicoQuake export ('# PLab PicoQuake Data')"),
    "thirdparty/sensorlogger_driving_total_acceleration.csv": ("text", "for TotalAcceleration.csv (file name)"),
    "thirdparty/sensorlogger_imu_accelerometer.csv": ("text", "for Accelerometer.csv (file name)"),
    "thirdparty/sensorlogger_walking_pdr_accelerometer.csv": ("text", "for Accelerometer.csv (file name)"),
    "devices/actigraph/exampleRAW.csv.gz": ("gzip", "gzip file unpacked: exampleRAW.csv"),
    **{f"devices/empatica_e4/{n}.csv": ("e4", "Empatica E4 export") for n in ("ACC", "BVP", "EDA", "HR", "TEMP")},
    **{
        f"devices/labview/{n}.lvm": ("lvm", "LabVIEW Measurement file")
        for n in (
            "long_single_header_first2048",
            "multi_time_column",
            "no_decimal_separator",
            "short",
            "with_comments",
            "with_empty_fields",
        )
    },
    "devices/science_journal/Untitled Experiment Trial 1.csv": ("text", None),
    "devices/sensor_logger/AccelerometerUncalibrated.csv": ("text", "g on iOS and m/s^2 on Android"),
}
#: shipped files that are not recordings: the entry named refuses them in one line
NOT_RECORDINGS = {
    # a catalogue: no column of numbers (file names, units, empty dates, profile paths), so it is no time series
    "fleet-example/units.csv": ("text", "no data rows found"),
    "devices/empatica_e4/IBI.csv": ("e4", "not a sampled signal"),
}
#: files beside the data that no reader is meant for (scripts, notes, escalator profiles)
SKIP_SUFFIXES = (".py", ".md", ".json", ".toml")


def test_every_shipped_file_is_listed():
    shipped = {
        p.relative_to(DATA).as_posix()
        for p in DATA.rglob("*")
        if p.is_file() and not p.name.startswith(".") and p.suffix not in SKIP_SUFFIXES
    }
    assert shipped == set(SHIPPED) | set(NOT_RECORDINGS)


@pytest.mark.parametrize("rel", sorted(SHIPPED))
def test_shipped_file_read_by_its_entry(rel):
    fmt, history = SHIPPED[rel]
    path = DATA / rel
    assert detect_format(path, path.read_bytes()).name == fmt
    ds = read_recording(path)
    assert ds.attrs["reader"] == READER_ATTR[fmt]
    if history is not None:
        assert history in ds.attrs["history"]


@pytest.mark.parametrize("rel", sorted(NOT_RECORDINGS))
def test_shipped_non_recording_refused_by_its_entry(rel):
    path = DATA / rel
    assert detect_format(path, path.read_bytes()).name == NOT_RECORDINGS[rel][0]
    with pytest.raises(RecordingError, match=NOT_RECORDINGS[rel][1]):
        read_recording(path)


def _witmotion_packets(n):
    """``n`` WitMotion packets: 0x55, type 0x51-0x54, 8 data bytes, checksum (low byte of the sum)."""
    out = b""
    for k in range(n):
        p = bytes([0x55, 0x51 + k % 4]) + bytes(range(k, k + 8))
        out += p + bytes([sum(p) & 0xFF])
    return out


def test_order_is_fixed_and_the_last_entry_claims_everything():
    assert format_names() == (
        "matlab",
        "hdf5",
        "netcdf",
        "gzip",
        "spreadsheet",
        "zip",
        "witmotion",
        "wav",
        "tdms",
        "uff",
        "ide",
        "seismic",
        "e4",
        "actigraph",
        "lvm",
        "text",
    )
    assert [f.name for f in FORMATS] == list(format_names())
    hdf5 = b"\x89HDF\r\n\x1a\n" + b"\x00" * 64
    cases = [  # (name, bytes, encoding, entry): each claimed by two sniffers goes to the first of them
        ("x.mseed", hdf5, None, "hdf5"),  # HDF5 signature beats a seismic suffix
        ("x.h5", hdf5 + b"_NCProperties", None, "netcdf"),  # ... netCDF-4's attributes make it netCDF
        ("x.nc", hdf5, None, "netcdf"),
        ("x.csv", b"MATLAB 5.0 MAT-file, Platform: x" + b"\x00" * 90, None, "matlab"),
        ("x.mat", b"time,a\n0,1\n", None, "matlab"),  # a .mat suffix whatever the content
        ("x.csv", b"RIFF\x24\x00\x00\x00WAVEfmt ", None, "wav"),
        ("x.dat", b"TDSm" + b"\x00" * 24, None, "tdms"),
        ("x.csv", b"    -1\n    58\nid1\n", None, "uff"),  # UFF is never read as CSV
        ("x.mseed", b"    -1\n    58b     1     2    11\n", None, "uff"),
        ("x.csv", b"-1\n7\n3\n", None, "text"),  # a column of integers starting with -1 is no UFF
        ("x.nc", b"time,a\n0,1\n", None, "netcdf"),  # a netCDF suffix whatever the content
        ("x.csv", b"CDF\x01" + b"\x00" * 32, None, "netcdf"),
        ("x.csv", b"\x00\x01\x02binary", None, "seismic"),  # NUL bytes, not UTF-16: binary
        ("x.csv", b"\x00\x01\x02binary", "latin-1", "text"),  # ... unless an encoding says it is text
        ("x.csv", "time,a\n0,1\n".encode("utf-16-le"), None, "text"),  # UTF-16 without a byte-order mark
        ("x.csv", "\ufefftime,a\n0,1\n".encode("utf-16"), None, "text"),
        ("x.mseed", b"time,a\n0,1\n", None, "seismic"),  # a seismic suffix whatever the content
        ("x.txt", b"TIMESERIES XX_TEST__BHZ_R, 6 samples, 10 sps\n", None, "seismic"),
        ("x.txt", b"time,a\n0,1\n", None, "text"),
        ("noext", bytes(range(1, 256)), None, "text"),  # no NUL, no signature: the last entry
        ("x.mseed", b"\x1f\x8b\x08\x00" + b"\x00" * 16, None, "gzip"),  # a container signature beats a suffix
        ("x.csv", b"PK\x03\x04" + b"\x00" * 26, None, "zip"),
        ("x.TXT", _witmotion_packets(6), None, "witmotion"),  # binary with valid 0x55 packets: named
        ("x.TXT", b"\x55\x51" + b"\x00" * 64, None, "seismic"),  # 0x55 without valid checksums: binary
        ("x.csv", b"1680686620.000000\n32.000000\n-34\n", None, "e4"),
        ("x.csv", b"------------ Data File Created By ActiGraph GT3X+ at 30 Hz -----------\n", None, "actigraph"),
        ("x.txt", b"LabVIEW Measurement\t\nWriter_Version\t2\n", None, "lvm"),
        ("x.csv", b"1680686620\n32\n", None, "text"),  # two rows only: not an E4 export
    ]
    for name, data, encoding, want in cases:
        got = [detect_format(name, data, encoding).name for _ in range(3)]
        assert got == [want] * 3, (name, data[:12], encoding)


def test_format_by_name(tmp_path):
    path = DATA / "field/layouts/phyphox.csv"
    auto, named = read_recording(path), read_recording(path, format="TEXT")
    assert auto.identical(named) and auto.attrs == named.attrs
    assert get_format("seismic") is FORMATS[format_names().index("seismic")]
    with pytest.raises(
        ValueError, match=r"format must be one of 'matlab', 'hdf5', 'netcdf', .*'lvm', 'text', got 'xlsx'"
    ):
        read_recording(path, format="xlsx")
    with pytest.raises(ValueError, match="format must be one of"):
        read_recording(path, format=3)
    with pytest.raises(RecordingError, match="phyphox.csv"):  # the named entry reads it, or says why not
        read_recording(path, format="netcdf")


def test_logger_profiles_are_one_entry_each():
    names = [p.name for p in PROFILES]
    assert len(names) == len(set(names))
    for p in PROFILES:
        assert p.source and p.facts, p.name
        assert (p.recognise is None) == (p.column_units is None), p.name
