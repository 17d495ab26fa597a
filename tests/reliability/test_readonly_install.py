"""A read-only install run by a user without a home (service account, cron, container non-root).

Once every command crashed at import with numba's ``RuntimeError: cannot cache function
'locate': no locator available`` (even ``vibkit --version``).  This test installs the package
non-editable into a temporary folder (``pip install --target``; a plain copy of the package if pip
cannot build here), makes it read-only (``chmod -R a-w``) and runs every command as uid 65534 with
``HOME=/nonexistent``, the dependencies coming from the test environment.  CI runs as root, so the
child drops to uid 65534 in ``preexec_fn``; the test is skipped (with the reason) when not root or
when no Python 3.x interpreter can be executed by that user.

The test must not depend on where the clone lives: in a private (0700) temporary folder, as CI
makes them, uid 65534 cannot reach the virtual environment's site-packages.  The dependencies are
then given to it as a tree of hard links (no data copied) in the test's own temporary folder; where
that is impossible (another file system) the test is skipped with the reason.
"""

from __future__ import annotations

import json
import os
import shutil
import stat
import subprocess
import sys
import sysconfig
import tempfile
import textwrap
from pathlib import Path

import pytest

import vibkit

ROOT = Path(__file__).resolve().parents[2]
NOBODY = 65534

pytestmark = [
    pytest.mark.skipif(
        not hasattr(os, "getuid") or os.getuid() != 0,
        reason="needs root to run the commands as uid 65534 (os.setuid in preexec_fn)",
    ),
    pytest.mark.slow,  # a pip install and every command in a fresh process
]


def _demote():
    os.setgroups([])
    os.setgid(NOBODY)
    os.setuid(NOBODY)


def _interpreter(env):
    """An interpreter of this Python version that uid 65534 can execute (the venv's may live in /root)."""
    ver = f"{sys.version_info[0]}.{sys.version_info[1]}"
    for cand in (
        sys.executable,
        os.path.realpath(sys.executable),
        shutil.which(f"python{ver}", path="/usr/bin:/bin"),
        shutil.which(f"python{ver}", path="/usr/local/bin"),
    ):
        if not cand:
            continue
        try:
            probe = subprocess.run(
                [cand, "-c", "import sys; print(f'{sys.version_info[0]}.{sys.version_info[1]}')"],
                env=env,
                preexec_fn=_demote,
                capture_output=True,
                text=True,
                cwd="/",
            )
        except OSError:  # not executable by that user
            continue
        if probe.returncode == 0 and probe.stdout.strip() == ver:
            return cand
    return None


def _install(target: Path) -> str:
    """Non-editable install of the repository into ``target``; returns how it was done.

    Built from a copy of the sources, so that the build leaves nothing (``build/``, ``*.egg-info``)
    in the repository."""
    src = target.parent / "src"
    shutil.copytree(ROOT / "vibkit", src / "vibkit", ignore=shutil.ignore_patterns("__pycache__"))
    shutil.copytree(ROOT / "sim", src / "sim")  # the shipped scenes, which setup.py copies into the package
    for folder in ("field", "fleet-example"):  # the example files of vibkit.datasets, which it copies too
        shutil.copytree(ROOT / "data" / folder, src / "data" / folder)
    shutil.copy(ROOT / "data" / "README.md", src / "data" / "README.md")
    for name in ("pyproject.toml", "setup.py", "MANIFEST.in", "README.md", "LICENSE"):
        if (ROOT / name).exists():
            shutil.copy(ROOT / name, src / name)
    base = [sys.executable, "-m", "pip", "install", "--quiet", "--no-deps", "--no-compile", "--target", str(target)]
    for extra in (["--no-build-isolation"], []):
        proc = subprocess.run(base + extra + [str(src)], capture_output=True, text=True)
        if proc.returncode == 0 and (target / "vibkit" / "__init__.py").exists():
            return "pip install --target" + (" --no-build-isolation" if extra else "")
        shutil.rmtree(target, ignore_errors=True)
    shutil.copytree(ROOT / "vibkit", target / "vibkit", ignore=shutil.ignore_patterns("__pycache__"))
    return "copy of the package (pip could not build here)"


def _make_read_only(path: Path):
    for dirpath, dirnames, filenames in os.walk(path):
        for name in filenames + dirnames:
            p = os.path.join(dirpath, name)
            os.chmod(p, stat.S_IMODE(os.lstat(p).st_mode) & ~0o222)
    os.chmod(path, stat.S_IMODE(os.stat(path).st_mode) & ~0o222)


def _probe_import(py, path):
    """Can uid 65534 import numpy from ``path`` with the interpreter ``py``?"""
    try:
        proc = subprocess.run(
            [
                py,
                "-I",
                "-c",
                f"import sys; sys.path.insert(0, {path!r}); import numpy; assert numpy.__file__.startswith({path!r})",
            ],
            preexec_fn=_demote,
            capture_output=True,
            text=True,
            cwd="/",
        )
    except OSError:
        return False
    return proc.returncode == 0


def _reachable_deps(top: Path, py: str) -> str:
    """The test environment's site-packages, or a hard-linked copy of it in ``top`` when uid 65534
    cannot reach it (the clone and its .venv in a private folder); skips the module if neither works."""
    deps = sysconfig.get_paths()["purelib"]
    if _probe_import(py, deps):
        return deps
    linked = top / "deps"
    try:
        shutil.copytree(
            deps,
            linked,
            copy_function=os.link,
            symlinks=True,
            ignore=shutil.ignore_patterns("__editable__*", "*.pth", "vibkit", "vibkit-*"),
        )
    except (OSError, shutil.Error) as exc:
        pytest.skip(
            f"uid {NOBODY} cannot reach {deps} (a private parent folder) and it cannot be hard-linked into {top}: {exc}"
        )
    for dirpath, dirnames, _ in os.walk(linked):  # the folders are new: let that user in
        for name in dirnames:
            os.chmod(os.path.join(dirpath, name), 0o755)
    os.chmod(linked, 0o755)
    if not _probe_import(py, str(linked)):
        pytest.skip(f"uid {NOBODY} cannot import numpy from {deps} nor from its hard-linked copy")
    return str(linked)


@pytest.fixture(scope="module")
def readonly():
    # not pytest's tmp_path: its parents are private to root, and the user must reach this folder
    top = Path(tempfile.mkdtemp(prefix="vibkit-readonly-"))
    os.chmod(top, 0o755)
    site = top / "site"
    how = _install(site)
    _make_read_only(site)
    work = top / "work"  # where the user may write (its outputs) and its temp folder
    (work / "tmp").mkdir(parents=True)
    for d in (work, work / "tmp"):
        os.chmod(d, 0o1777)
    env = {
        "PATH": "/usr/bin:/bin",
        "HOME": "/nonexistent",
        "LANG": "C.UTF-8",
        "TMPDIR": str(work / "tmp"),
        "MPLBACKEND": "Agg",
        "VIBKIT_PROGRESS_INTERVAL": "1e9",
    }
    py = _interpreter(env)
    if py is None:
        pytest.skip(
            f"no python{sys.version_info[0]}.{sys.version_info[1]} executable by uid {NOBODY} ({sys.executable} is not)"
        )
    env["PYTHONPATH"] = os.pathsep.join([str(site), _reachable_deps(top, py)])
    yield {"top": top, "site": site, "work": work, "env": env, "py": py, "how": how}
    shutil.rmtree(top, ignore_errors=True)  # root may remove read-only files


def _run(ro, code, timeout=600):
    """Run ``code`` (Python) as uid 65534 without a home; returns the CompletedProcess."""
    return subprocess.run(
        [ro["py"], "-c", textwrap.dedent(code)],
        env=ro["env"],
        preexec_fn=_demote,
        capture_output=True,
        text=True,
        cwd=ro["work"],
        timeout=timeout,
    )


def _cli(ro, *argv, timeout=600):
    code = f"""
        import sys
        from vibkit.cli import main
        try:
            rc = main({list(argv)!r})
        except SystemExit as exc:
            rc = exc.code
        sys.exit(rc)
    """
    return _run(ro, code, timeout=timeout)


def test_installed_read_only_and_imported_from_there(readonly):
    proc = _run(
        readonly,
        """
        import os, vibkit
        print(vibkit.__file__)
        print(os.access(os.path.dirname(vibkit.__file__), os.W_OK))
    """,
    )
    assert proc.returncode == 0, proc.stderr
    path, writable = proc.stdout.split()
    assert path == str(readonly["site"] / "vibkit" / "__init__.py")
    assert writable == "False"


def test_version_and_help_compile_nothing(readonly):
    """--version and --help work and do not even import numba (so they cannot compile)."""
    for flag in ("--version", "--help", "simulate --help"):
        proc = _run(
            readonly,
            f"""
            import sys
            from vibkit.cli import main
            try:
                main({flag.split()!r})
            except SystemExit as exc:
                assert exc.code == 0, exc.code
            assert "numba" not in sys.modules, "numba was imported"
        """,
        )
        assert proc.returncode == 0, proc.stderr
        assert "Traceback" not in proc.stderr
    assert f"vibkit {vibkit.__version__}" in _cli(readonly, "--version").stdout


def test_every_command_runs_without_a_home(readonly):
    work = readonly["work"]
    scene = work / "tiny.toml"
    scene.write_text(
        (ROOT / "sim" / "thesis-kinematics.toml")
        .read_text()
        .replace("stop = 3.5333333", "stop = 3.01")
        .replace("step = 0.0001", "step = 0.001")
    )
    rec = work / "leon.csv"
    shutil.copy(ROOT / "data" / "field" / "leon-tensioner.csv", rec)
    bench = work / "benchroot" / "benchmarks"
    bench.mkdir(parents=True)
    (bench / "bench_noop.py").write_text("print('noop benchmark ok')\n")
    leon = work / "leon.toml"  # the clone itself may be out of that user's reach
    shutil.copy(ROOT / "sim" / "leon.toml", leon)
    for p in (scene, rec, leon, work / "benchroot", bench, bench / "bench_noop.py"):
        os.chmod(p, 0o755 if p.is_dir() else 0o644)

    commands = [
        ("simulate", str(scene), "-o", str(work / "tiny.nc")),
        ("spectrum", str(rec)),
        ("pitch", str(rec), "--speed", "0.49", "--speed-uncertainty", "0.1%"),
        ("compare", str(rec), str(leon), "--duration", "2"),
        ("report", str(rec), "-o", str(work / "leon.pdf")),
        ("bench", "--root", str(work / "benchroot")),
    ]
    for argv in commands:
        proc = _cli(readonly, *argv)
        assert proc.returncode == 0, f"{argv[0]}: exit {proc.returncode}\n{proc.stderr[-3000:]}"
        assert "Traceback" not in proc.stderr and "no locator available" not in proc.stderr, proc.stderr
    assert (work / "tiny.nc").stat().st_uid == NOBODY
    assert (work / "leon.pdf").read_bytes()[:5] == b"%PDF-"
    # the kernels were cached where that user can write (its temp folder), not next to the sources
    cache = work / "tmp" / f"vibkit-numba-{NOBODY}"
    assert any(cache.rglob("*.nbi")), "no kernel cache in the user's temp folder"
    assert not any((readonly["site"] / "vibkit").rglob("*.nbi"))


def test_home_cache_preferred_and_no_cache_last_resort(readonly):
    """XDG_CACHE_HOME is used when writable; with nothing writable the kernels still run, uncached,
    with one line on stderr."""
    xdg = readonly["top"] / "xdg"
    xdg.mkdir()
    os.chmod(xdg, 0o1777)
    ro = dict(readonly, env=dict(readonly["env"], XDG_CACHE_HOME=str(xdg)))
    proc = _run(
        ro,
        """
        from vibkit.runtime.kernel_cache import cache_dir
        print(cache_dir())
    """,
    )
    assert proc.returncode == 0, proc.stderr
    assert proc.stdout.strip() == str(xdg / "vibkit" / "numba")

    nowhere = readonly["top"] / "nowhere"
    nowhere.mkdir(mode=0o555)
    proc = _run(
        readonly,
        f"""
        import tempfile
        tempfile.tempdir = {str(nowhere)!r}  # as if no temp folder were writable (gettempdir would fall back)
        import numpy as np
        from vibkit.signal import hampel
        x = np.zeros(50); x[25] = 100.0
        y = hampel(x, 3)
        print(float(np.asarray(y[0] if isinstance(y, tuple) else y)[25]))
    """,
    )
    assert proc.returncode == 0, proc.stderr
    assert float(proc.stdout.split()[-1]) == 0.0  # the spike is replaced by the window's median
    notes = [line for line in proc.stderr.splitlines() if "not cached" in line]
    assert len(notes) == 1 and "no writable folder" in notes[0]


def test_fleet_status_of_an_archived_schema_1_history(readonly):
    """A schema-1 history (an older vibkit's) that the user may only read, in a folder it may only read: status
    reads it without upgrading it (SQLite's immutable read: no -wal/-shm can be made), the file left as it was."""
    from corpus_fleet import schema1_db

    archive = readonly["top"] / "archive"
    archive.mkdir()
    schema1_db("fleet.sqlite")(archive)
    db = archive / "fleet.sqlite"
    os.chmod(db, 0o444)
    os.chmod(archive, 0o555)
    before = (db.read_bytes(), db.stat().st_mtime_ns, sorted(os.listdir(archive)))
    proc = _cli(readonly, "fleet", "status", "--json", "--db", str(db))
    assert proc.returncode == 0, proc.stderr[-3000:]
    assert sorted(u["unit"] for u in json.loads(proc.stdout)["units"]) == ["E22", "E23", "E24"]
    assert "read a schema-1 history without upgrading it" in proc.stderr and "Traceback" not in proc.stderr
    assert (db.read_bytes(), db.stat().st_mtime_ns, sorted(os.listdir(archive))) == before
