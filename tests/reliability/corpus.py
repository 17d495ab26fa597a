"""The reliability corpus: bad inputs (scenes, options, outputs, recordings) a stranger would try.

Each :class:`Case` is run through ``vibkit.cli.main`` (in a subprocess by
``benchmarks/reliability.py``, which writes ``benchmarks/results/reliability.md``; in-process or in a
subprocess by ``tests/reliability/test_corpus.py``) and judged by :func:`judge`:

* ``clean``: exit 1 (bad data) or 2 (usage) with exactly one error line on stderr, no traceback;
* ``ok``: exit 0 and the output written;
* ``traceback``: a Python traceback, a signal (segfault), a hang (timeout) or an unexpected exit;
* files ``lost``: a file the case protects (an input, an existing output, a link or a device)
  changed, vanished or changed type, or a temporary file (``*.vibkit-tmp-*``) was left behind.

New cases: add a :class:`Case` to ``CASES`` here, or a module ``tests/reliability/corpus_*.py``
with its own ``CASES`` list; :func:`all_cases` collects them all, so both the tests and the table
pick them up without further edits.
"""

from __future__ import annotations

import contextlib
import errno
import hashlib
import importlib.util
import io
import json
import os
import re
import signal
import stat
import subprocess
import sys
import time
from dataclasses import dataclass, field
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]
SIM = ROOT / "sim"
DATA = ROOT / "data" / "field"


@dataclass
class Case:
    """One input tried.

    Attributes
    ----------
    name : str
        Unique identifier.
    item : str
        The issue item it exercises (``output``, ``limits``, ``messages``, ``scene``, ``recording`` ...).
    argv : list of str
        Arguments of ``vibkit``; ``{w}`` is replaced by the case's work folder.
    files : dict
        Files to create in the work folder before the run: name -> str/bytes content.
    setup : callable, optional
        ``setup(work: Path)`` for what ``files`` cannot say (FIFOs, links, modes, folders).
    expect : str
        ``"error"`` (exit 1), ``"usage"`` (exit 2), ``"ok"`` (exit 0), ``"interrupted"`` (130/143).
    expect_in : tuple of str
        Substrings the message must contain (``{w}`` replaced), e.g. the file and the key.
    stdout_in : tuple of str
        Substrings the output on stdout must contain (what a result says).
    protect : tuple of str
        Paths (``{w}`` replaced) whose type and content must be the same afterwards.
    outputs : tuple of str
        Files that must exist after an ``ok`` run.
    absent : tuple of str
        Paths that must not exist afterwards.
    env : dict
        Extra environment variables.
    prelude : str
        Python run in the child before ``main`` (fault injection); forces a subprocess.
    send_signal : int, optional
        Signal sent to the child once it prints ``READY`` on stdout; forces a subprocess.
    subprocess_only : bool
        Never run in-process (a regression could hang the test process).
    heavy : bool
        Left out of the test suite for its cost (a whole report takes 10-40 s here); what it shows is
        tested more cheaply elsewhere (named in ``note``).  The table runs it.
    note : str
        What the case shows, for the table.
    """

    name: str
    item: str
    argv: list
    files: dict = field(default_factory=dict)
    setup: object = None
    expect: str = "error"
    expect_in: tuple = ()
    stdout_in: tuple = ()
    protect: tuple = ()
    outputs: tuple = ()
    absent: tuple = ()
    env: dict = field(default_factory=dict)
    prelude: str = ""
    send_signal: int | None = None
    subprocess_only: bool = False
    heavy: bool = False
    note: str = ""

    @property
    def needs_subprocess(self) -> bool:
        return bool(self.prelude or self.send_signal or self.subprocess_only)


# ------------------------------------------------------------------------------------------- scenes


def scene_text(base: str, *, replace=None, append: str = "", bom: bool = False) -> str:
    """A shipped scene (``sim/<base>.toml``) with textual replacements (each must apply) and additions."""
    text = (SIM / f"{base}.toml").read_text(encoding="utf-8")
    for old, new in (replace or {}).items():
        if old not in text:
            raise ValueError(f"corpus: {old!r} not in sim/{base}.toml")
        text = text.replace(old, new, 1)
    text += append
    return ("\ufeff" if bom else "") + text


def tiny(**kw) -> str:
    """The kinematics scene cut to 11 configurations: simulates in a moment."""
    rep = {"stop = 3.5333333": "stop = 3.01", "step = 0.0001": "step = 0.001"}
    rep.update(kw.pop("replace", {}) or {})
    return scene_text("thesis-kinematics", replace=rep, **kw)


TINY = {"tiny.toml": tiny()}
REC = {"rec.csv": (DATA / "leon-tensioner.csv").read_text(encoding="utf-8")}
SIMULATE = ["simulate", "{w}/tiny.toml", "-o"]


def _mkfifo(name):
    def setup(w: Path):
        os.mkfifo(w / name)

    return setup


def _symlink(name, target, make_target=None):
    def setup(w: Path):
        if make_target is not None:
            (w / target).write_bytes(make_target)
        os.symlink(target, w / name)

    return setup


def _chmod(name, mode, content=b"keep me\n"):
    def setup(w: Path):
        (w / name).write_bytes(content)
        os.chmod(w / name, mode)

    return setup


def _mkdir(name):
    def setup(w: Path):
        (w / name).mkdir()

    return setup


def _dead_pid() -> int:
    p = subprocess.Popen([sys.executable, "-c", "pass"])
    p.wait()
    return p.pid


def _stale_temp(name):
    def setup(w: Path):
        (w / f".{name}.vibkit-tmp-{_dead_pid()}").write_bytes(b"half a file from a killed run")

    return setup


# the child prints READY and waits inside the final step of a write (after the data, before the rename)
SLOW_COMMIT = """
import sys, time
import vibkit.runtime.safe_output as _so
_orig = _so._commit
def _slow(*a, **k):
    print("READY", flush=True)
    time.sleep(60)
    return _orig(*a, **k)
_so._commit = _slow
"""

# a disk that fills after 4 kB: every write of the safe-output module fails with ENOSPC
DISK_FULL = """
import errno, io, os
import vibkit.runtime.safe_output as _so
class _Full(io.FileIO):
    written = 0
    def write(self, b):
        _Full.written += len(b)
        if _Full.written > 4096:
            raise OSError(errno.ENOSPC, os.strerror(errno.ENOSPC))
        return super().write(b)
def _open(path, mode="r", *a, **k):
    return _Full(path, mode.replace("b", "")) if "w" in mode else open(path, mode, *a, **k)
_so.open = _open
"""


CASES = [
    # ------------------------------------------------------------------ -o: never clobber, never leak
    Case(
        "output is /dev/null",
        "output",
        SIMULATE + ["/dev/null"],
        files=TINY,
        expect_in=("/dev/null", "character device"),
        protect=("/dev/null",),
    ),
    Case(
        "output is a FIFO",
        "output",
        SIMULATE + ["{w}/out.fifo"],
        files=TINY,
        setup=_mkfifo("out.fifo"),
        expect_in=("FIFO",),
        protect=("{w}/out.fifo",),
        subprocess_only=True,
    ),
    Case(
        "output is /dev/stdout",
        "output",
        SIMULATE + ["/dev/stdout"],
        files=TINY,
        expect_in=("symbolic link",),
        protect=("/dev/stdout",),
    ),
    Case(
        "output is an existing recording",
        "output",
        SIMULATE + ["{w}/victim.csv"],
        files={**TINY, **{"victim.csv": REC["rec.csv"]}},
        expect_in=("already exists", "--force"),
        protect=("{w}/victim.csv",),
    ),
    Case(
        "output exists, --force",
        "output",
        SIMULATE + ["{w}/old.nc", "--force"],
        files={**TINY, "old.nc": b"old"},
        expect="ok",
        outputs=("{w}/old.nc",),
        note="replaced as asked",
    ),
    Case(
        "output exists, --overwrite",
        "output",
        SIMULATE + ["{w}/old.nc", "--overwrite"],
        files={**TINY, "old.nc": b"old"},
        expect="ok",
        outputs=("{w}/old.nc",),
    ),
    Case(
        "output read-only (0444), --force",
        "output",
        SIMULATE + ["{w}/ro.nc", "--force"],
        files=TINY,
        setup=_chmod("ro.nc", 0o444),
        expect_in=("read-only",),
        protect=("{w}/ro.nc",),
    ),
    Case(
        "output is a symlink to a file",
        "output",
        SIMULATE + ["{w}/link.nc", "--force"],
        files=TINY,
        setup=_symlink("link.nc", "target.nc", b"target data"),
        expect_in=("symbolic link",),
        protect=("{w}/link.nc", "{w}/target.nc"),
    ),
    Case(
        "output is a dangling symlink",
        "output",
        SIMULATE + ["{w}/dangling.nc"],
        files=TINY,
        setup=_symlink("dangling.nc", "nowhere.nc"),
        expect_in=("symbolic link",),
        protect=("{w}/dangling.nc",),
        absent=("{w}/nowhere.nc",),
    ),
    Case(
        "output is the scene itself",
        "output",
        SIMULATE + ["{w}/tiny.toml", "--force"],
        files=TINY,
        expect_in=("input",),
        protect=("{w}/tiny.toml",),
    ),
    Case("output path empty", "output", SIMULATE + [""], files=TINY, expect_in=("empty",)),
    Case(
        "output folder missing",
        "output",
        SIMULATE + ["{w}/no/such/folder/x.nc"],
        files=TINY,
        expect_in=("does not exist",),
    ),
    Case(
        "report -o an existing folder",
        "output",
        ["report", "{w}/rec.csv", "-o", "{w}/existing_dir.pdf"],
        files=REC,
        setup=_mkdir("existing_dir.pdf"),
        expect_in=("folder",),
        protect=("{w}/existing_dir.pdf",),
    ),
    Case(
        "report -o the recording",
        "output",
        ["report", "{w}/rec.csv", "-o", "{w}/rec.csv", "--force"],
        files=REC,
        protect=("{w}/rec.csv",),
    ),
    Case(
        "stale temp of a killed run",
        "output",
        SIMULATE + ["{w}/fresh.nc"],
        files=TINY,
        setup=_stale_temp("fresh.nc"),
        expect="ok",
        outputs=("{w}/fresh.nc",),
        note="the stale .fresh.nc.vibkit-tmp-PID is removed",
    ),
    Case("simulate, new output", "output", SIMULATE + ["{w}/new.nc"], files=TINY, expect="ok", outputs=("{w}/new.nc",)),
    Case(
        "report, new output",
        "output",
        ["report", "{w}/rec.csv", "-o", "{w}/new.pdf"],
        files=REC,
        expect="ok",
        outputs=("{w}/new.pdf",),
        heavy=True,
        note="tested in test_readonly_install.py and test_report.py",
    ),
    Case(
        "SIGTERM during the write",
        "output",
        SIMULATE + ["{w}/term.nc"],
        files=TINY,
        prelude=SLOW_COMMIT,
        send_signal=signal.SIGTERM,
        expect="interrupted",
        absent=("{w}/term.nc",),
    ),
    Case(
        "Ctrl-C during the write",
        "output",
        SIMULATE + ["{w}/int.nc"],
        files=TINY,
        prelude=SLOW_COMMIT,
        send_signal=signal.SIGINT,
        expect="interrupted",
        absent=("{w}/int.nc",),
    ),
    Case(
        "Ctrl-C replacing a file",
        "output",
        SIMULATE + ["{w}/keep.nc", "--force"],
        files={**TINY, "keep.nc": b"keep"},
        prelude=SLOW_COMMIT,
        send_signal=signal.SIGINT,
        expect="interrupted",
        protect=("{w}/keep.nc",),
    ),
    Case(
        "disk full (simulate)",
        "output",
        SIMULATE + ["{w}/full.nc"],
        files=TINY,
        prelude=DISK_FULL,
        expect_in=("{w}/full.nc: No space left",),
        absent=("{w}/full.nc",),
    ),
    Case(
        "disk full (report)",
        "output",
        ["report", "{w}/rec.csv", "-o", "{w}/full.pdf"],
        files=REC,
        prelude=DISK_FULL,
        expect_in=("{w}/full.pdf: No space left",),
        absent=("{w}/full.pdf",),
        heavy=True,
        note="the PDF is made in memory; write tested in test_safe_output.py",
    ),
    # ------------------------------------------------------------------ limits: checked before work
    Case(
        "--duration 1e9",
        "limits",
        ["simulate", str(SIM / "leon.toml"), "-o", "{w}/x.nc", "--duration", "1e9"],
        expect_in=("limit", "--duration"),
    ),
    Case(
        "output_step = 1e-9",
        "limits",
        ["simulate", "{w}/s.toml", "-o", "{w}/x.nc"],
        files={"s.toml": scene_text("thesis-forward", replace={"output_step = 0.005": "output_step = 1e-9"})},
        expect_in=("run.output_step", "limit"),
    ),
    Case(
        "kinematics step = 1e-12",
        "limits",
        ["simulate", "{w}/s.toml", "-o", "{w}/x.nc"],
        files={"s.toml": scene_text("thesis-kinematics", replace={"step = 0.0001": "step = 1e-12"})},
        expect_in=("kinematics.step",),
    ),
    Case(
        "max_step = 1e-12",
        "limits",
        ["simulate", "{w}/s.toml", "-o", "{w}/x.nc"],
        files={
            "s.toml": scene_text("thesis-forward", replace={'method = "dopri5"': 'method = "dopri5"\nmax_step = 1e-12'})
        },
        expect_in=("solver.max_step",),
    ),
    Case(
        "gravity g = 1e10",
        "limits",
        ["simulate", "{w}/s.toml", "-o", "{w}/x.nc"],
        files={"s.toml": scene_text("thesis-forward", replace={"gravity = true": "gravity = { g = 1e10 }"})},
        expect_in=("effects.gravity.g",),
    ),
    Case(
        "wall-time budget exceeded",
        "limits",
        ["simulate", "{w}/s.toml", "-o", "{w}/x.nc", "--max-wall-time", "0.5"],
        files={
            "s.toml": scene_text("thesis-forward", replace={'method = "dopri5"': 'method = "dopri5"\nmax_step = 1e-5'})
        },
        expect_in=("wall-time budget", "max_wall_time"),
        absent=("{w}/x.nc",),
    ),
    Case(
        "VIBKIT_MAX_RESULT_BYTES=100",
        "limits",
        SIMULATE + ["{w}/x.nc"],
        files=TINY,
        env={"VIBKIT_MAX_RESULT_BYTES": "100"},
        expect_in=("limit",),
    ),
    Case(
        "--max-result-bytes 200B",
        "limits",
        SIMULATE + ["{w}/x.nc", "--max-result-bytes", "200B"],
        files=TINY,
        expect_in=("limit",),
    ),
    Case(
        "[solver] max_result_bytes = 100",
        "limits",
        SIMULATE + ["{w}/x.nc"],
        files={"tiny.toml": tiny(append="\n[solver]\nmax_result_bytes = 100\n")},
        expect_in=("limit",),
    ),
    Case(
        "--max-result-bytes lots",
        "limits",
        SIMULATE + ["{w}/x.nc", "--max-result-bytes", "lots"],
        files=TINY,
        expect="usage",
    ),
    Case(
        "scene is a FIFO",
        "limits",
        ["simulate", "{w}/scene.toml", "-o", "{w}/x.nc"],
        setup=_mkfifo("scene.toml"),
        expect_in=("not a regular file",),
        subprocess_only=True,
    ),
    Case(
        "scene is /dev/zero",
        "limits",
        ["simulate", "/dev/zero", "-o", "{w}/x.nc"],
        expect_in=("not a regular file",),
        subprocess_only=True,
    ),
    Case("scene is a folder", "limits", ["simulate", "{w}", "-o", "{w}/x.nc"], expect_in=("folder",)),
    # ------------------------------------------------------------------ messages
    Case(
        "--speed-uncertainty abc",
        "messages",
        ["pitch", "{w}/rec.csv", "--speed", "0.49", "--speed-uncertainty", "abc"],
        files=REC,
        expect="usage",
        expect_in=("--speed-uncertainty",),
    ),
    Case(
        "--speed-uncertainty -5%",
        "messages",
        ["pitch", "{w}/rec.csv", "--speed", "0.49", "--speed-uncertainty=-5%"],
        files=REC,
        expect="usage",
        expect_in=("--speed-uncertainty",),
    ),
    Case(
        "report --speed-uncertainty x%",
        "messages",
        ["report", "{w}/rec.csv", "-o", "{w}/r.pdf", "--speed", "0.49", "--speed-uncertainty", "x%"],
        files=REC,
        expect="usage",
        absent=("{w}/r.pdf",),
    ),
    # ------------------------------------------------------------------ scene validation at load
    Case(
        "passengers.mass = [inf]",
        "scene",
        ["simulate", "{w}/s.toml", "-o", "{w}/x.nc"],
        files={"s.toml": scene_text("thesis-passengers", replace={"mass = [70.0, 90.0]": "mass = [70.0, inf]"})},
        expect_in=("{w}/s.toml", "effects.passengers.mass[1]"),
    ),
    Case(
        "passengers.step = [100000]",
        "scene",
        ["simulate", "{w}/s.toml", "-o", "{w}/x.nc"],
        files={"s.toml": scene_text("thesis-passengers", replace={"step = [3, 53]": "step = [3, 100000]"})},
        expect_in=("{w}/s.toml", "effects.passengers.step[1]", "1..53"),
    ),
    Case(
        "passengers.step = [true]",
        "scene",
        ["simulate", "{w}/s.toml", "-o", "{w}/x.nc"],
        files={"s.toml": scene_text("thesis-passengers", replace={"step = [3, 53]": "step = [3, true]"})},
        expect_in=("effects.passengers.step[1]",),
    ),
    Case(
        "outputs.rollers = [true]",
        "scene",
        SIMULATE + ["{w}/x.nc"],
        files={"tiny.toml": tiny(append="rollers = [true]\n")},
        expect_in=("outputs.rollers",),
    ),
    Case(
        "solver.method = rk99",
        "scene",
        ["simulate", "{w}/s.toml", "-o", "{w}/x.nc"],
        files={"s.toml": scene_text("thesis-forward", replace={'method = "dopri5"': 'method = "rk99"'})},
        expect_in=("{w}/s.toml", "solver.method", "dopri5"),
    ),
    Case(
        "scene with a UTF-8 BOM",
        "scene",
        SIMULATE + ["{w}/bom.nc"],
        files={"tiny.toml": tiny(bom=True)},
        expect="ok",
        outputs=("{w}/bom.nc",),
    ),
    Case(
        "tooth_height = 10",
        "scene",
        SIMULATE + ["{w}/x.nc"],
        files={"tiny.toml": tiny(replace={"tooth_height = 0.070": "tooth_height = 10"})},
        expect_in=("sprocket.tooth_height",),
    ),
    Case(
        "tip wider than base",
        "scene",
        SIMULATE + ["{w}/x.nc"],
        files={"tiny.toml": tiny(replace={"tip_width = 0.040": "tip_width = 0.080"})},
        expect_in=("sprocket.tip_width",),
    ),
    Case(
        "motion.start = 1e9",
        "scene",
        ["simulate", "{w}/s.toml", "-o", "{w}/start.nc", "--duration", "0.5"],
        files={"s.toml": scene_text("leon", replace={"start = 0.0": "start = 1e9"})},
        expect="ok",
        outputs=("{w}/start.nc",),
        note="reduced modulo the guide's perimeter: full closure accuracy",
    ),
    Case(
        "kinematics.start = 1e9",
        "scene",
        SIMULATE + ["{w}/x.nc"],
        files={"tiny.toml": tiny(replace={"start = 3.0": "start = 1e9", "stop = 3.01": "stop = 1000000000.01"})},
        expect_in=("kinematics.start",),
    ),
    Case(
        "contact stiffness 1e20",
        "scene",
        ["simulate", "{w}/s.toml", "-o", "{w}/x.nc"],
        files={"s.toml": scene_text("thesis-forward", replace={"stiffness = 1.0e6": "stiffness = 1.0e20"})},
        expect_in=("{w}/s.toml", "effects.contact.stiffness"),
    ),
    Case(
        "solver.rtol = 10",
        "scene",
        ["simulate", "{w}/s.toml", "-o", "{w}/x.nc"],
        files={"s.toml": scene_text("thesis-forward", replace={'method = "dopri5"': 'method = "dopri5"\nrtol = 10'})},
        expect_in=("{w}/s.toml", "solver.rtol"),
    ),
    Case(
        "motor kp = 1e20",
        "scene",
        ["simulate", "{w}/s.toml", "-o", "{w}/x.nc"],
        files={"s.toml": scene_text("thesis-forward", replace={"kp = 600.0": "kp = 1e20"})},
        expect_in=("{w}/s.toml", "effects.motor.kp"),
    ),
    Case(
        "scene not TOML",
        "scene",
        ["simulate", "{w}/s.toml", "-o", "{w}/x.nc"],
        files={"s.toml": "[scene\nname="},
        expect_in=("not valid TOML",),
    ),
    Case(
        "scene is binary",
        "scene",
        ["simulate", "{w}/s.toml", "-o", "{w}/x.nc"],
        files={"s.toml": bytes(range(256)) * 4},
    ),
    # ------------------------------------------------------------------ recordings (more: corpus_*.py)
    Case("recording empty", "recording", ["spectrum", "{w}/empty.csv"], files={"empty.csv": b""}),
    Case(
        "recording binary garbage",
        "recording",
        ["spectrum", "{w}/junk.csv"],
        files={"junk.csv": bytes(range(256)) * 16},
    ),
    Case("recording header only", "recording", ["spectrum", "{w}/head.csv"], files={"head.csv": "time,accel_x\n"}),
    Case("recording missing", "recording", ["pitch", "{w}/missing.csv", "--speed", "0.5"]),
]


def all_cases() -> list[Case]:
    """``CASES`` of this module and of every ``corpus_*.py`` next to it (names must be unique)."""
    cases = list(CASES)
    here = Path(__file__).resolve().parent
    # the corpus_* modules import ``corpus``: where this module was loaded from its file under another name
    # (benchmarks/reliability.py), they get this one
    sys.modules.setdefault("corpus", sys.modules[__name__])
    for path in sorted(here.glob("corpus_*.py")):
        spec = importlib.util.spec_from_file_location(f"_vibkit_{path.stem}", path)
        mod = importlib.util.module_from_spec(spec)
        spec.loader.exec_module(mod)
        cases += list(getattr(mod, "CASES", []))
    names = [c.name for c in cases]
    dup = {n for n in names if names.count(n) > 1}
    if dup:
        raise ValueError(f"duplicate reliability case names: {sorted(dup)}")
    return cases


# -------------------------------------------------------------------------------------------- running


def _sub(text: str, work: Path) -> str:
    return text.replace("{w}", str(work))


def _fingerprint(path: str):
    """(type, content hash or link target) of a path, None if absent; devices by type only."""
    try:
        st = os.lstat(path)
    except FileNotFoundError:
        return None
    if stat.S_ISLNK(st.st_mode):
        return ("link", os.readlink(path))
    if stat.S_ISREG(st.st_mode):
        with open(path, "rb") as f:
            return ("file", hashlib.sha256(f.read()).hexdigest(), stat.S_IMODE(st.st_mode))
    return (stat.S_IFMT(st.st_mode), None)


def prepare(case: Case, work: Path) -> dict:
    """Create the case's files in ``work``; returns the fingerprints of what it protects."""
    work.mkdir(parents=True, exist_ok=True)
    for name, content in case.files.items():
        p = work / name
        if isinstance(content, bytes):
            p.write_bytes(content)
        else:
            p.write_text(content, encoding="utf-8")
    if case.setup is not None:
        case.setup(work)
    return {p: _fingerprint(_sub(p, work)) for p in case.protect}


CHILD = """
import json, sys
{prelude}
from vibkit.cli import main
try:
    rc = main(json.loads(sys.argv[1]))
except SystemExit as exc:
    rc = exc.code if isinstance(exc.code, int) else 1
sys.exit(rc)
"""


def run_subprocess(case: Case, work: Path, *, timeout: float = 300.0, python: str = sys.executable, code_root=None):
    """(returncode or None on timeout, stdout, stderr) of the case run in a fresh interpreter.

    ``code_root``: the folder holding the ``vibkit`` package to run (default this repository).
    """
    argv = [_sub(a, work) for a in case.argv]
    if code_root is not None:  # older code has no --force: it replaced files without asking
        argv = [a for a in argv if a not in ("--force", "--overwrite")]
    env = dict(os.environ, **case.env)
    env.setdefault("VIBKIT_PROGRESS_INTERVAL", "1e9")
    root = str(code_root or ROOT)
    env["PYTHONPATH"] = os.pathsep.join([root] + ([env["PYTHONPATH"]] if env.get("PYTHONPATH") else []))
    cmd = [python, "-c", CHILD.format(prelude=case.prelude), json.dumps(argv)]
    if case.send_signal is None:
        try:
            p = subprocess.run(cmd, env=env, cwd=work, capture_output=True, text=True, timeout=timeout)
        except subprocess.TimeoutExpired as exc:
            return None, exc.stdout or "", (exc.stderr or "") if isinstance(exc.stderr, str) else ""
        return p.returncode, p.stdout, p.stderr
    # a person's Ctrl-C: the child gets SIGINT's default disposition even where this process was
    # started in the background (there SIGINT is ignored, and a child would inherit that)
    proc = subprocess.Popen(
        cmd,
        env=env,
        cwd=work,
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
        preexec_fn=lambda: signal.signal(signal.SIGINT, signal.SIG_DFL),
    )
    t0 = time.monotonic()
    line = ""
    while time.monotonic() - t0 < timeout:
        line = proc.stdout.readline()
        if not line or line.strip() == "READY":
            break
    if line.strip() == "READY":
        proc.send_signal(case.send_signal)
    try:
        out, err = proc.communicate(timeout=timeout)
    except subprocess.TimeoutExpired:
        proc.kill()
        out, err = proc.communicate()
        return None, out, err
    return proc.returncode, line + out, err


def run_inprocess(case: Case, work: Path):
    """(returncode, stdout, stderr) of ``vibkit.cli.main`` called in this process."""
    from vibkit.cli import main

    argv = [_sub(a, work) for a in case.argv]
    out, err = io.StringIO(), io.StringIO()
    old_env = {k: os.environ.get(k) for k in case.env}
    os.environ.update(case.env)
    try:
        with contextlib.redirect_stdout(out), contextlib.redirect_stderr(err):
            try:
                rc = main(argv)
            except SystemExit as exc:
                rc = exc.code if isinstance(exc.code, int) else 1
            except BaseException:  # a traceback: report it like the interpreter would
                import traceback

                traceback.print_exc(file=err)
                rc = 1
    finally:
        for k, v in old_env.items():
            if v is None:
                os.environ.pop(k, None)
            else:
                os.environ[k] = v
    return rc, out.getvalue(), err.getvalue()


def _error_lines(stderr: str) -> list[str]:
    lines = [ln for ln in stderr.splitlines() if ln.strip()]
    skip = ("usage:", " ", "vibkit: note:", "warning:", "note:")
    return [ln for ln in lines if not ln.startswith(skip) and "Warning" not in ln]


#: an exception's class name as Python prints it (``OSError:``, ``KeyError:``, ``SacIOError``)
_PYTHON_NAME = re.compile(r"\b[A-Z][A-Za-z]*(?:Error|Exception)\b(?=:|\(| |$)")


def judge(case: Case, work: Path, before: dict, rc, stdout: str, stderr: str) -> dict:
    """Classify a run (see the module docstring); ``passed`` says whether it met the case's expectation."""
    res = {"case": case.name, "item": case.item, "returncode": rc, "problems": []}
    tb = (
        rc is None
        or (isinstance(rc, int) and rc < 0)
        or "Traceback (most recent call last)" in stderr
        or "Fatal Python error" in stderr
    )
    errs = _error_lines(stderr)
    if tb:
        res["outcome"] = "traceback" if rc is not None else "hang"
    elif rc == 0:
        res["outcome"] = "ok"
    elif rc in (1, 2) and len(errs) == 1:
        res["outcome"] = "clean"
    elif rc in (130, 143):
        res["outcome"] = "interrupted"
    else:
        res["outcome"] = "unclear"
        res["problems"].append(f"exit {rc} with {len(errs)} error line(s)")
    res["message"] = errs[0] if errs else ""
    lost = []
    for p, fp in before.items():
        now = _fingerprint(_sub(p, work))
        if now != fp:
            lost.append(_sub(p, work))
    for p in case.absent:
        if os.path.lexists(_sub(p, work)):
            lost.append(_sub(p, work) + " (should not exist)")
    if work.is_dir():
        lost += [str(q) for q in work.rglob("*.vibkit-tmp-*")]
    res["lost"] = lost
    want = {"error": (1,), "usage": (2,), "ok": (0,), "interrupted": (130, 143)}[case.expect]
    if rc not in want:
        res["problems"].append(f"expected exit {'/'.join(map(str, want))}, got {rc}")
    if case.expect in ("error", "usage") and res["outcome"] != "clean":
        res["problems"].append(f"not one clean error line: {res['outcome']}")
    if tb:
        res["problems"].append("traceback, crash or hang")
    for s in case.expect_in:
        if _sub(s, work) not in stderr:
            res["problems"].append(f"message lacks {_sub(s, work)!r}")
    for s in case.stdout_in:
        if _sub(s, work) not in stdout:
            res["problems"].append(f"output lacks {_sub(s, work)!r}")
    python_name = _PYTHON_NAME.search(stderr) if not tb else None
    if python_name:  # a message for a person, not an exception's class name
        res["problems"].append(f"message shows the Python name {python_name.group(0)!r}")
    if case.expect == "ok":
        for p in case.outputs:
            if not os.path.isfile(_sub(p, work)):
                res["problems"].append(f"output {_sub(p, work)} missing")
    if lost:
        res["problems"].append(f"files lost/clobbered/left: {lost}")
    res["passed"] = not res["problems"]
    return res


def touches_system(case: Case) -> bool:
    """True when the case writes near a path outside its work folder (``/dev/null``, ``/dev/stdout`` ...):
    safe with this code, which refuses them, but never to be run against older code that might not."""
    return any(a.startswith("/") and not a.startswith(str(ROOT)) for a in case.argv) or any(
        p.startswith("/") for p in case.protect
    )


def run_case(case: Case, work: Path, *, inprocess: bool = False, timeout: float = 300.0, code_root=None) -> dict:
    """Prepare, run and judge one case in ``work`` (a fresh folder)."""
    before = prepare(case, work)
    if inprocess and not case.needs_subprocess and code_root is None:
        rc, out, err = run_inprocess(case, work)
    else:
        rc, out, err = run_subprocess(case, work, timeout=timeout, code_root=code_root)
    return judge(case, work, before, rc, out, err)


__all__ = ["Case", "CASES", "all_cases", "run_case", "judge", "prepare", "errno"]
