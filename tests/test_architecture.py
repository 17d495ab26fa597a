"""The package's shape: few top-level modules, small modules, imports that run one way, no cycles.

The layers, from the bottom: ``runtime`` (guards every layer shares) <- ``signal`` and ``io`` (never the
model) <- ``model`` <- ``analyses`` <- ``diagnose`` <- ``fleet`` and ``sweep`` <- ``cli``. A module
may import its own layer and the layers below it, never one above. The checks parse the sources
(every import statement, also those inside functions), so a lazy import cannot hide an upward edge.
"""

from __future__ import annotations

import ast
from pathlib import Path

import pytest

PKG = Path(__file__).resolve().parents[1] / "vibkit"

#: layer of each subpackage: an import may go to the same or a lower number only
LAYER = {"runtime": 0, "signal": 1, "io": 1, "model": 2, "analyses": 3, "diagnose": 4, "fleet": 5, "sweep": 5, "cli": 6}
#: imports the layer numbers alone would allow but the architecture forbids
FORBIDDEN = {("signal", "io"), ("io", "signal")}
MAX_LINES = 700
MAX_TOP_LEVEL_MODULES = 6


def _modules():
    for path in sorted(PKG.rglob("*.py")):
        rel = path.relative_to(PKG.parent).with_suffix("")
        parts = list(rel.parts)
        is_pkg = parts[-1] == "__init__"
        if is_pkg:
            parts = parts[:-1]
        yield ".".join(parts), path, is_pkg


MODULES = {name: (path, is_pkg) for name, path, is_pkg in _modules()}


def _imports(name: str) -> list[tuple[str, int, bool]]:
    """(imported module, line, at load time) for every vibkit import in module ``name``."""
    path, is_pkg = MODULES[name]
    tree = ast.parse(path.read_text(), filename=str(path))
    package = name if is_pkg else name.rsplit(".", 1)[0]
    top_level = {id(node) for node in tree.body}
    # statements under `if TYPE_CHECKING:` or in functions are not run at load time
    load_time = set()
    for node in tree.body:
        if isinstance(node, (ast.Import, ast.ImportFrom)):
            load_time.add(id(node))
        elif isinstance(node, ast.Try):
            load_time.update(id(n) for n in node.body if isinstance(n, (ast.Import, ast.ImportFrom)))
    found = []
    for node in ast.walk(tree):
        if isinstance(node, ast.Import):
            targets = [a.name for a in node.names]
        elif isinstance(node, ast.ImportFrom):
            if node.level:
                base = package.split(".")
                base = base[: len(base) - (node.level - 1)]
                mod = ".".join(base + ([node.module] if node.module else []))
            else:
                mod = node.module or ""
            targets = [mod]
            # `from . import x` / `from .pkg import module`: the module when it is one
            targets += [f"{mod}.{a.name}" for a in node.names if f"{mod}.{a.name}" in MODULES]
        else:
            continue
        for t in targets:
            if t == "vibkit" or t.startswith("vibkit."):
                found.append((t, node.lineno, id(node) in load_time or id(node) in top_level))
    return found


def _layer(module: str) -> str | None:
    parts = module.split(".")
    return parts[1] if len(parts) > 1 and parts[1] in LAYER else None


def test_few_modules_at_the_top():
    top = [p.name for p in PKG.glob("*.py")]
    assert len(top) <= MAX_TOP_LEVEL_MODULES, top


@pytest.mark.parametrize("name", sorted(MODULES))
def test_module_is_small(name):
    path, _ = MODULES[name]
    n = len(path.read_text().splitlines())
    assert n <= MAX_LINES, f"{path.relative_to(PKG.parent)} has {n} lines (at most {MAX_LINES})"


def test_imports_run_one_way():
    bad = []
    for name in MODULES:
        src = _layer(name)
        if src is None:
            continue  # vibkit/__init__, __main__, demo and the compatibility names sit above every layer
        for target, line, _ in _imports(name):
            dst = _layer(target)
            if target == "vibkit" or dst is None:
                # the package root: only its version string is allowed from inside a layer
                if target in ("vibkit", "vibkit.__init__") or target.startswith("vibkit.__"):
                    continue
                bad.append(f"{name}:{line} imports {target} (a top-level module)")
            elif LAYER[dst] > LAYER[src] or (src, dst) in FORBIDDEN:
                bad.append(f"{name}:{line} ({src}) imports {target} ({dst})")
    assert not bad, "\n".join(bad)


def test_signal_and_io_never_import_the_model():
    for name in MODULES:
        if _layer(name) in ("signal", "io"):
            for target, line, _ in _imports(name):
                assert _layer(target) not in ("model", "analyses", "diagnose", "fleet", "sweep", "cli"), (
                    f"{name}:{line} imports {target}"
                )


def test_no_import_cycles_at_load_time():
    graph = {name: set() for name in MODULES}
    for name in MODULES:
        for target, _, at_load in _imports(name):
            # a module's own packages are always loaded before it runs: never a cycle
            if at_load and target in MODULES and target != name and not name.startswith(target + "."):
                graph[name].add(target)
    # importing a module also runs its packages' __init__
    for name in MODULES:
        for target in list(graph[name]):
            parts = target.split(".")
            for k in range(2, len(parts)):
                parent = ".".join(parts[:k])
                if parent != name and parent in MODULES and not name.startswith(parent + "."):
                    graph[name].add(parent)
    state, stack, cycles = {}, [], []

    def visit(n):
        state[n] = 1
        stack.append(n)
        for m in sorted(graph[n]):
            if state.get(m) == 1:
                cycles.append(stack[stack.index(m) :] + [m])
            elif m not in state:
                visit(m)
        stack.pop()
        state[n] = 2

    for n in sorted(graph):
        if n not in state:
            visit(n)
    assert not cycles, "import cycles:\n" + "\n".join(" -> ".join(c) for c in cycles)


def test_the_checks_can_fail(tmp_path, monkeypatch):
    """A lazy upward import and a load-time cycle, planted in fake modules, are caught."""
    upward = tmp_path / "fake_signal.py"
    upward.write_text("def f():\n    from ..model.scene import load_scene\n")
    a, b = tmp_path / "a.py", tmp_path / "b.py"
    a.write_text("from . import b\n")
    b.write_text("from .a import x\n")
    fake = dict(MODULES)
    fake["vibkit.signal.fake_signal"] = (upward, False)
    fake["vibkit.runtime.a"], fake["vibkit.runtime.b"] = (a, False), (b, False)
    monkeypatch.setitem(globals(), "MODULES", fake)
    with pytest.raises(AssertionError, match="fake_signal:2"):
        test_imports_run_one_way()
    with pytest.raises(AssertionError, match="vibkit.runtime.a -> vibkit.runtime.b -> vibkit.runtime.a"):
        test_no_import_cycles_at_load_time()
