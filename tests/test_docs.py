"""The API reference lists what vibkit.signal exports, and every docs page is reachable from a toctree.

The Sphinx build itself (``make docs``, warnings as errors) checks the pages' syntax, references and
docstrings; these checks are the ones it cannot make: a name added to ``vibkit.signal.__all__`` but not
to a topic of ``docs/api/signal.rst`` would silently be missing from the reference.
"""

import re
from pathlib import Path

import vibkit.signal

DOCS = Path(__file__).resolve().parents[1] / "docs"


def test_every_signal_export_is_in_the_reference():
    text = (DOCS / "api" / "signal.rst").read_text(encoding="utf-8")
    listed = set(re.findall(r"^   (\w+)$", text, re.M)) | set(re.findall(r"``(\w+)``", text))
    missing = sorted(set(vibkit.signal.__all__) - listed)
    assert missing == [], f"vibkit.signal exports {missing}: list each under its topic in docs/api/signal.rst"
    unknown = sorted(n for n in re.findall(r"^   (\w+)$", text, re.M) if n not in vibkit.signal.__all__)
    assert unknown == [], f"docs/api/signal.rst lists names vibkit.signal does not export: {unknown}"


def test_every_page_is_in_a_toctree():
    pages = {
        p.relative_to(DOCS).with_suffix("").as_posix()
        for p in DOCS.rglob("*")
        if p.suffix in (".md", ".rst")
        and not {"_build", "_templates", "generated", "results", "examples", "auto_examples"} & set(p.parts)
    }
    linked = {"index"}
    for page in pages:
        path = next(DOCS.glob(page + ".*"))
        folder = Path(page).parent
        for block in re.findall(r"```\{toctree\}(.*?)```|\.\. toctree::(.*?)(?:\n\S|\Z)", path.read_text(), re.S):
            for line in "".join(block).splitlines():
                line = line.strip()
                if line and not line.startswith(":"):
                    linked.add((folder / line).as_posix())
    assert sorted(pages - linked) == []


def test_the_signal_package_docstring_lists_every_export_under_a_topic():
    doc = vibkit.signal.__doc__
    listed = set(re.findall(r"\b(\w+)\b", doc.split("Spectral analysis", 1)[1].split("Everything else", 1)[0]))
    missing = sorted(set(vibkit.signal.__all__) - listed)
    assert missing == [], f"vibkit.signal's docstring does not list {missing} under a topic"


def test_the_api_reference_documents_the_public_api_only():
    # no package is walked recursively (that generated a page for every internal module); each object a page
    # names by its full path exists and is public (no leading underscore in any part of its name)
    import importlib

    for page in (DOCS / "api").glob("*.rst"):
        text = page.read_text(encoding="utf-8")
        assert ":recursive:" not in text, f"docs/api/{page.name} walks a package recursively"
        for name in re.findall(r"^   (vibkit\.[\w.]+)$", text, re.M):
            assert not any(part.startswith("_") for part in name.split(".")), f"{page.name}: {name} is private"
            module, _, attr = name.rpartition(".")
            try:
                obj = importlib.import_module(name)
            except ImportError:
                obj = getattr(importlib.import_module(module), attr, None)
            assert obj is not None, f"docs/api/{page.name} names {name}, which does not exist"


def test_guide_pages_cite_no_test_paths_and_no_measurement_dates():
    # the guides say what a command does and how well; the tests behind it and each run's date and machine
    # are on docs/explanation/validation.md and the benchmark results pages
    for page in sorted((DOCS / "guide").glob("*.md")):
        text = re.sub(r"```.*?```", "", page.read_text(encoding="utf-8"), flags=re.S)
        assert not re.search(r"`tests/", text), f"docs/guide/{page.name} cites a test path"
        for para in text.split("\n\n"):
            dated = re.search(r"\b20\d\d-\d\d-\d\d\b", para)
            measured = re.search(r"load average|sandbox|Intel|AMD|EPYC|\bUTC\b", para)
            assert not (dated and measured), f"docs/guide/{page.name} dates a measurement: {para[:80]!r}"


def test_every_guide_page_has_a_figure_the_build_draws_or_a_benchmark_wrote():
    # a figure of the examples gallery (docs/examples/plot_*.py, run by every build) or a benchmark's own plot
    examples = {p.stem for p in (DOCS / "examples").glob("plot_*.py")}
    for page in sorted((DOCS / "guide").glob("*.md")):
        if page.name == "index.md":
            continue
        text = page.read_text(encoding="utf-8")
        drawn = set(re.findall(r"auto_examples/images/sphx_glr_(plot_\w+?)_\d{3}\.png", text))
        assert drawn or re.search(r"!\[[^\]]*\]\([^)]*\.png\)", text), f"docs/guide/{page.name} has no figure"
        assert drawn <= examples, f"docs/guide/{page.name} shows figures of no example: {sorted(drawn - examples)}"
