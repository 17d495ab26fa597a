"""Reading a recording takes memory in proportion to the file, never a buffer of the size limit."""

from __future__ import annotations

import io
import os
import subprocess
import sys
import textwrap
from pathlib import Path

import pytest

from vibkit.io import read_bounded

ROOT = Path(__file__).resolve().parents[2]
FIELD = ROOT / "data" / "field" / "las-palmas-accelerometer.csv"


@pytest.mark.skipif(sys.platform != "linux", reason="RLIMIT_AS is enforced on Linux")
def test_field_file_read_under_a_3_GB_address_limit():
    # the default limit is 4 GiB: reserving it up front fails under a 3 GB address space
    code = textwrap.dedent(
        f"""
        import resource
        resource.setrlimit(resource.RLIMIT_AS, (3_000_000_000, 3_000_000_000))
        import vibkit
        ds = vibkit.read_recording({str(FIELD)!r})
        print(ds.sizes["time"])
        """
    )
    env = dict(os.environ, PYTHONPATH=os.pathsep.join([str(ROOT), os.environ.get("PYTHONPATH", "")]))
    env["NUMBA_NUM_THREADS"] = "1"  # each thread stack counts against the address limit
    proc = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, env=env, timeout=300)
    assert proc.returncode == 0, proc.stderr[-2000:]
    assert int(proc.stdout.split()[-1]) == 24600


class _Counting(io.BytesIO):
    """A stream that records the sizes asked of each read."""

    def __init__(self, data):
        super().__init__(data)
        self.asked = []

    def read(self, n=-1):
        self.asked.append(n)
        return super().read(n)


@pytest.mark.parametrize("size", [0, 10, 65535, 65536, 65537, 3_000_000])
def test_read_bounded_returns_every_byte_and_asks_in_proportion(size):
    data = bytes(range(256)) * (size // 256) + bytes(size % 256)
    for hint in (size, 0):  # the stated size, or none (a pipe, /proc)
        f = _Counting(data)
        assert read_bounded(f, hint, limit=4 * 1024**3) == data
        assert max(f.asked) <= max(2 * size, 1 << 20) + 1  # never the 4 GiB limit


def test_read_bounded_stops_one_byte_past_the_limit():
    f = _Counting(b"x" * 5000)
    out = read_bounded(f, 0, limit=1000)
    assert len(out) == 1001  # the caller sees it is over the limit
    assert sum(f.asked) <= 1001 + 1
