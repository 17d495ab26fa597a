"""WAV files written by scipy.io.wavfile: float32, float64 and int16, mono and stereo."""

from __future__ import annotations

import numpy as np
import pytest

from vibkit.io import RecordingError, read_recording
from vibkit.io.registry import detect_format
from vibkit.io.text.units import STANDARD_GRAVITY

wavfile = pytest.importorskip("scipy.io.wavfile")

FS = 8000
T = np.arange(4000) / FS
X = 0.25 * np.sin(2 * np.pi * 100.0 * T)


@pytest.mark.parametrize("dtype", [np.float32, np.float64])
def test_float_wav_read_as_written(tmp_path, dtype):
    p = tmp_path / "f.wav"
    wavfile.write(p, FS, np.column_stack([X, -X]).astype(dtype))
    assert detect_format(p, p.read_bytes()).name == "wav"
    ds = read_recording(p)
    assert ds.attrs["reader"] == "vibkit.io.wav" and list(ds.data_vars) == ["channel_1", "channel_2"]
    assert ds.attrs["sample_rate_hz"] == FS
    np.testing.assert_allclose(ds["time"].values, T, rtol=0, atol=1e-12)
    np.testing.assert_array_equal(ds["channel_1"].values, X.astype(dtype).astype(np.float64))
    np.testing.assert_array_equal(ds["channel_2"].values, -X.astype(dtype).astype(np.float64))
    assert ds["channel_1"].attrs["units"] == "unknown"  # a WAV file states no unit
    g = read_recording(p, units="g")  # ... the caller does
    np.testing.assert_allclose(g["channel_1"].values, X.astype(dtype).astype(np.float64) * STANDARD_GRAVITY, rtol=1e-12)


def test_int16_wav_in_counts_scaled_by_units(tmp_path):
    p = tmp_path / "i.wav"
    counts = np.round(X * 32767).astype(np.int16)
    wavfile.write(p, FS, counts)
    ds = read_recording(p)
    assert ds["channel_1"].attrs["units"] == "counts"
    np.testing.assert_array_equal(ds["channel_1"].values, counts.astype(float))
    assert "full scale 32768" in ds.attrs["history"]
    g = read_recording(p, units="g/32768")
    np.testing.assert_allclose(g["channel_1"].values, counts * STANDARD_GRAVITY / 32768, rtol=1e-12)


def test_damaged_wav_is_one_line_naming_the_file(tmp_path):
    p = tmp_path / "cut.wav"
    p.write_bytes(b"RIFF\x24\x00\x00\x00WAVEfmt \x10\x00\x00\x00\x03\x00")
    with pytest.raises(RecordingError, match=r"cut\.wav: cannot read as a WAV file"):
        read_recording(p)
