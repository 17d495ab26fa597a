"""MATLAB MAT-files: v5 written by scipy.io.savemat, v7.3 written with h5py in MATLAB's own layout.

The v7.3 file is what MATLAB's ``save -v7.3`` writes: a 512-byte user block opening with
``MATLAB 7.3 MAT-file``, each variable an HDF5 dataset with a ``MATLAB_class`` attribute, stored
column-major (an N x 2 matrix is a 2 x N dataset), char arrays as UTF-16 code units, structs as
groups and cell arrays as object references into ``#refs#``.  Values are known sines; units are
checked against their SI factors.
"""

from __future__ import annotations

import numpy as np
import pytest

from vibkit.io import RecordingError, read_recording
from vibkit.io.registry import detect_format
from vibkit.io.text.units import STANDARD_GRAVITY

scipy_io = pytest.importorskip("scipy.io")
h5py = pytest.importorskip("h5py")

FS = 512.0
N = 1024
T = np.arange(N) / FS
X = 0.5 * np.sin(2 * np.pi * 25.0 * T)
Y = 0.2 * np.cos(2 * np.pi * 40.0 * T)


def test_v5_matrix_with_fs_and_a_cell_array_of_units(tmp_path):
    p = tmp_path / "run.mat"
    units = np.array(["g", "m/s^2"], dtype=object)
    scipy_io.savemat(p, {"data": np.column_stack([X, Y]), "fs": FS, "units": units})
    assert detect_format(p, p.read_bytes()).name == "matlab"
    ds = read_recording(p)
    assert ds.attrs["reader"] == "vibkit.io.matlab"
    assert list(ds.data_vars) == ["data_1", "data_2"]
    assert ds.attrs["sample_rate_hz"] == FS
    np.testing.assert_allclose(ds["time"].values, T, rtol=0, atol=1e-12)
    assert ds["data_1"].attrs["units"] == "m/s^2" and ds["data_1"].attrs["quantity"] == "acceleration"
    np.testing.assert_allclose(ds["data_1"].values, X * STANDARD_GRAVITY, rtol=1e-12)  # g -> m/s^2
    np.testing.assert_allclose(ds["data_2"].values, Y, rtol=1e-12)
    assert "MATLAB 5.0 MAT-file" in ds.attrs["history"]


def test_v5_struct_with_a_time_vector_and_channel_choice(tmp_path):
    p = tmp_path / "s.mat"
    scipy_io.savemat(p, {"rec": {"t": T, "acc": X, "acc_units": "mm/s^2", "temp": Y}})
    ds = read_recording(p, channel="rec.acc")
    assert list(ds.data_vars) == ["rec_acc"]
    np.testing.assert_allclose(ds["rec_acc"].values, X * 1e-3, rtol=1e-12)
    assert ds.attrs["sample_rate_hz"] == pytest.approx(FS, rel=1e-9)  # from the time vector's mean step


def test_v5_without_a_time_base_names_what_is_missing(tmp_path):
    p = tmp_path / "bare.mat"
    scipy_io.savemat(p, {"acc": X})
    with pytest.raises(RecordingError, match=r"bare\.mat: no time base: expected a time vector .*variables \(acc\)"):
        read_recording(p)
    ds = read_recording(p, sample_rate=FS)  # ... or sample_rate= gives it
    assert ds.attrs["sample_rate_hz"] == FS and ds.sizes["time"] == N


def test_v5_arrays_of_different_lengths_refused_until_chosen(tmp_path):
    p = tmp_path / "mixed.mat"
    scipy_io.savemat(p, {"a": X, "b": X[:100], "fs": FS})
    with pytest.raises(RecordingError, match=r"mixed\.mat: variables of different lengths \(a: 1024, b: 100\)"):
        read_recording(p)
    assert read_recording(p, channel="a").sizes["time"] == N


def test_mat_suffix_on_text_is_not_read_as_csv(tmp_path):
    p = tmp_path / "fake.mat"
    p.write_text("time,a\n0,1\n1,2\n")
    with pytest.raises(RecordingError, match=r"fake\.mat: cannot read as a MATLAB MAT-file"):
        read_recording(p)


def _v73(path, variables):
    """Write ``variables`` as MATLAB ``save -v7.3`` does (see the module docstring)."""
    with h5py.File(path, "w", userblock_size=512) as f:
        refs = f.create_group("#refs#")

        def put(group, name, value):
            if isinstance(value, dict):
                g = group.create_group(name)
                g.attrs["MATLAB_class"] = np.bytes_("struct")
                for k, v in value.items():
                    put(g, k, v)
            elif isinstance(value, str):
                d = group.create_dataset(name, data=np.array([[ord(c)] for c in value], dtype=np.uint16))
                d.attrs["MATLAB_class"] = np.bytes_("char")
            elif isinstance(value, list):  # a cell array of char
                rs = []
                for i, s in enumerate(value):
                    d = refs.create_dataset(f"{name}{i}", data=np.array([[ord(c)] for c in s], dtype=np.uint16))
                    d.attrs["MATLAB_class"] = np.bytes_("char")
                    rs.append(d.ref)
                d = group.create_dataset(name, data=np.array([rs], dtype=h5py.ref_dtype).T)
                d.attrs["MATLAB_class"] = np.bytes_("cell")
            else:
                a = np.atleast_2d(np.asarray(value, dtype=np.float64))
                if a.shape[0] == 1 and a.size > 1:
                    a = a.T  # a column vector, as MATLAB users keep samples
                d = group.create_dataset(name, data=a.T)  # column-major: MATLAB's N x C is C x N here
                d.attrs["MATLAB_class"] = np.bytes_("double")

        for k, v in variables.items():
            put(f, k, v)
    head = b"MATLAB 7.3 MAT-file, Platform: GLNXA64, Created on: Mon Dec  7 05:00:00 2026 HDF5 schema 1.00 ."
    head = head.ljust(116, b" ") + b"\x00" * 8 + b"\x00\x02" + b"IM"
    with open(path, "r+b") as fh:
        fh.write(head.ljust(512, b"\x00"))


def test_v73_matrix_struct_and_units(tmp_path):
    p = tmp_path / "big.mat"
    _v73(p, {"data": np.column_stack([X, Y]), "Fs": FS, "units": ["g", "mm/s^2"], "info": {"operator": "ana"}})
    raw = p.read_bytes()
    assert raw.startswith(b"MATLAB 7.3 MAT-file") and raw[512:520] == b"\x89HDF\r\n\x1a\n"
    assert detect_format(p, raw).name == "matlab"
    ds = read_recording(p)
    assert ds.attrs["reader"] == "vibkit.io.matlab" and ds.attrs["format"] == "MATLAB 7.3"
    assert list(ds.data_vars) == ["data_1", "data_2"] and ds.sizes["time"] == N
    np.testing.assert_allclose(ds["data_1"].values, X * STANDARD_GRAVITY, rtol=1e-12)
    np.testing.assert_allclose(ds["data_2"].values, Y * 1e-3, rtol=1e-12)
    assert ds.attrs["sample_rate_hz"] == FS


def test_v73_vectors_in_a_struct_with_a_time_vector(tmp_path):
    p = tmp_path / "s73.mat"
    _v73(p, {"rec": {"time": T + 10.0, "x": X, "x_units": "m"}})
    ds = read_recording(p)
    assert list(ds.data_vars) == ["rec_x"] and ds["rec_x"].attrs["units"] == "m"
    np.testing.assert_allclose(ds["time"].values, T + 10.0, rtol=0, atol=1e-12)
    np.testing.assert_allclose(ds["rec_x"].values, X, rtol=1e-12)
