"""The example recordings and the example fleet shipped with vibkit: ``vibkit.datasets.path("leon-tensioner")``.

The repository keeps them in ``data/field/`` (the two field cases, rebuilt from the published summaries of
the study, and small files in the layouts of the loggers people bring) and ``data/fleet-example/`` (a
synthetic fleet of three escalators measured once a year); building the wheel copies those two folders and
their provenance (``data/README.md``) into this package (``setup.py``), so an installed vibkit has them
without a clone.  In a clone (an editable install, ``PYTHONPATH``) they are read from ``data/`` directly.
Nothing else of ``data/`` ships: the third-party and device files keep their own licences.

None of these files is an original field recording: each is made by a seeded script of the repository
(``data/make_field_data.py``, ``data/make_fleet_example.py``), as its header and :func:`provenance` say.

A file is named by its path under ``data/`` (``"field/leon-tensioner.csv"``, with or without the leading
``data/``) or, where that is unique, by its name without the extension (``"leon-tensioner"``, ``"phyphox"``,
``"units"``); the two folders by their names (``"fleet-example"``).  :func:`copy` writes them all into a
folder in the repository's layout, so that the documentation's examples (``data/field/leon-tensioner.csv``)
run as written from any folder after ``vibkit datasets copy data``:

>>> import vibkit.datasets
>>> vibkit.datasets.path("leon-tensioner").name
'leon-tensioner.csv'
>>> "fleet-example/units.csv" in vibkit.datasets.names()
True
"""

from __future__ import annotations

import filecmp
import os
import shutil
from pathlib import Path

__all__ = ["names", "path", "provenance", "copy", "folder"]

_HERE = Path(__file__).resolve().parent
_SHIPPED = _HERE / "files"  # what setup.py copies into the built package
_CLONE = _HERE.parents[1] / "data"  # the repository's data/, when running from a clone
#: the folders of data/ that ship, and what each holds (the long provenance: data/README.md, shipped as README.md)
FOLDERS = {
    "field": (
        "vibkit reconstructions of the study's two field recordings (Las Palmas accelerometer, Leon tensioner) "
        "from its published figures and numbers, and synthetic files in the layouts of common loggers "
        "(layouts/); made by data/make_field_data.py with a fixed seed, NOT original recordings"
    ),
    "fleet-example": (
        "a SYNTHETIC fleet of three escalators (E07, E12, E21) measured once a year 2024-2026, their profiles "
        "(escalators/) and the catalogue units.csv; made by data/make_fleet_example.py with fixed seeds"
    ),
}
LICENCE = "BSD-3-Clause, as vibkit (the files are vibkit's own, made by its scripts)"


def folder() -> Path:
    """The folder holding ``field/`` and ``fleet-example/``: this package's copy once installed, else the clone's data/."""
    if (_SHIPPED / "field").is_dir():
        return _SHIPPED
    return _CLONE


def _files() -> list[str]:
    root = folder()
    found = []
    for top in FOLDERS:
        for p in sorted((root / top).rglob("*")):
            if p.is_file() and "__pycache__" not in p.parts:
                found.append(p.relative_to(root).as_posix())
    return found


def names() -> tuple[str, ...]:
    """Every shipped file, as its path under ``data/`` (``"field/leon-tensioner.csv"`` ...), sorted."""
    return tuple(sorted(_files()))


def _stem(rel: str) -> str:
    name = rel.rsplit("/", 1)[-1]
    return name.split(".", 1)[0]


def path(name: str) -> Path:
    """The shipped file or folder ``name`` names.

    Parameters
    ----------
    name : str
        A path under ``data/`` (``"field/leon-tensioner.csv"``, ``"data/fleet-example/units.csv"``), a file's
        name without its extension where that is unique (``"leon-tensioner"``), or a shipped folder
        (``"fleet-example"``, ``"field/layouts"``).

    Raises
    ------
    ValueError
        Nothing shipped has that name (the message says how to list them), or a bare name is ambiguous
        (the message lists the candidates).
    """
    key = str(name).strip().removeprefix("./").removeprefix("data/").rstrip("/")
    root = folder()
    files = _files()
    if key in files or (key and any(f.startswith(key + "/") for f in files)):
        return root / key
    matches = [f for f in files if _stem(f) == key or f.rsplit("/", 1)[-1] == key]
    if len(matches) == 1:
        return root / matches[0]
    if matches:
        raise ValueError(f"dataset {name!r} names {len(matches)} files: {', '.join(matches)}; give one of these paths")
    raise ValueError(
        f"no shipped dataset {name!r}: expected a file of data/field or data/fleet-example "
        "(e.g. 'leon-tensioner', 'fleet-example'; 'vibkit datasets list' lists them)"
    )


def provenance(name: str) -> str:
    """Where the shipped file or folder ``name`` comes from, in one line (its licence: :data:`LICENCE`)."""
    p = path(name)
    top = p.relative_to(folder()).parts[0]
    return FOLDERS[top]


def copy(dest, *, force: bool = False) -> list[Path]:
    """Copy every shipped file into ``dest`` in the repository's layout (``dest/field/...``,
    ``dest/fleet-example/...``); returns the files written.

    A file already there with the same bytes is left as it is (so copying twice, or into a clone's own
    ``data/``, writes nothing); one with other bytes is not replaced unless ``force``.

    Raises
    ------
    FileExistsError
        A file of that name with other bytes is in the way (and not ``force``); nothing was written.
    """
    dest = Path(dest)
    root = folder()
    plan = []
    for rel in _files():
        src, target = root / rel, dest / rel
        if target.exists():
            if target.is_file() and filecmp.cmp(src, target, shallow=False):
                continue
            if not force or not target.is_file():
                raise FileExistsError(
                    f"{target}: already exists with other contents; nothing was copied "
                    "(give another folder, or --force to replace the example files)"
                )
        plan.append((src, target))
    written = []
    for src, target in plan:
        target.parent.mkdir(parents=True, exist_ok=True)
        tmp = target.with_name(f".{target.name}.{os.getpid()}.tmp")
        shutil.copyfile(src, tmp)
        os.replace(tmp, target)  # atomic: a reader never sees half a file
        written.append(target)
    return written
