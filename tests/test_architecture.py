"""The package's shape: few top-level modules, small modules, imports that run one way, no cycles.

The layers, from the bottom: ``runtime`` (guards every layer shares), ``scenes`` and ``datasets`` (the shipped scene and example files) <- ``signal`` and ``io`` (never the
model) <- ``model`` <- ``analyses`` <- ``diagnose`` <- ``fleet`` and ``sweep`` <- ``cli``. A module
may import its own layer and the layers below it, never one above. The checks parse the sources
(every import statement, also those inside functions), so a lazy import cannot hide an upward edge.
"""

from __future__ import annotations

import ast
import functools
from pathlib import Path

import pytest

PKG = Path(__file__).resolve().parents[1] / "vibkit"

#: layer of each subpackage: an import may go to the same or a lower number only
LAYER = {
    "runtime": 0,
    "scenes": 0,
    "datasets": 0,
    "signal": 1,
    "io": 1,
    "model": 2,
    "analyses": 3,
    "diagnose": 4,
    "fleet": 5,
    "sweep": 5,
    "cli": 6,
}
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


def _parsed(path: Path) -> ast.Module:
    return _parse(path.read_text(), str(path))


@functools.lru_cache(maxsize=None)
def _parse(text: str, filename: str) -> ast.Module:
    """A source's tree, parsed once (the checks below walk every module several times)."""
    return ast.parse(text, filename=filename)


def _imports(name: str) -> list[tuple[str, int, bool]]:
    """(imported module, line, at load time) for every vibkit import in module ``name``."""
    path, is_pkg = MODULES[name]
    tree = _parsed(path)
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


def _graph(at_load_only=False):
    """Module -> the vibkit modules it imports (at load time only, or anywhere: also inside functions), each
    import also reaching the packages above its target (their ``__init__`` runs first)."""
    graph = {name: set() for name in MODULES}
    for name in MODULES:
        for target, _, at_load in _imports(name):
            # a module's own packages are always loaded before it runs: never a cycle
            if (
                (at_load or not at_load_only)
                and target in MODULES
                and target != name
                and not name.startswith(target + ".")
            ):
                graph[name].add(target)
    for name in MODULES:
        for target in list(graph[name]):
            parts = target.split(".")
            for k in range(2, len(parts)):
                parent = ".".join(parts[:k])
                if parent != name and parent in MODULES and not name.startswith(parent + "."):
                    graph[name].add(parent)
    return graph


def import_cycles(graph) -> list[list[str]]:
    """Every cycle a depth-first walk of ``graph`` closes, each as the modules round it."""
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
    return cycles


def test_no_import_cycles():
    """No cycle among vibkit's modules, counting the imports inside functions too: a function-level import does
    not make a cycle harmless, it only hides it until the function runs."""
    cycles = import_cycles(_graph())
    assert not cycles, "import cycles:\n" + "\n".join(" -> ".join(c) for c in cycles)


#: the start-ups that must stay light, and why: ``import vibkit`` (its names load on first use), ``vibkit --help``
#: (a command imports the library when it runs) and reading or checking a scene or an escalator profile (``vibkit
#: scene``, a sweep's plan: no compiled kernel needed). The only function-level import of vibkit's own code allowed
#: is one that keeps a module out of such a start-up: from a module that start-up loads, of one it does not
LIGHT_ROOTS = ("vibkit", "vibkit.cli", "vibkit.model.scene", "vibkit.model.profile")
#: third-party packages too heavy for a light start-up (compilers, plotting, readers, clusters, databases)
HEAVY = frozenset({"numba", "scipy", "matplotlib", "obspy", "dask", "distributed", "zarr", "psycopg", "xarray"})


def loaded_by(root, graph) -> set[str]:
    """The modules that importing ``root`` loads (``graph``: the load-time imports), its packages included."""
    seen, todo = set(), [root]
    while todo:
        n = todo.pop()
        if n in seen or n not in graph:
            continue
        seen.add(n)
        parts = n.split(".")
        todo += [".".join(parts[:k]) for k in range(1, len(parts))]
        todo += sorted(graph[n])
    return seen


#: own modules that may be imported inside a function from anywhere, and why: the signal layer's compiled kernels
#: (numba) load only where a kernel runs, so that reading a recording and its spectrum compile and import nothing
#: of numba (tests/cli/test_startup_imports.py)
#: and the worn link's signature's runs (the model's kernels), loaded only where no run kept on disk serves, so that a
#: warm ``vibkit links`` reads its kept signature without loading the model or numba
DEFERRED_ALLOWED = {
    "vibkit.signal.kernels": "numba's kernels, loaded where they run",
    "vibkit.diagnose.link_signature_runs": "the model's kernels, loaded where a kept signature run misses",
    "vibkit.diagnose.fresh_simulation": "the model's kernels, loaded where a kept simulation misses",
}


def deferred_own_imports() -> list[str]:
    """Function-level imports of vibkit's own modules that keep no light start-up light (:data:`LIGHT_ROOTS`)."""
    load = _graph(at_load_only=True)
    starts = [loaded_by(root, load) for root in LIGHT_ROOTS]
    bad = []
    for name in MODULES:
        for target, line, at_load in _imports(name):
            if at_load or target not in MODULES or target == name or name.startswith(target + "."):
                continue
            if target in DEFERRED_ALLOWED:
                continue
            if any(name in s and target not in s for s in starts):
                continue  # deferred so that a light start-up stays light
            bad.append(f"{name}:{line} imports {target} inside a function (import it at the top of the module)")
    return bad


def test_own_modules_imported_at_the_top():
    bad = deferred_own_imports()
    assert not bad, "\n".join(bad)


def heavy_at_load(name) -> set[str]:
    """The :data:`HEAVY` packages module ``name`` imports at load time."""
    path, _ = MODULES[name]
    found = set()
    for node in ast.parse(path.read_text()).body:
        if isinstance(node, ast.Import):
            found |= {a.name.split(".")[0] for a in node.names}
        elif isinstance(node, ast.ImportFrom) and not node.level and node.module:
            found.add(node.module.split(".")[0])
    return found & HEAVY


def test_the_light_start_ups_load_nothing_heavy():
    """No module a light start-up loads imports a heavy package at load time: what the deferral above allows is
    what keeps these start-ups light, and no loophole."""
    load = _graph(at_load_only=True)
    light = set().union(*(loaded_by(root, load) for root in LIGHT_ROOTS))
    heavy = {n: sorted(heavy_at_load(n)) for n in sorted(light) if heavy_at_load(n)}
    assert not heavy, heavy


@pytest.fixture
def plant(tmp_path, monkeypatch):
    """``plant(vibkit__pkg__name="source")``: module ``vibkit.pkg.name`` added to (or replaced in) MODULES, its
    source written under a temporary folder; the checks then read it as one of the package's."""

    def _plant(**files):
        fake = dict(MODULES)
        for key, text in files.items():
            path = tmp_path / f"{key}.py"
            path.write_text(text)
            fake[key.replace("__", ".")] = (path, False)
        monkeypatch.setitem(globals(), "MODULES", fake)

    return _plant


def test_the_checks_can_fail(plant):
    """A lazy upward import and a load-time cycle, planted in fake modules, are caught."""
    plant(
        vibkit__signal__fake_signal="def f():\n    from ..model.scene import load_scene\n",
        vibkit__runtime__a="from . import b\n",
        vibkit__runtime__b="from .a import x\n",
    )
    with pytest.raises(AssertionError, match="fake_signal:2"):
        test_imports_run_one_way()
    with pytest.raises(AssertionError, match="vibkit.runtime.a -> vibkit.runtime.b -> vibkit.runtime.a"):
        test_no_import_cycles()


def test_a_cycle_through_a_function_level_import_is_caught(plant):
    """One module importing the other at the top, the other importing it back inside a function: a cycle."""
    plant(
        vibkit__diagnose__fake_a="from .fake_b import y\n",
        vibkit__diagnose__fake_b="def y():\n    from .fake_a import x\n    return x\n",
    )
    assert import_cycles(_graph(at_load_only=True)) == []  # invisible at load time
    with pytest.raises(AssertionError, match=r"diagnose.fake_a -> vibkit.diagnose.fake_b -> vibkit.diagnose.fake_a"):
        test_no_import_cycles()


def test_a_function_level_import_of_own_code_is_caught(plant):
    """A planted function-level import of vibkit's own code is reported with its line."""
    plant(vibkit__fleet__fake_lazy="import math\n\n\ndef f():\n    from ..analyses.simulation import simulate\n")
    with pytest.raises(AssertionError, match="fleet.fake_lazy:5 imports vibkit.analyses.simulation inside a function"):
        test_own_modules_imported_at_the_top()


def test_a_command_defers_the_library_only(plant):
    """A command (loaded by ``vibkit --help``) may defer the library, not a module ``--help`` loads anyway."""
    app = MODULES["vibkit.cli.app"][0].read_text() + "\nfrom . import fake_cmd\n"
    plant(
        vibkit__cli__app=app,
        vibkit__cli__fake_cmd="def run(a):\n    from vibkit.analyses.simulation import simulate\n",
    )
    assert not [b for b in deferred_own_imports() if "fake_cmd" in b]
    plant(vibkit__cli__fake_cmd="def run(a):\n    from .output import msg\n")
    with pytest.raises(AssertionError, match="cli.fake_cmd:2 imports vibkit.cli.output inside a function"):
        test_own_modules_imported_at_the_top()


def test_the_heavy_check_can_fail(plant):
    """A module ``vibkit --help`` loads that imports numba at load time is caught."""
    plant(vibkit__cli__app=MODULES["vibkit.cli.app"][0].read_text() + "\nimport numba\n")
    with pytest.raises(AssertionError, match="vibkit.cli.app.*numba"):
        test_the_light_start_ups_load_nothing_heavy()


#: the names the compiled kernels give their parameter and work arrays and tuples (vibkit.model.slots),
#: the integrator's step control and counters: a compiled kernel reads them by named slot, never by a
#: bare number
SLOT_ARRAYS = frozenset({"prm", "fp", "ip", "ws", "info", "tb", "head", "ctl", "counters"})
#: arrays of one row per roller whose columns are named slots (the closure's partials, PART_* of
#: vibkit.model.slots): the row may be a number (roller 1 is part[0, ...]), the column may not
COLUMN_ARRAYS = frozenset({"part"})


def _decorators(fn: ast.AST) -> set[str]:
    """The names of a function's decorators (bare, called, or as nb.njit)."""
    names = set()
    for dec in fn.decorator_list:
        target = dec.func if isinstance(dec, ast.Call) else dec
        names.add(target.attr if isinstance(target, ast.Attribute) else getattr(target, "id", None))
    return names


def _is_compiled(fn: ast.AST) -> bool:
    """Whether a function is compiled by numba: njit, jit, or vibkit.runtime.kernel's kernel."""
    return bool(_decorators(fn) & {"njit", "jit", "kernel"})


def _literal_int(node: ast.AST | None) -> bool:
    if isinstance(node, ast.UnaryOp) and isinstance(node.op, (ast.USub, ast.UAdd)):
        node = node.operand
    return isinstance(node, ast.Constant) and isinstance(node.value, int)


def _bare_slot(index: ast.AST) -> bool:
    """A bare integer, a slice with a bare integer bound, or a tuple index holding either."""
    if _literal_int(index):
        return True
    if isinstance(index, ast.Slice):
        return _literal_int(index.lower) or _literal_int(index.upper)
    if isinstance(index, ast.Tuple):
        return any(_bare_slot(e) for e in index.elts)
    return False


def _bare_column(node: ast.Subscript) -> bool:
    """``part[i, 2]``: a bare number as the column of a :data:`COLUMN_ARRAYS` array."""
    index = node.slice
    if not (isinstance(node.value, ast.Name) and node.value.id in COLUMN_ARRAYS):
        return False
    return isinstance(index, ast.Tuple) and _bare_slot(index.elts[-1])


def bare_slots(source: str, filename: str = "<string>") -> list[str]:
    """``file:line: kernel reads array[...]`` for each bare-number subscript of a slot array
    (:data:`SLOT_ARRAYS`, also ``prm[2][5]``) and each bare-number column of a :data:`COLUMN_ARRAYS`
    array inside a compiled kernel of ``source``."""
    found = []
    for fn in ast.walk(ast.parse(source, filename=filename)):
        if not (isinstance(fn, (ast.FunctionDef, ast.AsyncFunctionDef)) and _is_compiled(fn)):
            continue
        for node in ast.walk(fn):
            if not isinstance(node, ast.Subscript):
                continue
            if _bare_column(node):
                found.append(f"{filename}:{node.lineno}: {fn.name} reads {ast.unparse(node)}")
                continue
            if not _bare_slot(node.slice):
                continue
            base = node.value
            while isinstance(base, ast.Subscript):  # prm[PRM_IP][3]: the array is prm's slot
                base = base.value
            if isinstance(base, ast.Name) and base.id in SLOT_ARRAYS:
                found.append(f"{filename}:{node.lineno}: {fn.name} reads {ast.unparse(node)}")
    return found


def test_compiled_kernels_read_slots_by_name():
    found = []
    for _, (path, _) in sorted(MODULES.items()):
        found += bare_slots(path.read_text(), str(path.relative_to(PKG.parent)))
    assert not found, "name the slot (vibkit.model.slots):\n" + "\n".join(found)


def test_the_slot_check_can_fail():
    source = (
        "import numba as nb\n"
        "from numba import njit\n"
        "@nb.njit(cache=True)\n"
        "def k(fp, ip, prm, info):\n"
        "    a = fp[3] + fp[FP_G]\n"
        "    info[10:13] = 0.0\n"
        "    return prm[3][-1] + ip[IP_N]\n"
        "@njit\n"
        "def j(ws, ctl, counters, part):\n"
        "    counters[2] += 1\n"
        "    return ws[18] + ctl[3] + part[0, PART_XS] + part[i, 2]\n"
        "def python_side(fp, ctl):\n"
        "    return fp[3] + ctl[3]\n"
    )
    found = sorted(f.split(": ", 1)[1] for f in bare_slots(source))
    assert found == [
        "j reads counters[2]",
        "j reads ctl[3]",
        "j reads part[i, 2]",
        "j reads ws[18]",
        "k reads fp[3]",
        "k reads info[10:13]",
        "k reads prm[3]",
        "k reads prm[3][-1]",
    ]


# --- kernels without reference counts -------------------------------------------------------------

#: the compiled functions of the model and the analyses that allocate arrays (or call one that does), so
#: keep numba's reference counts (``numba.njit``); every other kernel there is ``vibkit.runtime.kernel.kernel``
ALLOCATING = frozenset(
    {
        "walk_arrays",  # the walk's scratch
        "sweep_kernel",  # calls walk_arrays
        "_nodes",  # the pitch table's nodes, walk_arrays
        "_near",  # the segments within the sprocket's reach
        "_observe",  # the outputs' scratch
        "_dopri5_chunk",  # the stages
        "kkt_pattern",  # the study's sparse pattern
    }
)


def plain_njit(source: str, filename: str = "<string>") -> list[str]:
    """``file:line: name`` for each function of ``source`` compiled with numba's njit or jit (not ``kernel``)."""
    return [
        f"{filename}:{fn.lineno}: {fn.name}"
        for fn in ast.walk(ast.parse(source, filename=filename))
        if isinstance(fn, ast.FunctionDef) and _decorators(fn) & {"njit", "jit"}
    ]


def test_model_kernels_are_compiled_without_reference_counts():
    """numba's atomic reference counts took 42-45 % of the forward run's CPU time (docs/developer.md): a
    kernel of the model or the analyses is ``kernel()`` unless it allocates."""
    found = []
    for name, (path, _) in sorted(MODULES.items()):
        if name.startswith(("vibkit.model", "vibkit.analyses")):
            found += [f for f in plain_njit(path.read_text(), str(path)) if f.rsplit(": ", 1)[1] not in ALLOCATING]
    assert not found, "use vibkit.runtime.kernel.kernel() (or add an allocating kernel to ALLOCATING):\n" + "\n".join(
        found
    )


def test_the_reference_count_check_can_fail():
    source = "import numba as nb\n@nb.njit(cache=True)\ndef a(x):\n    return x\n@kernel()\ndef b(x):\n    return x\n"
    assert [f.split(": ", 1)[1] for f in plain_njit(source)] == ["a"]


# --- scene keys are read through the schema -------------------------------------------------------

#: the modules that read the raw scene (its TOML tables) and fill in defaults
SCHEMA_MODULES = {"vibkit.model.schema", "vibkit.model.scene", "vibkit.model.scene_checks", "vibkit.model.profile"}
#: modules that may parse scene TOML, and why
RAW_TOML_ALLOWED = {
    "vibkit.sweep.plan": "writes varied copies of a scene's TOML text; each copy is validated when it is loaded",
}


def _schema_names():
    from vibkit.model.schema import EFFECTS

    return set(EFFECTS), {k for opts in EFFECTS.values() for k in opts}


def _literal_key(node):
    """The string literal ``node`` reads by, for ``x["k"]`` and ``x.get("k", ...)`` / setdefault / pop."""
    if isinstance(node, ast.Subscript) and isinstance(node.slice, ast.Constant) and isinstance(node.slice.value, str):
        return node.value, node.slice.value
    if (
        isinstance(node, ast.Call)
        and isinstance(node.func, ast.Attribute)
        and node.func.attr in ("get", "setdefault", "pop")
        and node.args
        and isinstance(node.args[0], ast.Constant)
        and isinstance(node.args[0].value, str)
    ):
        return node.func.value, node.args[0].value
    return None, None


def scene_key_reads(source: str, name: str) -> list[str]:
    """Places in module ``name`` that read a scene key around the schema (empty for the schema modules).

    Flagged: parsing TOML (``tomllib``) outside the schema modules and :data:`RAW_TOML_ALLOWED`; the
    untyped tables of given keys (``scene.section(...)``, ``scene.sections``), whose missing keys would
    need a default restated; and an effect's option read by a string (``effects["contact"]["damping"]``,
    ``o = effects["motor"]; o.get("ki", 0.0)``): options are typed, their defaults in the schema.
    """
    if name in SCHEMA_MODULES:
        return []
    effect_names, option_keys = _schema_names()
    tree = ast.parse(source)
    bad = []

    def effect_table(node):
        recv, key = _literal_key(node)
        return recv is not None and key in effect_names

    # names bound to one effect's options: o = effects["contact"]
    bound = set()
    for node in ast.walk(tree):
        if isinstance(node, ast.Assign) and effect_table(node.value):
            bound |= {t.id for t in node.targets if isinstance(t, ast.Name)}
    for node in ast.walk(tree):
        line = getattr(node, "lineno", 0)
        if isinstance(node, (ast.Import, ast.ImportFrom)) and name not in RAW_TOML_ALLOWED:
            mods = [a.name for a in node.names] if isinstance(node, ast.Import) else [node.module or ""]
            if "tomllib" in mods:
                bad.append(f"{name}:{line} parses TOML (scenes are read by vibkit.model.scene)")
        if isinstance(node, ast.Attribute) and node.attr == "sections":
            bad.append(f"{name}:{line} reads Scene.sections (use the typed scene.run, scene.solver, ...)")
        if isinstance(node, ast.Call) and isinstance(node.func, ast.Attribute) and node.func.attr == "section":
            bad.append(f"{name}:{line} reads scene.section(...) (use the typed scene.run, scene.solver, ...)")
        recv, key = _literal_key(node)
        if key in option_keys and (effect_table(recv) or (isinstance(recv, ast.Name) and recv.id in bound)):
            bad.append(f"{name}:{line} reads effect option '{key}' by name (use the typed options' attribute)")
    return bad


def test_scene_keys_are_read_through_the_schema():
    bad = []
    for name, (path, _) in MODULES.items():
        bad += scene_key_reads(path.read_text(), name)
    assert not bad, "\n".join(bad)


@pytest.mark.parametrize(
    "snippet",
    [
        "import tomllib\n",
        "x = scene.section('run').get('start', 0.0)\n",
        "x = dict(scene.sections)\n",
        "k = effects['contact'].get('damping', 0.0)\n",
        "k = effects.get('motor', {}).get('ki', 0.0)\n",
        "o = effects['tensioner']\nk = o['stiffness']\n",
    ],
)
def test_the_scene_key_check_can_fail(snippet):
    """Each way around the schema, planted in a fake module, is caught; typed reads are not."""
    assert scene_key_reads(snippet, "vibkit.analyses.fake"), snippet
    assert scene_key_reads(snippet, "vibkit.model.scene") == []


def test_typed_scene_reads_pass_the_scene_key_check():
    ok = "k = effects['contact'].damping\nr = scene.run.start\nf = FP['g']\nv = scene.outputs['variables']\n"
    assert scene_key_reads(ok, "vibkit.analyses.fake") == []
