"""The project's own facts agree with each other: the version, its changelog entry, the licence, the
ruff that pre-commit runs, and no test or benchmark that edits ``sys.path``."""

import ast
import re
import tomllib
from pathlib import Path

import vibkit

ROOT = Path(__file__).resolve().parents[1]
PYPROJECT = tomllib.loads((ROOT / "pyproject.toml").read_text(encoding="utf-8"))


def test_the_changelog_has_an_entry_for_this_version():
    """Results stamp vibkit.__version__: a version users see is one the changelog explains."""
    versions = re.findall(r"^## \[(\d+\.\d+\.\d+)\]", (ROOT / "CHANGELOG.md").read_text(encoding="utf-8"), re.M)
    assert versions and versions[0] == vibkit.__version__, (versions[:1], vibkit.__version__)


def test_the_licence_file_is_the_one_pyproject_names():
    assert PYPROJECT["project"]["license"] == "BSD-3-Clause"
    text = (ROOT / "LICENSE").read_text(encoding="utf-8")
    assert text.startswith("BSD 3-Clause License") and "the vibkit developers" in text


def test_pre_commit_runs_the_ruff_the_tests_pin():
    pinned = [r for r in PYPROJECT["project"]["optional-dependencies"]["test"] if r.startswith("ruff==")]
    assert len(pinned) == 1
    config = (ROOT / ".pre-commit-config.yaml").read_text(encoding="utf-8")
    rev = re.search(r"ruff-pre-commit\n\s+rev: v(\S+)", config)
    assert rev and rev.group(1) == pinned[0].removeprefix("ruff=="), (rev and rev.group(1), pinned)


def _path_edits(path):
    """Lines of ``path`` that call sys.path.insert/append/extend or assign to sys.path."""
    found = []
    for node in ast.walk(ast.parse(path.read_text(encoding="utf-8"))):
        target = None
        if isinstance(node, ast.Call) and isinstance(node.func, ast.Attribute):
            target = node.func.value
        elif isinstance(node, (ast.Assign, ast.AugAssign)):
            target = node.targets[0] if isinstance(node, ast.Assign) else node.target
        if (
            isinstance(target, ast.Attribute)
            and target.attr == "path"
            and isinstance(target.value, ast.Name)
            and target.value.id == "sys"
        ):
            found.append(node.lineno)
    return sorted(found)


def test_no_test_or_benchmark_edits_sys_path():
    """The helpers are importable as they are: tests/support and the corpus by pytest's pythonpath, the
    benchmarks' by their own folder (and tests/support through benchmarks/_common.py)."""
    files = sorted((ROOT / "tests").rglob("*.py")) + sorted((ROOT / "benchmarks").glob("*.py"))
    edits = {str(f.relative_to(ROOT)): lines for f in files if (lines := _path_edits(f))}
    assert edits == {}


def test_the_path_check_can_fail(tmp_path):
    bad = tmp_path / "bad.py"
    bad.write_text("import sys\nsys.path.insert(0, 'x')\nsys.path = []\nsys.path += ['y']\n")
    assert _path_edits(bad) == [2, 3, 4]
