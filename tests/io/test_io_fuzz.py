"""Property-based tests: the CSV reader returns a valid recording or raises RecordingError, nothing else."""

import numpy as np
import pytest
from hypothesis import HealthCheck, assume, given, settings
from hypothesis import strategies as st

from vibkit.io import RecordingError, read_recording

SETTINGS = settings(
    max_examples=150, deadline=None, suppress_health_check=[HealthCheck.function_scoped_fixture, HealthCheck.too_slow]
)
ALPHABET = st.sampled_from(list("0123456789.,;\t |\n\r-+eE#:=\"'abcxyzNaT()[]/sgm ") + ["nan", "1e999", "ó", "\x00"])


def valid(ds):
    assert list(ds.sizes) == ["time"] and ds.sizes["time"] >= 2
    t = ds["time"].values
    assert t.dtype == np.float64 and np.all(np.isfinite(t)) and np.all(np.diff(t) > 0)
    assert ds.data_vars
    for name, var in ds.data_vars.items():
        if name != "segment":
            assert var.dtype == np.float64 and not np.all(np.isnan(var.values))
            assert {"units", "long_name", "quantity"} <= set(var.attrs)
            assert not np.any(np.isinf(var.values))
    for key in ("source_file", "sha256", "reader", "sample_rate_hz", "history"):
        assert key in ds.attrs
    assert np.isfinite(ds.attrs["sample_rate_hz"]) and ds.attrs["sample_rate_hz"] > 0


def read_or_error(path, **kw):
    try:
        ds = read_recording(path, **kw)
    except RecordingError as err:
        assert "\n" not in str(err) and str(err).startswith(str(path))
        return None
    valid(ds)
    return ds


@SETTINGS
@given(text=st.lists(ALPHABET, max_size=300).map("".join))
def test_random_text(tmp_path, text):
    p = tmp_path / "fuzz.csv"
    p.write_bytes(text.encode("utf-8"))
    read_or_error(p, sample_rate=100.0)
    read_or_error(p)


@SETTINGS
@given(data=st.binary(max_size=600))
def test_random_bytes(tmp_path, data):
    p = tmp_path / "fuzz.dat"
    p.write_bytes(data)
    read_or_error(p)


@pytest.mark.slow
@SETTINGS
@given(
    nrows=st.integers(2, 40),
    values=st.lists(st.floats(-1e6, 1e6, allow_nan=False), min_size=160, max_size=160),
    nchan=st.integers(1, 4),
    sep=st.sampled_from([",", ";", "\t", " "]),
    comma=st.booleans(),
    unit=st.sampled_from([("s", 1.0), ("ms", 1e-3)]),
    chan_unit=st.sampled_from([("m/s^2", 1.0), ("g", 9.80665), ("mm", 1e-3)]),
    meta=st.lists(st.sampled_from(["# note", "Operator: Ana", "Sample rate: 100 Hz", ""]), max_size=3),
    step=st.floats(0.5, 10.0),
)
def test_written_tables_read_back(tmp_path, nrows, values, nchan, sep, comma, unit, chan_unit, meta, step):
    dec = "," if comma and sep != "," else "."
    t = np.arange(nrows) * round(step, 3)
    x = np.asarray(values[: nrows * nchan]).reshape(nrows, nchan) if nrows * nchan <= 160 else None
    assume(x is not None)
    names = [f"ch{j}_{chan_unit[0]}" if sep == " " else f"ch{j} ({chan_unit[0]})" for j in range(nchan)]
    if sep == " " and chan_unit[0] == "m/s^2":
        names = [f"ch{j}_m/s2" for j in range(nchan)]
    tname = f"time_{unit[0]}" if sep == " " else f"time ({unit[0]})"
    lines = list(meta) + [sep.join([tname] + names)]
    for i in range(nrows):
        cells = [f"{t[i]:.3f}"] + [f"{v:.6e}" for v in x[i]]
        lines.append(sep.join(c.replace(".", dec) for c in cells))
    p = tmp_path / "table.csv"
    p.write_text("\n".join(lines) + "\n", encoding="utf-8")
    ds = read_recording(p)
    valid(ds)
    np.testing.assert_allclose(ds["time"].values, t * unit[1], rtol=1e-12, atol=1e-12)
    for j in range(nchan):
        got = ds[f"ch{j}"].values
        np.testing.assert_allclose(got, x[:, j] * chan_unit[1], rtol=1e-6, atol=0)
        assert ds[f"ch{j}"].attrs["units"] == ("m" if chan_unit[0] == "mm" else "m/s^2")
