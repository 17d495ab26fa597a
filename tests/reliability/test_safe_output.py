"""vibkit.runtime.safe_output: regular files only, no clobbering, atomic, nothing left behind."""

import errno
import io
import os
import stat
import subprocess
import sys

import numpy as np
import pytest
import xarray as xr

import vibkit.runtime.safe_output as so
from vibkit.io import write_result


def _ds(n=1000):
    return xr.Dataset({"x": ("time", np.arange(float(n)), {"units": "m"})}, coords={"time": np.arange(float(n))})


def _temps(folder):
    return [p for p in os.listdir(folder) if so.TMP_MARK in p]


def test_written_atomically_with_the_umask_mode(tmp_path):
    out = tmp_path / "r.nc"
    write_result(_ds(), out, overwrite=False)
    back = xr.load_dataset(out, engine="h5netcdf")
    np.testing.assert_array_equal(back.x.values, np.arange(1000.0))
    umask = os.umask(0)
    os.umask(umask)
    assert stat.S_IMODE(out.stat().st_mode) == 0o666 & ~umask
    assert _temps(tmp_path) == []


def test_existing_file_needs_overwrite_and_inputs_never(tmp_path):
    out = tmp_path / "r.nc"
    out.write_bytes(b"precious")
    with pytest.raises(so.OutputError, match="already exists; give --force"):
        write_result(_ds(), out, overwrite=False)
    assert out.read_bytes() == b"precious"
    with pytest.raises(so.OutputError, match="is an input"):
        write_result(_ds(), out, overwrite=True, inputs=[str(out)])
    assert out.read_bytes() == b"precious"
    write_result(_ds(), out, overwrite=True)
    assert out.read_bytes()[:4] == b"\x89HDF"


@pytest.mark.parametrize("kind", ["symlink", "fifo", "folder", "device"])
def test_non_regular_targets_refused_even_with_overwrite(tmp_path, kind):
    target = tmp_path / "t.nc"
    if kind == "symlink":
        (tmp_path / "real.nc").write_bytes(b"real")
        os.symlink("real.nc", target)
    elif kind == "fifo":
        os.mkfifo(target)
    elif kind == "folder":
        target.mkdir()
    else:
        target = "/dev/null"
    before = os.lstat(target)
    with pytest.raises(so.OutputError):
        write_result(_ds(), target, overwrite=True)
    after = os.lstat(target)
    assert stat.S_IFMT(before.st_mode) == stat.S_IFMT(after.st_mode)
    if kind == "symlink":
        assert (tmp_path / "real.nc").read_bytes() == b"real" and os.readlink(target) == "real.nc"
    if kind != "device":
        assert _temps(tmp_path) == []


def test_read_only_file_refused_even_with_overwrite(tmp_path):
    out = tmp_path / "ro.nc"
    out.write_bytes(b"keep")
    out.chmod(0o444)
    with pytest.raises(so.OutputError, match="read-only"):
        write_result(_ds(), out, overwrite=True)
    assert out.read_bytes() == b"keep"


def test_a_file_appearing_while_writing_is_not_clobbered(tmp_path):
    out = tmp_path / "race.nc"
    with pytest.raises(so.OutputError, match="exists"):
        with so.atomic_output(out, overwrite=False) as tmp:
            with open(tmp, "wb") as f:
                f.write(b"new")
            out.write_bytes(b"theirs")  # another program was faster
    assert out.read_bytes() == b"theirs"
    assert _temps(tmp_path) == []


def test_error_inside_the_write_leaves_nothing(tmp_path):
    out = tmp_path / "e.nc"
    with pytest.raises(RuntimeError):
        with so.atomic_output(out) as tmp:
            assert os.path.basename(tmp) == f".e.nc{so.TMP_MARK}{os.getpid()}"
            raise RuntimeError("boom")
    assert not out.exists() and _temps(tmp_path) == []


def test_disk_full_is_an_oserror_and_leaves_nothing(tmp_path, monkeypatch):
    """ENOSPC simulated in the one place that writes data: a clean OSError, no temp, target intact."""
    out = tmp_path / "full.nc"
    out.write_bytes(b"old result")

    class Full(io.FileIO):
        def write(self, b):
            raise OSError(errno.ENOSPC, os.strerror(errno.ENOSPC))

    monkeypatch.setattr(so, "open", lambda p, mode="r", *a, **k: Full(p, "w"), raising=False)
    with pytest.raises(OSError) as exc:
        write_result(_ds(), out, overwrite=True)
    assert exc.value.errno == errno.ENOSPC
    assert out.read_bytes() == b"old result" and _temps(tmp_path) == []


def test_report_pdf_in_memory_then_disk_full(tmp_path, monkeypatch):
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    from matplotlib.backends.backend_pdf import PdfPages

    from vibkit.diagnose.report import _pdf_in_memory

    out = tmp_path / "r.pdf"
    with _pdf_in_memory(out, overwrite=False, inputs=()) as buf, PdfPages(buf) as pdf:
        fig = plt.figure()
        pdf.savefig(fig)
        plt.close(fig)
    assert out.read_bytes()[:5] == b"%PDF-"

    def full(p, mode="r", *a, **k):
        class F(io.FileIO):
            def write(self, b):
                raise OSError(errno.ENOSPC, os.strerror(errno.ENOSPC))

        return F(p, "w")

    monkeypatch.setattr(so, "open", full, raising=False)
    with pytest.raises(OSError, match="No space left"):
        with _pdf_in_memory(tmp_path / "full.pdf", overwrite=False, inputs=()) as buf, PdfPages(buf) as pdf:
            fig = plt.figure()
            pdf.savefig(fig)
            plt.close(fig)
    assert not (tmp_path / "full.pdf").exists() and _temps(tmp_path) == []


@pytest.mark.skipif(not hasattr(os, "getuid") or os.getuid() != 0, reason="mounting a tmpfs needs root")
def test_real_full_disk_on_a_tiny_tmpfs(tmp_path):
    mnt = tmp_path / "tiny"
    mnt.mkdir()
    if (
        subprocess.run(["mount", "-t", "tmpfs", "-o", "size=64k", "tmpfs", str(mnt)], capture_output=True).returncode
        != 0
    ):
        pytest.skip("cannot mount a tmpfs here (no CAP_SYS_ADMIN)")
    try:
        with pytest.raises(OSError) as exc:
            write_result(_ds(100_000), mnt / "big.nc")  # 1.6 MB into 64 kB
        assert exc.value.errno == errno.ENOSPC
        assert os.listdir(mnt) == []
    finally:
        subprocess.run(["umount", str(mnt)], check=False)


def test_stale_temporaries_of_dead_processes_only(tmp_path):
    out = tmp_path / "x.nc"
    dead = subprocess.Popen([sys.executable, "-c", "pass"])
    dead.wait()
    stale = tmp_path / f".x.nc{so.TMP_MARK}{dead.pid}"
    live = tmp_path / f".x.nc{so.TMP_MARK}{os.getppid()}"  # our parent runs
    other = tmp_path / f".y.nc{so.TMP_MARK}{dead.pid}"  # another output's: not ours to judge now
    for p in (stale, live, other):
        p.write_bytes(b"partial")
    removed = so.clean_stale_temporaries(out)
    assert removed == [str(stale)]
    assert live.exists() and other.exists() and not stale.exists()


def test_check_output_path_messages(tmp_path):
    with pytest.raises(so.OutputError, match="empty"):
        so.check_output_path("")
    with pytest.raises(so.OutputError, match="does not exist"):
        so.check_output_path(tmp_path / "no" / "x.nc")
    with pytest.raises(so.OutputError, match="names a folder"):
        so.check_output_path(str(tmp_path) + "/")
    assert so.check_output_path(tmp_path / "new.nc") == str(tmp_path / "new.nc")


def test_cli_interrupt_exit_codes(monkeypatch, tmp_path, capsys):
    """Ctrl-C exits 130 and SIGTERM 143, one line on stderr, no traceback."""
    import signal

    import vibkit
    from vibkit.cli import main

    scene = tmp_path / "s.toml"
    scene.write_text((__import__("pathlib").Path(__file__).parents[2] / "sim" / "thesis-kinematics.toml").read_text())

    def interrupted(*a, **k):
        raise KeyboardInterrupt

    monkeypatch.setattr(vibkit, "simulate", interrupted, raising=False)
    assert main(["simulate", str(scene), "-o", str(tmp_path / "o.nc")]) == 130
    assert capsys.readouterr().err.strip() == "vibkit simulate: interrupted; nothing was written"

    def terminated(*a, **k):
        os.kill(os.getpid(), signal.SIGTERM)  # the handler main() installed turns it into an exception

    monkeypatch.setattr(vibkit, "simulate", terminated, raising=False)
    assert main(["simulate", str(scene), "-o", str(tmp_path / "o.nc")]) == 143
    assert "interrupted (signal 15)" in capsys.readouterr().err
    assert signal.getsignal(signal.SIGTERM) == signal.SIG_DFL
