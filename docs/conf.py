"""Sphinx configuration of vibkit's documentation (``make docs``; every warning is an error).

Pages are Markdown (MyST); the API reference (the public API only, never a recursive walk of the package) is
generated from the numpydoc docstrings by autodoc and autosummary. Two kinds of page are written at build time, never by hand (both ignored by git):

* ``api/generated/``: autosummary's stub page for each documented object;
* ``benchmarks/results/``: one page per ``benchmarks/results/*.md`` that includes it, so that what
  ``make bench`` writes is what the documentation shows.
* ``auto_examples/``: the examples gallery, each ``examples/plot_*.py`` run by sphinx-gallery and its
  figures saved; the guide pages show those figures, so every build redraws them with this version. Two
  examples draw a PDF's pages with ``pdftoppm`` (poppler-utils), which the build therefore needs.

Maths is rendered by MathJax 3 copied into the built site by ``sphinx-mathjax-offline`` (no CDN: the pages
read offline, and MathJax keeps the maths selectable text, which images would not).
"""

from __future__ import annotations

import sys
from pathlib import Path

DOCS = Path(__file__).resolve().parent
ROOT = DOCS.parent
sys.path.insert(0, str(ROOT))  # autodoc imports this checkout's vibkit, installed or not

import vibkit  # noqa: E402

project = "vibkit"
author = "the vibkit developers"
copyright = "the vibkit developers, BSD-3-Clause"
version = release = vibkit.__version__

extensions = [
    "myst_parser",
    "numpydoc",
    "sphinx.ext.autodoc",
    "sphinx.ext.autosummary",
    "sphinx.ext.mathjax",
    # MathJax 3 served from the built site (_static/mathjax), not from a CDN: the maths renders offline
    "sphinx-mathjax-offline",
    # the examples gallery: docs/examples/plot_*.py run at every build, their figures shown on the gallery
    # pages and on the guide pages (docs/auto_examples/ is written by the build, ignored by git)
    "sphinx_gallery.gen_gallery",
]
source_suffix = {".md": "markdown", ".rst": "restructuredtext"}
templates_path = ["_templates"]
exclude_patterns = ["_build", "_templates", "**/.ipynb_checkpoints", "examples", "sg_execution_times.rst"]
myst_enable_extensions = ["dollarmath", "colon_fence", "deflist"]
myst_heading_anchors = 3

# autodoc / autosummary / numpydoc
autosummary_generate = True
autosummary_ignore_module_all = False  # a package's page lists its __all__
autosummary_imported_members = False
autodoc_default_options = {"members": True, "show-inheritance": False}
autodoc_typehints = "none"  # the numpydoc Parameters section says the types
numpydoc_show_class_members = False
numpydoc_class_members_toctree = False
numpydoc_validation_checks: set[str] = set()
numpydoc_xref_param_type = False

html_theme = "pydata_sphinx_theme"
html_title = f"vibkit {release}"
html_theme_options = {"navigation_with_keys": False, "show_toc_level": 2}
html_static_path = ["_static"]
html_css_files = ["vibkit.css"]  # wide code blocks and tables: the content column uses the window's width

sphinx_gallery_conf = {
    "examples_dirs": "examples",
    "gallery_dirs": "auto_examples",
    "filename_pattern": r"/plot_",
    "within_subsection_order": "FileNameSortKey",
    "download_all_examples": False,
    "remove_config_comments": True,
    "matplotlib_animations": False,
    "image_scrapers": ("matplotlib",),
    "reset_modules": ("matplotlib",),
    "show_memory": False,
    "write_computation_times": False,
}

# -- pages generated at build time -------------------------------------------------------------------

RESULTS = ROOT / "benchmarks" / "results"
RESULT_PAGES = DOCS / "benchmarks" / "results"


def _write_if_changed(path: Path, text: str) -> None:
    if not path.exists() or path.read_text(encoding="utf-8") != text:
        path.parent.mkdir(parents=True, exist_ok=True)
        path.write_text(text, encoding="utf-8")


def write_benchmark_pages() -> None:
    """One page per ``benchmarks/results/*.md``: its file name as the title, the file included."""
    wanted = set()
    for src in sorted(RESULTS.glob("*.md")):
        page = RESULT_PAGES / src.name
        wanted.add(page.name)
        rel = Path("..", "..", "..", "benchmarks", "results", src.name).as_posix()
        text = (
            f"# {src.stem}\n\n"
            f"`benchmarks/results/{src.name}`, as `make bench` last wrote it.\n\n"
            f"```{{include}} {rel}\n:heading-offset: 1\n:relative-images:\n```\n"
        )
        _write_if_changed(page, text)
    for old in RESULT_PAGES.glob("*.md"):
        if old.name not in wanted:
            old.unlink()


write_benchmark_pages()


def write_scene_keys_page() -> None:
    """The scene reference: every key of the scene schema (vibkit.model.schema), rendered from it."""
    from vibkit.model.schema import schema_table

    text = (
        "# Scene keys\n\n"
        "Every key a scene file (`sim/*.toml`) may hold, with its unit, default and plausible range, "
        "rendered from the scene schema (`vibkit/model/schema.py`) at each build: the schema is the one "
        "place a key is declared, validated and documented. *required*: the scene must give it; "
        "*not set*: the key is optional and its meaning says what happens without it.\n\n"
        + schema_table()
        + "\n"
    )
    _write_if_changed(DOCS / "api" / "generated" / "scene-keys.md", text)


write_scene_keys_page()


def write_profile_keys_page() -> None:
    """The escalator profile's reference: every key of a profile (vibkit.model.profile), rendered from it."""
    from vibkit.model.profile import profile_table

    text = (
        "# Escalator profile keys\n\n"
        "Every key an escalator profile (`--escalator FILE`, `vibkit scene FILE`) may hold, with its unit, "
        "default and plausible range, rendered from `vibkit/model/profile.py` at each build with the scene "
        "schema's machinery. *required*: the profile must give it; *not set*: optional, its meaning says "
        "what happens without it. A profile gives `chain.n_links`, or an escalator's `geometry.rise` and "
        "`geometry.incline_deg`, or a moving walk's `geometry.length` and `geometry.incline_deg` (0 to 12 deg); "
        "the geometry's keys are checked together (see the guide's section on moving walks).\n\n" + profile_table() + "\n"
    )
    _write_if_changed(DOCS / "api" / "generated" / "profile-keys.md", text)


write_profile_keys_page()


def write_glossary_page() -> None:
    """The glossary: the report's glossary page (vibkit.diagnose.report.appendix.GLOSSARY), one place for both."""
    from vibkit.diagnose.report.appendix import GLOSSARY

    terms = "\n".join(f"{term}\n: {text}\n" for term, text in GLOSSARY)
    text = (
        "# Glossary\n\n"
        "The words of vibkit's reports and guides, as a field engineer needs them: the same text as the last "
        "page of every report (`vibkit/diagnose/report/appendix.py`, rendered at each build).\n\n" + terms
    )
    _write_if_changed(DOCS / "api" / "generated" / "glossary.md", text)


write_glossary_page()


def _changelog_guard(app, docname, source):
    """The changelog page includes ``CHANGELOG.md`` from the repository root, given a title if its first
    heading is not one; without the file the page says so instead of failing the build."""
    if docname != "changelog":
        return
    path = ROOT / "CHANGELOG.md"
    if not path.exists():
        source[0] = "# Changelog\n\nThis checkout has no `CHANGELOG.md` at the repository root.\n"
        return
    first = next((line for line in path.read_text(encoding="utf-8").splitlines() if line.startswith("#")), "")
    if not first.startswith("# "):
        source[0] = "# Changelog\n\n```{include} ../CHANGELOG.md\n```\n"


def _escape_bars(app, what, name, obj, options, lines):
    """Docstrings write |x| for an absolute value; reST would read a substitution: escape the bars.

    Bars inside ``literals`` and lines that are reST tables or line blocks are left alone.
    """
    for i, line in enumerate(lines):
        if "|" not in line or line.lstrip().startswith(("|", "+")):
            continue
        parts = line.split("``")
        parts[::2] = [p.replace("|", "\\|") for p in parts[::2]]
        lines[i] = "``".join(parts)


def _skip_shadowed(app, what, name, obj, skip, options):
    """``vibkit.sweep`` is both the function and the package: the package's page documents it."""
    if what != "module" and callable(obj) and (ROOT / "vibkit" / name / "__init__.py").exists():
        return True
    return None


def setup(app):
    app.connect("source-read", _changelog_guard)
    app.connect("autodoc-process-docstring", _escape_bars)
    app.connect("autodoc-skip-member", _skip_shadowed)
