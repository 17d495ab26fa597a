"""Installed size of vibkit's dependencies: the base install and each extra, from the distributions installed here.

For each set of requirements (pyproject.toml's ``dependencies``, alone and with each extra), the
closure of their requirements is walked through ``importlib.metadata`` (markers evaluated for this
interpreter, requirement extras such as ``psycopg[binary]`` followed), and the sizes of the files
each distribution's RECORD lists are added up: what ``pip install`` puts into site-packages, without
pip itself, Python, and byte code compiled later.  "before" is the base as it was when obspy,
distributed and zarr were hard dependencies.  Writes benchmarks/results/install_size.{md,csv}.

Run: ``python benchmarks/install_size.py`` in an environment where ``pip install -e '.[test]'`` ran.
"""

from __future__ import annotations

import importlib.metadata as md
import re
import tomllib
from pathlib import Path

from packaging.markers import default_environment
from packaging.requirements import Requirement

from _common import RESULTS, machine, markdown_table, today, write_csv, write_text

ROOT = Path(__file__).resolve().parents[1]
MOVED = ["obspy>=1.4", "distributed>=2024.1", "zarr>=2.18"]  # hard dependencies before they became extras


def _norm(name):
    return re.sub(r"[-_.]+", "-", name).lower()


def _size(dist) -> int:
    total = 0
    for f in dist.files or ():
        try:
            total += f.locate().stat().st_size
        except OSError:
            pass
    return total


def closure(requirements) -> dict[str, int]:
    """{distribution: installed bytes} of ``requirements`` and everything they require."""
    env = default_environment()
    seen, todo = {}, [(Requirement(r), "") for r in requirements]
    while todo:
        req, extra = todo.pop()
        if req.marker is not None and not req.marker.evaluate({**env, "extra": extra}):
            continue
        name = _norm(req.name)
        key = (name, tuple(sorted(req.extras)))
        if key in seen:
            continue
        try:
            dist = md.distribution(req.name)
        except md.PackageNotFoundError:
            seen[key] = None
            continue
        seen[key] = dist
        for r in dist.requires or ():
            rr = Requirement(r)
            if rr.marker is None or rr.marker.evaluate({**env, "extra": ""}):
                todo.append((rr, ""))
            else:
                for e in req.extras:
                    if rr.marker.evaluate({**env, "extra": e}):
                        todo.append((rr, e))
    out = {}
    for (name, _), dist in seen.items():
        if dist is not None:
            out[name] = _size(dist)
    return out


def main():
    project = tomllib.loads((ROOT / "pyproject.toml").read_text())["project"]
    base = list(project["dependencies"])
    extras = project["optional-dependencies"]
    sets = {"base": base, "before (obspy, distributed, zarr required)": base + MOVED}
    for name in ("seismic", "parallel", "tdms", "postgres"):
        if name in extras:
            sets[f"base + {name}"] = base + list(extras[name])
    base_pkgs = closure(base)
    rows = []
    for label, reqs in sets.items():
        pk = closure(reqs)
        added = sorted(set(pk) - set(base_pkgs), key=lambda n: -pk[n])
        rows.append(
            {
                "install": label,
                "distributions": len(pk),
                "size_MB": round(sum(pk.values()) / 1e6, 1),
                "beyond the base": ", ".join(f"{n} {pk[n] / 1e6:.1f}" for n in added[:6]) or "-",
            }
        )
    top = sorted(base_pkgs.items(), key=lambda kv: -kv[1])[:8]
    text = (
        "# Installed size of vibkit's dependencies\n\n"
        f"{today()}, {machine()}; `python benchmarks/install_size.py` (sizes of the files each installed "
        "distribution's RECORD lists, in MB = 1e6 bytes; pip, Python and later byte code not counted).\n\n"
        + markdown_table(rows)
        + "\n\nLargest in the base: "
        + ", ".join(f"{n} {s / 1e6:.1f} MB" for n, s in top)
        + ".\n"
    )
    write_text(RESULTS / "install_size.md", text)
    write_csv(RESULTS / "install_size.csv", rows)
    print(text)


if __name__ == "__main__":
    main()
