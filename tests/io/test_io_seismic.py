"""Waveform files through obspy: one variable per trace id, gaps as segments, units only when given."""

import numpy as np
import pytest

from vibkit.io import RecordingError, read_recording

obspy = pytest.importorskip("obspy")


def trace(cha, data, fs=100.0, start=0.0):
    tr = obspy.Trace(data=np.asarray(data))
    tr.stats.network, tr.stats.station, tr.stats.location, tr.stats.channel = "VK", "ESC", "", cha
    tr.stats.sampling_rate = fs
    tr.stats.starttime = obspy.UTCDateTime(2020, 1, 1) + start
    return tr


def test_sac_file_with_units_given(tmp_path):
    data = np.arange(50, dtype=np.float32)
    p = tmp_path / "z.sac"
    trace("HNZ", data, fs=50.0).write(str(p), format="SAC")
    ds = read_recording(p, units="g/1000")
    np.testing.assert_allclose(ds["vk_esc_hnz"].values, data * 9.80665 / 1000, rtol=1e-7)
    assert ds["vk_esc_hnz"].attrs["units"] == "m/s^2" and ds["vk_esc_hnz"].attrs["quantity"] == "acceleration"
    np.testing.assert_allclose(ds["time"].values, np.arange(50) / 50.0, atol=1e-9)
    assert ds.attrs["sample_rate_hz"] == 50.0
    assert "trace VK.ESC..HNZ in g/1000 (given)" in ds.attrs["history"]


def test_miniseed_with_a_gap_gives_segments(tmp_path):
    a = np.arange(100, dtype=np.int32)
    st = obspy.Stream([trace("HNZ", a), trace("HNZ", a + 1000, start=3.0)])
    p = tmp_path / "gap.mseed"
    st.write(str(p), format="MSEED")
    ds = read_recording(p)
    np.testing.assert_array_equal(ds["segment"].values, np.repeat([0, 1], 100))
    np.testing.assert_array_equal(ds["vk_esc_hnz"].values, np.r_[a, a + 1000].astype(float))
    np.testing.assert_allclose(ds["time"].values, np.r_[np.arange(100) / 100, 3 + np.arange(100) / 100], atol=1e-9)
    assert "2 segments" in ds.attrs["history"]


def test_channel_selection_and_differing_rates(tmp_path):
    st = obspy.Stream(
        [trace("HNZ", np.arange(100, dtype=np.int32)), trace("HNX", np.arange(50, dtype=np.int32), fs=50.0)]
    )
    p = tmp_path / "two.mseed"
    st.write(str(p), format="MSEED")
    with pytest.raises(RecordingError, match="different sampling rates"):
        read_recording(p)
    ds = read_recording(p, channel="HNX")
    assert list(ds.data_vars) == ["vk_esc_hnx"] and ds.attrs["sample_rate_hz"] == 50.0
    with pytest.raises(RecordingError, match="no trace 'HHZ'"):
        read_recording(p, channel="HHZ")


def test_unknown_unit_for_a_trace(tmp_path):
    p = tmp_path / "z.mseed"
    obspy.Stream([trace("HNZ", np.arange(10, dtype=np.int32))]).write(str(p), format="MSEED")
    with pytest.raises(ValueError, match="'parsecs' is not a unit"):
        read_recording(p, units="parsecs")
    with pytest.raises(ValueError, match="no trace 'HNX'"):
        read_recording(p, units={"HNX": "g"})
