"""Reliability cases of ``vibkit sweep``: sizes refused before anything is allocated, keys that
would give identical runs, strict numbers, a start-up that leaves no samples, and signals during the runs.

All but the signal cases are refused before a Dask cluster starts (a second or two each).
"""

import signal

from corpus import SIM, Case, tiny

LEON = str(SIM / "leon.toml")
FORWARD = str(SIM / "thesis-forward.toml")
KINEMATICS = str(SIM / "thesis-kinematics.toml")
OUT = ["-o", "{w}/o.zarr"]
SIZE = ("runs", "of results", "--max-result-bytes")

# the child prints READY once the first run is stored, then keeps computing slowly
SLOW_SWEEP = """
import importlib, time
_st = importlib.import_module("vibkit.sweep.store")  # vibkit.sweep is the function
_orig = _st._Store.write_run
def _slow(self, rec):
    _orig(self, rec)
    print("READY", flush=True)
    time.sleep(30)
_st._Store.write_run = _slow
"""


def _full_disk_after(n_ok):
    """The child's store writer stores ``n_ok`` runs, then finds the disk full (ENOSPC, as zarr's writer raises it)."""
    return f"""
import errno, importlib, os
_st = importlib.import_module("vibkit.sweep.store")
_orig, _n = _st._Store.write_run, [0]
def _write(self, rec):
    _n[0] += 1
    if _n[0] > {n_ok}:
        raise OSError(errno.ENOSPC, os.strerror(errno.ENOSPC), str(self.path / "runs" / "r000000" / "0"))
    _orig(self, rec)
_st._Store.write_run = _write
"""


CASES = [
    # ------------------------------------------------------------------ size, before anything is allocated
    Case(
        "sweep of 1e9 grid points",
        "sweep",
        ["sweep", LEON, "--vary", "motion.speed=0.4:0.5:1000000000", "--duration", "1"] + OUT,
        expect_in=("1e+09 runs",) + SIZE,
        absent=("{w}/o.zarr",),
        subprocess_only=True,
        note="refused from the plan's shape: no grid is built",
    ),
    Case(
        "sweep of 1e9 grid points, --max-runs 1",
        "sweep",
        ["sweep", LEON, "--vary", "motion.speed=0.4:0.5:1000000000", "--max-runs", "1"] + OUT,
        expect_in=SIZE,
        absent=("{w}/o.zarr",),
        subprocess_only=True,
    ),
    Case(
        "sweep --samples 1e9",
        "sweep",
        ["sweep", LEON, "--vary", "motion.speed=0.4:0.5", "--samples", "1000000000"] + OUT,
        expect_in=SIZE,
        absent=("{w}/o.zarr",),
        subprocess_only=True,
    ),
    Case(
        "sweep of 3 keys x 1000 values",
        "sweep",
        [
            "sweep",
            LEON,
            "--vary",
            "motion.speed=0.4:0.5:1000",
            "--vary",
            "motion.step=0.001:0.002:1000",
            "--vary",
            "chain.link_pitch=0.133:0.134:1000",
        ]
        + OUT,
        expect_in=SIZE,
        absent=("{w}/o.zarr",),
        subprocess_only=True,
    ),
    Case(
        "sweep --max-result-bytes 1kB",
        "sweep",
        ["sweep", "{w}/tiny.toml", "--vary", "chain.link_pitch=0.1333,0.1335", "--max-result-bytes", "1kB"] + OUT,
        files={"tiny.toml": tiny()},
        expect_in=("2 runs",) + SIZE,
        absent=("{w}/o.zarr",),
    ),
    Case(
        "sweep --max-result-bytes lots",
        "sweep",
        ["sweep", "{w}/tiny.toml", "--vary", "chain.link_pitch=0.1333,0.1335", "--max-result-bytes", "lots"] + OUT,
        files={"tiny.toml": tiny()},
        expect="usage",
    ),
    # ------------------------------------------------------------------ keys the analysis does not read
    Case(
        "sweep motion.speed on a forward scene",
        "sweep",
        ["sweep", FORWARD, "--vary", "motion.speed=0.45,0.55"] + OUT,
        expect_in=("motion.speed", "forward analysis"),
        absent=("{w}/o.zarr",),
    ),
    Case(
        "sweep motion.speed on a kinematics scene",
        "sweep",
        ["sweep", KINEMATICS, "--vary", "motion.speed=0.45,0.55"] + OUT,
        expect_in=("motion.speed", "kinematics analysis"),
        absent=("{w}/o.zarr",),
    ),
    Case(
        "sweep run.duration on an inverse scene",
        "sweep",
        ["sweep", LEON, "--vary", "run.duration=1,2"] + OUT,
        expect_in=("run.duration", "inverse analysis"),
        absent=("{w}/o.zarr",),
    ),
    Case(
        "sweep run.seed on a forward scene",
        "sweep",
        ["sweep", FORWARD, "--vary", "run.seed=1,2"] + OUT,
        expect_in=("run.seed", "forward analysis"),
        absent=("{w}/o.zarr",),
    ),
    Case(
        "sweep kinematics.step on an inverse scene",
        "sweep",
        ["sweep", LEON, "--vary", "kinematics.step=0.001,0.002"] + OUT,
        expect_in=("kinematics.step", "inverse analysis"),
        absent=("{w}/o.zarr",),
    ),
    Case(
        "sweep solver.rtol on an inverse scene",
        "sweep",
        ["sweep", LEON, "--vary", "solver.rtol=1e-6,1e-7"] + OUT,
        expect_in=("solver.rtol", "inverse analysis"),
        absent=("{w}/o.zarr",),
    ),
    Case(
        "sweep run.duration with --duration",
        "sweep",
        ["sweep", FORWARD, "--vary", "run.duration=1,2", "--duration", "1"] + OUT,
        expect_in=("run.duration", "--duration"),
        absent=("{w}/o.zarr",),
    ),
    # ------------------------------------------------------------------ numbers and the start-up
    Case(
        "sweep motion.speed=0_5",
        "sweep",
        ["sweep", LEON, "--vary", "motion.speed=0_5"] + OUT,
        expect_in=("motion.speed", "'0_5'"),
        absent=("{w}/o.zarr",),
        note="float('0_5') would be 5 m/s",
    ),
    Case(
        "sweep motion.speed=0_4:0.5:3",
        "sweep",
        ["sweep", LEON, "--vary", "motion.speed=0_4:0.5:3"] + OUT,
        expect="usage",
        expect_in=("motion.speed",),
    ),
    Case(
        "sweep N = 1_000",
        "sweep",
        ["sweep", LEON, "--vary", "motion.speed=0.4:0.5:1_000"] + OUT,
        expect="usage",
        expect_in=("whole number",),
    ),
    Case(
        "sweep --samples 1_000",
        "sweep",
        ["sweep", LEON, "--vary", "motion.speed=0.4:0.5", "--samples", "1_000"] + OUT,
        expect="usage",
        expect_in=("--samples",),
    ),
    Case(
        "sweep --settle 0_5",
        "sweep",
        ["sweep", LEON, "--vary", "motion.speed=0.4,0.5", "--settle", "0_5"] + OUT,
        expect="usage",
        expect_in=("--settle",),
    ),
    Case(
        "sweep --settle 5 --duration 1",
        "sweep",
        ["sweep", LEON, "--vary", "motion.speed=0.4,0.5", "--settle", "5", "--duration", "1"] + OUT,
        expect_in=("--settle 5 s", "two samples"),
        absent=("{w}/o.zarr",),
    ),
    Case(
        "sweep --settle on a kinematics scene",
        "sweep",
        ["sweep", "{w}/tiny.toml", "--vary", "chain.link_pitch=0.1333,0.1335", "--settle", "1"] + OUT,
        files={"tiny.toml": tiny()},
        expect_in=("settle",),
        absent=("{w}/o.zarr",),
    ),
    # ------------------------------------------------------------------ signals during the runs
    Case(
        "SIGTERM during a sweep",
        "sweep",
        ["sweep", "{w}/tiny.toml", "--vary", "chain.link_pitch=0.1333:0.1337:4", "--workers", "1"] + OUT,
        files={"tiny.toml": tiny()},
        prelude=SLOW_SWEEP,
        send_signal=signal.SIGTERM,
        expect="interrupted",
        expect_in=("of 4 runs are stored in", "run the same sweep again"),
        heavy=True,
        note="starts a Dask cluster (10-30 s here); the store is resumable (test_sweep_limits.py)",
    ),
    # ------------------------------------------------------------------ a full disk during the runs
    Case(
        "sweep onto a disk full before the first run",
        "sweep",
        ["sweep", "{w}/tiny.toml", "--vary", "chain.link_pitch=0.1333:0.1337:4", "--workers", "1", "--quiet"] + OUT,
        files={"tiny.toml": tiny()},
        prelude=_full_disk_after(0),
        expect_in=("{w}/o.zarr: No space left on device", "held no finished run and was removed"),
        absent=("{w}/o.zarr",),
        heavy=True,
        note="no partial store left: this run made it and stored nothing in it (tests/sweep/test_sweep.py)",
    ),
    Case(
        "sweep onto a disk full after 2 runs",
        "sweep",
        ["sweep", "{w}/tiny.toml", "--vary", "chain.link_pitch=0.1333:0.1337:4", "--workers", "1", "--quiet"] + OUT,
        files={"tiny.toml": tiny()},
        prelude=_full_disk_after(2),
        expect_in=("{w}/o.zarr: No space left on device", "2 of 4 runs are stored there", "to resume: vibkit sweep"),
        heavy=True,
        note="the store with its 2 runs stays, the resume point; the message gives the command that continues",
    ),
    Case(
        "Ctrl-C during a sweep",
        "sweep",
        ["sweep", "{w}/tiny.toml", "--vary", "chain.link_pitch=0.1333:0.1337:4", "--workers", "1"] + OUT,
        files={"tiny.toml": tiny()},
        prelude=SLOW_SWEEP,
        send_signal=signal.SIGINT,
        expect="interrupted",
        expect_in=("of 4 runs are stored in",),
        heavy=True,
        note="as SIGTERM",
    ),
]
