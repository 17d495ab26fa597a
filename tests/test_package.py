"""The package as an installed user gets it: the shipped scenes and example files, ``py.typed``, and the built
wheel at work outside the clone (``vibkit simulate`` of a shipped scene by name, ``vibkit pitch -`` reading stdin,
every command of the README and of the getting-started page as written)."""

from __future__ import annotations

import json
import os
import shutil
import subprocess
import sys
import sysconfig
import zipfile
from pathlib import Path

import pytest

import vibkit
import vibkit.datasets
import vibkit.scenes

ROOT = Path(__file__).resolve().parents[1]
SIM = ROOT / "sim"


def test_shipped_scenes_are_the_files_of_sim():
    assert vibkit.scenes.names() == tuple(sorted(p.stem for p in SIM.glob("*.toml")))
    assert "las-palmas" in vibkit.scenes.names()
    for name in vibkit.scenes.names():
        assert vibkit.scenes.path(name).read_bytes() == (SIM / f"{name}.toml").read_bytes()


def test_scene_by_name_where_no_file_exists(tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    assert vibkit.load_scene("leon").name == "leon"
    assert vibkit.load_scene("leon.toml").name == "leon"
    assert vibkit.load_scene("sim/leon.toml").name == "leon"  # the path the documentation writes
    own = tmp_path / "leon.toml"  # a file of that name wins over the shipped scene
    own.write_text((SIM / "leon.toml").read_text().replace('name = "leon"', 'name = "my-leon"'))
    assert vibkit.load_scene("leon.toml").name == "my-leon"
    with pytest.raises(ValueError, match="no shipped scene 'nope'; the shipped scenes are: las-palmas"):
        vibkit.scenes.path("nope")
    assert vibkit.scenes.find("nope") is None and vibkit.scenes.find("other/leon.toml") is None


def test_py_typed_marker_in_the_package():
    assert (Path(vibkit.__file__).parent / "py.typed").is_file()


def _copy_sources(dst: Path) -> Path:
    """What a build reads (pyproject, setup.py, the package, sim/), copied so the clone gets no build/."""
    src = dst / "src"
    shutil.copytree(ROOT / "vibkit", src / "vibkit", ignore=shutil.ignore_patterns("__pycache__", "*.nb*"))
    shutil.copytree(SIM, src / "sim")
    for folder in ("field", "fleet-example"):  # the example files of vibkit.datasets
        shutil.copytree(ROOT / "data" / folder, src / "data" / folder)
    shutil.copy(ROOT / "data" / "README.md", src / "data" / "README.md")
    for name in ("pyproject.toml", "setup.py", "MANIFEST.in", "README.md", "LICENSE"):
        if (ROOT / name).exists():
            shutil.copy(ROOT / name, src / name)
    return src


@pytest.fixture(scope="module")
def installed(tmp_path_factory):
    """The wheel built from the sources, installed with --no-deps into a fresh virtual environment whose
    dependencies are this environment's (a .pth file naming its site-packages: they are not copied)."""
    top = tmp_path_factory.mktemp("wheel")
    src = _copy_sources(top)
    wheels = top / "dist"
    # pyproject asks for setuptools>=77: pip's build isolation installs it from the package index
    build = subprocess.run(
        [sys.executable, "-m", "pip", "wheel", "--no-deps", "--quiet", "-w", str(wheels), str(src)],
        capture_output=True,
        text=True,
        timeout=600,
    )
    if build.returncode != 0:
        pytest.skip(f"cannot build the wheel here (no package index for setuptools>=77?): {build.stderr[-500:]}")
    (wheel,) = wheels.glob("vibkit-*.whl")
    with zipfile.ZipFile(wheel) as z:
        listed = set(z.namelist())
    assert "vibkit/py.typed" in listed
    assert {f"vibkit/scenes/{p.name}" for p in SIM.glob("*.toml")} <= listed
    shipped = {f"vibkit/datasets/files/{name}" for name in vibkit.datasets.names()}
    assert shipped | {"vibkit/datasets/files/README.md"} <= listed
    assert not any("thirdparty" in n or "devices/" in n or "realworld" in n for n in listed)  # other licences
    venv = top / "venv"
    subprocess.run([sys.executable, "-m", "venv", "--without-pip", str(venv)], check=True, timeout=120)
    py = venv / "bin" / "python"
    site = subprocess.run(
        [py, "-c", "import sysconfig; print(sysconfig.get_paths()['purelib'])"], capture_output=True, text=True
    ).stdout.strip()
    subprocess.run(
        [sys.executable, "-m", "pip", "--python", str(py), "install", "--quiet", "--no-deps", str(wheel)],
        check=True,
        timeout=600,
    )
    Path(site, "test-dependencies.pth").write_text(sysconfig.get_paths()["purelib"] + "\n")
    _copy_model_kernels(Path(site) / "vibkit")
    work = top / "work"  # outside the clone: nothing of the repository is reachable from here
    work.mkdir()
    shutil.copy(ROOT / "data" / "field" / "las-palmas-accelerometer.csv", work / "rec.csv")
    env = {k: v for k, v in os.environ.items() if k not in ("PYTHONPATH", "VIRTUAL_ENV")}
    env.update(PATH=f"{venv / 'bin'}{os.pathsep}{env.get('PATH', '')}", MPLBACKEND="Agg")
    return {"venv": venv, "work": work, "env": env}


#: the subpackages whose compiled kernels the installed copy is given from the clone's cache; the signal layer's
#: it compiles and caches itself, beside its installed modules (checked by the README's test)
GIVEN_KERNELS = ("model", "analyses")


def _copy_model_kernels(installed_pkg):
    """The model's compiled kernels, as this clone's numba cache holds them, copied beside the installed modules.

    numba keys a cached kernel by the digest of its module's source and of its bytecode (numba >= 0.68), not by
    the path: the installed modules are the clone's files, so the copies are exactly what the installed copy would
    compile (a minute or two of CPU that every other test of the suite has already paid once). A fresh install
    compiling them is what every fresh clone does first and what ``vibkit warm``'s test checks."""
    from vibkit.analyses.warm_up import warm_up
    from vibkit.runtime.kernel_cache import cache_dir

    warm_up()  # compiled here (or loaded) first: the cache to copy is whole
    if cache_dir() is not None:  # the clone's package is not writable: its cache lives elsewhere, keyed by path
        return
    for sub in GIVEN_KERNELS:
        for f in (ROOT / "vibkit" / sub / "__pycache__").glob("*.nb[ic]"):
            target = installed_pkg / sub / "__pycache__"
            target.mkdir(exist_ok=True)
            shutil.copy2(f, target / f.name)


def _shell(inst, command, timeout=900):
    return subprocess.run(
        command, shell=True, cwd=inst["work"], env=inst["env"], capture_output=True, text=True, timeout=timeout
    )


@pytest.mark.slow  # builds and installs the wheel, then a forward simulation in a fresh process
def test_wheel_simulates_a_shipped_scene_and_reads_stdin_outside_the_clone(installed):
    where = _shell(
        installed, "python -c 'import vibkit, vibkit.scenes; print(vibkit.__file__, vibkit.scenes.path(\"leon\"))'"
    )
    assert where.returncode == 0, where.stderr
    assert where.stdout.startswith(str(installed["venv"])), where.stdout  # the installed copy, not the clone
    assert str(ROOT) not in where.stdout

    sim = _shell(installed, "vibkit simulate las-palmas --duration 1 -o out.nc")
    assert sim.returncode == 0, sim.stderr[-2000:]
    assert "scene     las-palmas (forward)" in sim.stdout
    assert (installed["work"] / "out.nc").read_bytes()[:8] == b"\x89HDF\r\n\x1a\n"

    # 0.52 m/s: the Las Palmas speed (3.9 Hz over the 133.33 mm catalogue pitch; see sim/las-palmas.toml)
    pitch = _shell(installed, "cat rec.csv | vibkit pitch - --speed 0.52 --json")
    assert pitch.returncode in (0, 3), pitch.stderr[-2000:]  # a verdict or inconclusive, never an error
    result = json.loads(pitch.stdout)
    assert result["schema"] == "vibkit.pitch/1"
    assert result["detection"]["frequency_hz"] == pytest.approx(3.9, abs=0.1)  # the Las Palmas link-pass
    from_file = json.loads(_shell(installed, "vibkit pitch rec.csv --speed 0.52 --json").stdout)
    result.pop("file", None), from_file.pop("file", None)
    assert result == from_file  # stdin read as the file with the same bytes
    assert sorted(os.listdir(installed["work"])) == ["out.nc", "rec.csv"]  # no file named '-'


#: the pages whose every command must run from the wheel, outside the clone, as written
WHEEL_PAGES = (ROOT / "README.md", ROOT / "docs" / "getting-started.md")
#: what the default run changes (the expensive commands made short, as tests/test_readme.py does; a sweep is only
#: parsed); ``VIBKIT_README_FULL=1`` runs every command and Python block exactly as written
WHEEL_CHEAP = {
    "vibkit simulate": ["--duration", "1"],
    "vibkit compare": ["--duration", "2"],
    "vibkit report": ["--duration", "2"],
    "vibkit ride sim/": ["--duration", "3"],
    "vibkit fleet scan": ["--workers", "0"],
    "vibkit sweep": None,
}


def _page_examples(page):
    from test_readme import examples

    return examples(page)


@pytest.mark.slow  # builds and installs the wheel, then every command of two pages in a process of its own
@pytest.mark.parametrize("page", WHEEL_PAGES, ids=lambda p: p.name)
def test_every_command_of_the_readme_and_getting_started_runs_from_the_wheel(installed, page, tmp_path):
    """From an empty folder outside the clone, with only the installed wheel: the page's shell commands in
    order, as written (the clone's setup, ``make`` and ``. .venv/bin/activate``, left out; ``vibkit bench``
    refused in one line, as the pages say); the data files come from ``vibkit datasets copy data``."""
    full = os.environ.get("VIBKIT_README_FULL") == "1"
    work = tmp_path / "work"
    work.mkdir()
    env = dict(installed["env"], VIBKIT_PROGRESS_INTERVAL="1e9")
    env.pop("VIBKIT_FLEET_DB", None)
    bindir = installed["venv"] / "bin"
    ran = []
    for kind, ex in _page_examples(page):
        if kind == "py":
            if full:
                proc = subprocess.run(
                    [bindir / "python", "-c", ex], cwd=work, env=env, capture_output=True, text=True, timeout=1800
                )
                assert proc.returncode == 0, f"a Python block of {page.name} failed:\n{proc.stderr[-3000:]}"
            else:
                compile(ex, page.name, "exec")
            continue
        argv = list(ex)
        if argv[0] == "make" or argv[0] in (".", "source"):
            continue  # the clone's setup
        if argv[0] == "export":
            name, _, value = argv[1].partition("=")
            env[name] = value
            continue
        line = " ".join(argv)
        if argv[0] in ("python", "vibkit"):
            argv[0] = str(bindir / argv[0])
        key = next((k for k in WHEEL_CHEAP if line.startswith(k)), None)
        if key is not None and not full:
            argv = argv[:2] + ["--help"] if WHEEL_CHEAP[key] is None else argv + WHEEL_CHEAP[key]
        proc = subprocess.run(argv, cwd=work, env=env, capture_output=True, text=True, timeout=1800)
        ran.append(line)
        assert "Traceback" not in proc.stderr, f"{page.name}: {line}:\n{proc.stderr[-3000:]}"
        if line.startswith("vibkit bench"):  # the benchmark scripts are a clone's: refused in one line
            assert proc.returncode == 1 and proc.stderr.count("\n") == 1, proc.stderr
            assert "part of a clone of the repository" in proc.stderr and "--root" in proc.stderr
            continue
        assert proc.returncode == 0, f"{page.name}: {line}: exit {proc.returncode}\n{proc.stderr[-3000:]}"
    assert "vibkit datasets copy data" in ran
    assert sum(line.startswith("vibkit ") for line in ran) >= 9
    assert sorted(p.name for p in work.iterdir()) == ["data", "out"]  # nothing written beside out/ (and data/)
    assert (work / "data" / "field" / "leon-tensioner.csv").read_bytes() == (
        ROOT / "data" / "field" / "leon-tensioner.csv"
    ).read_bytes()
    if page.name == "README.md":
        # the installed copy caches the kernels it compiled itself beside its modules (the signal layer's)
        site_pkg = Path(installed["venv"].glob("lib/python*/site-packages/vibkit").__next__())
        assert list((site_pkg / "signal" / "__pycache__").glob("*.nbi")), "no kernel cached beside the installed copy"
        assert (work / "out" / "fleet.pdf").read_bytes()[:5] == b"%PDF-"
        assert (work / "out" / "las-palmas.pdf").read_bytes()[:5] == b"%PDF-"
