"""The scenes shipped with vibkit, by name: ``vibkit.scenes.names()``, ``vibkit.scenes.path("las-palmas")``.

The repository keeps them in ``sim/*.toml`` (the one copy that is edited); building the wheel copies
them into this package (``setup.py``), so an installed vibkit has them without a clone.  In a
clone (an editable install, ``PYTHONPATH``) they are read from ``sim/`` directly.

A scene's name is its file name without ``.toml``.  :func:`vibkit.load_scene`, :func:`vibkit.simulate`
and ``vibkit simulate`` accept a shipped scene's name wherever no file of that name exists:

>>> import vibkit.scenes
>>> "las-palmas" in vibkit.scenes.names()
True
"""

from __future__ import annotations

from pathlib import Path

__all__ = ["names", "path", "find"]

_HERE = Path(__file__).resolve().parent
_CLONE = _HERE.parents[1] / "sim"  # the repository's sim/, when running from a clone


def _folder() -> Path:
    """Where the scene files are: this package once installed from the wheel, else the clone's sim/."""
    if any(_HERE.glob("*.toml")):
        return _HERE
    return _CLONE


def names() -> tuple[str, ...]:
    """The shipped scenes' names, sorted (``"las-palmas"``, ``"leon"``, ``"thesis-forward"`` ...)."""
    return tuple(sorted(p.stem for p in _folder().glob("*.toml")))


def path(name: str) -> Path:
    """The file of the shipped scene ``name`` (with or without ``.toml``).

    Raises
    ------
    ValueError
        No shipped scene has that name; the message lists them.
    """
    stem = str(name).removesuffix(".toml")
    p = _folder() / f"{stem}.toml"
    if stem not in names():
        raise ValueError(f"no shipped scene {name!r}; the shipped scenes are: {', '.join(names())}")
    return p


def find(scene) -> Path | None:
    """The shipped scene that ``scene`` names where no such file exists, else None.

    A bare name (``"las-palmas"``, ``"las-palmas.toml"``) or the repository's path of a shipped
    scene (``"sim/las-palmas.toml"``, as the documentation writes it) names one; anything else,
    and any path that exists, does not.
    """
    p = Path(scene)
    if p.exists():
        return None
    parent = p.parent.as_posix()
    if parent not in (".", "sim") or p.suffix not in ("", ".toml"):
        return None
    stem = p.name.removesuffix(".toml")
    return _folder() / f"{stem}.toml" if stem in names() else None
