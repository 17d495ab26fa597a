"""UFF/UNV dataset 58 (time responses): a file written by hand following the universal file
specification, and files written by pyuff (ASCII and binary 58b); UFF is never read as CSV."""

from __future__ import annotations

import numpy as np
import pytest

from vibkit.io import RecordingError, read_recording
from vibkit.io.registry import detect_format
from vibkit.io.text.units import STANDARD_GRAVITY
from vibkit.io.uff import rate_from_increment

FS = 1024.0
T = np.arange(300) / FS
X = 2.5 * np.sin(2 * np.pi * 50.0 * T)


def _e(v, width=13, digits=5):
    return f"{v:{width}.{digits}E}"


def _dataset58(node, direction, values, *, func=1, unit="g", dx=1.0 / FS, ord_type=2):
    """One dataset 58 as the specification lays it out (single precision: 6E13.5 per line)."""
    rows = ["    -1", "    58", "Hand-written time response".ljust(80), "NONE".ljust(80)]
    rows += ["07-DEC-26 05:00:00".ljust(80), "NONE".ljust(80), "NONE".ljust(80)]
    rows.append(f"{func:5d}{0:10d}{0:5d}{0:10d} {'NONE':10s}{node:10d}{direction:4d} {'NONE':10s}{0:10d}{0:4d}")
    rows.append(f"{ord_type:10d}{len(values):10d}{1:10d}{_e(0.0)}{_e(dx)}{_e(0.0)}")
    rows.append(f"{17:10d}{0:5d}{0:5d}{0:5d} {'Time':20s} {'s':20s}")
    rows.append(f"{12:10d}{0:5d}{0:5d}{0:5d} {'Acceleration':20s} {unit:20s}")
    rows.append(f"{0:10d}{0:5d}{0:5d}{0:5d} {'NONE':20s} {'NONE':20s}")
    rows.append(f"{0:10d}{0:5d}{0:5d}{0:5d} {'NONE':20s} {'NONE':20s}")
    for k in range(0, len(values), 6):
        rows.append("".join(_e(v) for v in values[k : k + 6]))  # negative values run into their neighbours
    rows.append("    -1")
    return "\n".join(rows) + "\n"


def test_hand_written_two_channels_in_g(tmp_path):
    p = tmp_path / "hand.uff"
    header151 = "    -1\n   151\nmodel\nNONE\nvibkit\n07-DEC-26\n\nvibkit\n07-DEC-26\n    -1\n"
    p.write_text(header151 + _dataset58(12, 3, X) + _dataset58(12, 2, -X))
    assert detect_format(p, p.read_bytes()).name == "uff"
    ds = read_recording(p)
    assert ds.attrs["reader"] == "vibkit.io.uff"
    assert list(ds.data_vars) == ["node_12_z", "node_12_y"]
    assert ds["node_12_z"].attrs["long_name"] == "node 12 +Z" and ds["node_12_z"].attrs["units"] == "m/s^2"
    x5 = np.array([float(_e(v)) for v in X])  # the file holds six significant digits
    np.testing.assert_allclose(ds["node_12_z"].values, x5 * STANDARD_GRAVITY, rtol=1e-12)
    np.testing.assert_allclose(ds["node_12_y"].values, -x5 * STANDARD_GRAVITY, rtol=1e-12)
    assert ds.attrs["sample_rate_hz"] == FS  # 9.76563E-04 s is 1/1024 s rounded: said in the history
    assert "is 1/1024 s written with 6 significant digits" in ds.attrs["history"]
    assert "datasets other than 58 skipped: 151" in ds.attrs["history"]
    np.testing.assert_allclose(ds["time"].values, T, rtol=0, atol=1e-12)


def test_uff_is_never_read_as_csv(tmp_path):
    p = tmp_path / "export.txt"  # whatever the suffix
    p.write_text(_dataset58(1, 1, X[:17]))
    assert detect_format(p, p.read_bytes()).name == "uff"
    ds = read_recording(p)
    assert ds.attrs["reader"] == "vibkit.io.uff" and ds.sizes["time"] == 17
    assert detect_format(p.with_suffix(".csv"), p.read_bytes()).name == "uff"  # a .csv suffix too


def test_frf_and_complex_refused_with_the_line(tmp_path):
    p = tmp_path / "frf.unv"
    p.write_text(_dataset58(3, 1, X[:12], func=4))
    with pytest.raises(RecordingError, match=r"frf\.unv, line 8: dataset 58 holds function type 4 \(frequency"):
        read_recording(p)
    q = tmp_path / "cplx.unv"
    q.write_text(_dataset58(3, 1, X[:12], ord_type=5))
    with pytest.raises(RecordingError, match=r"cplx\.unv, line 9: .*ordinate data type 5"):
        read_recording(q)


def test_cut_short_and_different_time_bases(tmp_path):
    p = tmp_path / "cut.uff"
    p.write_text(_dataset58(1, 1, X[:30]).rsplit("    -1", 1)[0])
    with pytest.raises(RecordingError, match=r"cut\.uff.*not closed by a '-1' delimiter line"):
        read_recording(p)
    q = tmp_path / "two.uff"
    q.write_text(_dataset58(1, 1, X[:30]) + _dataset58(2, 1, X[:30], dx=1 / 512))
    with pytest.raises(RecordingError, match=r"two\.uff, line \d+: .*does not share the time base"):
        read_recording(q)
    assert list(read_recording(q, channel="node 2 +X").data_vars) == ["node_2_x"]


def test_rate_from_increment():
    assert rate_from_increment("9.76563E-04")[0] == 1024.0  # 1/1024 s = 9.765625E-04 rounded up
    assert rate_from_increment("9.76562E-04")[0] == 1024.0  # ... or to even, as C's printf does
    assert rate_from_increment("1.00000E-03") == (1000.0, None)
    fs, note = rate_from_increment("9.76600E-04")  # not a rounded whole rate: 1/increment
    assert fs == pytest.approx(1 / 9.766e-4, rel=1e-12) and note is None


# pyuff leaves the file of a binary write open (its own handle, closed by the garbage collector)
@pytest.mark.filterwarnings("ignore::ResourceWarning", "ignore::pytest.PytestUnraisableExceptionWarning")
@pytest.mark.parametrize("binary", [0, 1])
def test_written_by_pyuff(tmp_path, binary):
    pyuff = pytest.importorskip("pyuff")
    p = tmp_path / f"py{binary}.uff"
    u = pyuff.UFF(str(p))
    for node, sign in ((7, 1.0), (8, -1.0)):
        d = pyuff.prepare_58(
            binary=binary,
            func_type=1,
            rsp_node=node,
            rsp_dir=3,
            ref_node=0,
            ref_dir=0,
            ord_data_type=4,
            abscissa_spacing=1,
            abscissa_spec_data_type=17,
            abscissa_axis_units_lab="s",
            ordinate_spec_data_type=12,
            ordinate_axis_units_lab="m/s^2",
            orddenom_spec_data_type=0,
            z_axis_spec_data_type=0,
            data=sign * X,
            x=T,
            id1="pyuff time response",
        )
        u.write_sets(d, mode="add")
    assert detect_format(p, p.read_bytes()).name == "uff"
    ds = read_recording(p)
    assert list(ds.data_vars) == ["node_7_z", "node_8_z"] and ds.attrs["sample_rate_hz"] == FS
    np.testing.assert_allclose(ds["node_7_z"].values, X, rtol=1e-10, atol=1e-12)  # %20.11e or binary doubles
    np.testing.assert_allclose(ds["node_8_z"].values, -X, rtol=1e-10, atol=1e-12)
    assert ds["node_7_z"].attrs["units"] == "m/s^2" and ds["node_7_z"].attrs["description"] == "pyuff time response"
