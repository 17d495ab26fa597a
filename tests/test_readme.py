"""The examples of the README and the docs run as written, in order, on the files that ship with the repository.

Every ```bash and ```python block of README.md, and of every page under docs/ (each page in its own
sandbox), is taken apart into commands (shell: one a line,
``\\`` continuations joined; Python: the whole block).  They run in a sandbox folder that holds
links to the repository's ``sim/``, ``data/`` and ``benchmarks/`` and nothing else, so that what
they write is seen: it must all be under ``out/``, which git ignores.

Two depths:

* by default (part of the suite) the cheap commands run as written, in this process through
  ``vibkit.cli.main`` (one import), the ones that simulate with a shorter ``--duration`` appended
  (argparse: the last one wins), and the expensive ones (the Python tour, ``report``, ``sweep``, ``bench --quick``) are
  only parsed: ``--help`` of their command, ``compile`` of the Python block;
* ``VIBKIT_README_FULL=1`` runs every example exactly as written (about 10 minutes; what the issue
  asks of a release: ``make demo``, then every README command, exit 0, ``git status`` clean).

``make ...`` (the setup) and ``. .venv/bin/activate`` are not run: the full run calls ``vibkit`` as
``sys.executable -m vibkit`` and ``python`` as ``sys.executable``. A block that must not run is written
as ```text, ```console or ```toml.

Every path of the repository that the README or a docs page names (``vibkit/...``, ``tests/...``,
``data/...``, ``sim/...``, ``benchmarks/...``, ``docs/...``) must exist.
"""

import os
import re
import shlex
import shutil
import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
README = ROOT / "README.md"
#: the documentation's pages, in a stable order; not Sphinx's output (docs/_build) nor the benchmark
#: pages it writes (docs/benchmarks/results, each including a file of benchmarks/results)
DOC_PAGES = sorted(
    p
    for p in (ROOT / "docs").rglob("*.md")
    if "_build" not in p.parts and not p.is_relative_to(ROOT / "docs" / "benchmarks" / "results")
)
FULL = os.environ.get("VIBKIT_README_FULL") == "1"

# commands (by their first words) changed in the default, cheap run; None: --help only
CHEAP = {
    "vibkit simulate": ["--duration", "1"],
    "vibkit compare": ["--duration", "2"],
    "vibkit ride sim/": ["--duration", "3"],
    "vibkit fleet scan": ["--workers", "0"],  # no Dask cluster to start
    "vibkit report": None,
    "vibkit sweep": None,
    "vibkit bench": None,
}


def blocks(text):
    """(language, code) of every fenced bash/python block, in order."""
    return [(m.group(1), m.group(2)) for m in re.finditer(r"^```(bash|python)\n(.*?)^```", text, re.M | re.S)]


def shell_commands(code):
    """One command a line, continuations joined, comments and blank lines dropped."""
    out = []
    for line in code.replace("\\\n", " ").splitlines():
        words = shlex.split(line, comments=True)
        if words:
            out.append(words)
    return out


def examples(page=README):
    """Every example of a page (the README by default), in order: ("sh", argv) or ("py", code)."""
    ex = []
    for lang, code in blocks(page.read_text(encoding="utf-8")):
        if lang == "python":
            ex.append(("py", code))
        else:
            ex.extend(("sh", argv) for argv in shell_commands(code))
    return ex


def test_the_readme_has_its_examples():
    ex = examples()
    firsts = [" ".join(a[:2]) for kind, a in ex if kind == "sh"]
    for cmd in ("vibkit simulate", "vibkit report", "vibkit fleet", "vibkit sweep", "vibkit bench", "make demo"):
        assert cmd in firsts, f"{cmd} is no longer in the README: is this test still reading the right blocks?"
    assert any(kind == "py" for kind, _ in ex)


def test_outputs_are_ignored_by_git():
    """Every file an example writes (-o, write_report, the fleet database) is ignored by git."""
    written = {"out/x", "vibkit-fleet.sqlite", "reports/leon.pdf", "out/sweep.zarr/x"}
    for kind, ex in [e for page in (README, *DOC_PAGES) for e in examples(page)]:
        if kind == "sh" and "-o" in ex:
            written.add(ex[ex.index("-o") + 1])
        if kind == "py":
            written.update(re.findall(r'write_report\([^,]+, "([^"]+)"', ex))
    if shutil.which("git") is None or not (ROOT / ".git").exists():
        pytest.skip("not a git checkout")
    proc = subprocess.run(
        ["git", "check-ignore", "--no-index", *sorted(written)], cwd=ROOT, capture_output=True, text=True
    )
    ignored = set(proc.stdout.split())
    assert ignored == written, f"not ignored by git: {sorted(written - ignored)}"


def _sandbox(tmp_path):
    for name in ("sim", "data", "benchmarks"):
        (tmp_path / name).symlink_to(ROOT / name)
    return tmp_path


class Done:
    """What one in-process command gave: the fields of a CompletedProcess that the test reads."""

    def __init__(self, returncode, stderr):
        self.returncode, self.stderr = returncode, stderr


def _in_process(argv, capsys):
    """``vibkit ARGV`` through :func:`vibkit.cli.main` in this process (the cheap run: one import)."""
    from vibkit.cli import main

    try:
        rc = main(argv)
    except SystemExit as exc:
        rc = exc.code
    return Done(rc, capsys.readouterr().err)


def _run_shell(argv, cwd, env, capsys):
    """Run one README shell line; returns (result or None, what was run)."""
    if argv[0] == "make" or argv[0] in (".", "source"):
        return None, "skipped (setup)"
    if argv[0] == "export":
        name, _, value = argv[1].partition("=")
        env[name] = value
        os.environ[name] = value  # the in-process commands read it too (monkeypatched by the test)
        return None, "export"
    if argv[0] in ("mkdir", "rm", "cp"):
        return subprocess.run(argv, cwd=cwd, env=env, capture_output=True, text=True), " ".join(argv)
    if argv[0] == "python":
        return subprocess.run(
            [sys.executable] + argv[1:], cwd=cwd, env=env, capture_output=True, text=True, timeout=900
        ), " ".join(argv)
    if argv[0] != "vibkit":
        raise AssertionError(f"the README shows a command this test does not know how to run: {argv}")
    if FULL:  # exactly as written, each in its own process
        return subprocess.run(
            [sys.executable, "-m", "vibkit"] + argv[1:], cwd=cwd, env=env, capture_output=True, text=True, timeout=900
        ), " ".join(argv)
    key = next((k for k in CHEAP if " ".join(argv).startswith(k)), None)
    args = argv[1:]
    if key is not None:
        extra = CHEAP[key]
        if extra is None:  # expensive: parse only
            args = [w for w in argv[1:3] if not w.startswith("-") and "/" not in w and "." not in w] + ["--help"]
        else:
            args = args + extra
    return _in_process(args, capsys), "vibkit " + " ".join(args)


def _run_page(page, box, monkeypatch, capsys):
    """Run every example of one page in the sandbox ``box``, in order; returns what was run."""
    monkeypatch.chdir(box)
    monkeypatch.delenv("VIBKIT_FLEET_DB", raising=False)
    env = dict(os.environ, MPLBACKEND="Agg", PYTHONPATH=str(ROOT), VIBKIT_PROGRESS_INTERVAL="1e9")
    name = page.relative_to(ROOT).as_posix()
    ran = []
    for kind, ex in examples(page):
        if kind == "py":
            if FULL:
                proc = subprocess.run(
                    [sys.executable, "-c", ex], cwd=box, env=env, capture_output=True, text=True, timeout=900
                )
                assert proc.returncode == 0, f"a Python block of {name} failed:\n{proc.stderr[-3000:]}"
            else:
                compile(ex, name, "exec")
            continue
        proc, what = _run_shell(ex, box, env, capsys)
        if proc is None:
            continue
        ran.append(what)
        assert proc.returncode == 0, f"{name}: {what}: exit {proc.returncode}\n{proc.stderr[-3000:]}"
        assert "Traceback" not in proc.stderr, f"{name}: {what}:\n{proc.stderr[-3000:]}"
    return ran


def test_every_example_runs_in_order(tmp_path, monkeypatch, capsys):
    box = _sandbox(tmp_path)
    ran = _run_page(README, box, monkeypatch, capsys)
    assert len(ran) >= 14
    # nothing written outside out/ (the links are the sandbox's own)
    left = sorted(p.name for p in box.iterdir() if p.name not in ("sim", "data", "benchmarks", "out"))
    assert left == [], f"the examples wrote outside out/: {left}"
    assert (box / "out" / "fleet.sqlite").exists()
    assert (box / "out" / "fleet.pdf").read_bytes()[:5] == b"%PDF-"


@pytest.mark.parametrize(
    "page", [p for p in DOC_PAGES if examples(p)], ids=lambda p: p.relative_to(ROOT / "docs").as_posix()
)
def test_every_docs_example_runs_in_order(page, tmp_path, monkeypatch, capsys):
    """Each docs page's examples, in order, in a fresh sandbox of their own; outputs under out/ only."""
    box = _sandbox(tmp_path)
    _run_page(page, box, monkeypatch, capsys)
    left = sorted(p.name for p in box.iterdir() if p.name not in ("sim", "data", "benchmarks", "out"))
    assert left == [], f"the examples of {page.name} wrote outside out/: {left}"


#: a path of the repository as the README and the docs name it: one of these folders, then a path
#: (braces {a,b} and globs * allowed), not part of a longer path or a URL
REPO_PATH = re.compile(r"(?<![\w/.$~-])((?:vibkit|tests|data|sim|benchmarks|docs)/[\w./{},*-]*)")


def _expand_braces(path):
    m = re.search(r"\{([^{}]*)\}", path)
    if not m:
        return [path]
    return [x for alt in m.group(1).split(",") for x in _expand_braces(path[: m.start()] + alt + path[m.end() :])]


def named_paths(text):
    """Every repository path a page names, braces expanded, trailing punctuation dropped.

    Sphinx's own references (toctree entries, ``{doc}`` targets) name pages, not files, and are
    checked by the docs build; a path with ``...`` in it is a pattern, not a path.
    """
    text = re.sub(r"^```\{toctree\}.*?^```", "", text, flags=re.M | re.S)
    text = re.sub(r"\{doc\}`[^`]*`", "", text)
    out = set()
    for raw in REPO_PATH.findall(text):
        if "..." in raw:
            continue
        for path in _expand_braces(raw.rstrip(".,")):
            if path.startswith("docs/_build"):
                continue  # Sphinx's output, not in a checkout
            out.add(path.rstrip("/") or path)
    return out


def test_named_paths_parse():
    text = (
        "see `vibkit/model/guide.py`, benchmarks/results/closure.{md,png} and ~/.cache/vibkit/numba; "
        "{doc}`benchmarks/index`, `tests/...`."
    )
    assert named_paths(text) == {
        "vibkit/model/guide.py",
        "benchmarks/results/closure.md",
        "benchmarks/results/closure.png",
    }


@pytest.mark.parametrize("page", [README, *DOC_PAGES], ids=lambda p: p.relative_to(ROOT).as_posix())
def test_every_path_named_exists(page):
    """A path the page names (``vibkit/...``, ``tests/...``, ``data/...``, ``sim/...``, ``benchmarks/...``) exists."""
    missing = sorted(p for p in named_paths(page.read_text(encoding="utf-8")) if not list(ROOT.glob(p)))
    assert missing == [], f"{page.relative_to(ROOT)} names paths that do not exist: {missing}"
