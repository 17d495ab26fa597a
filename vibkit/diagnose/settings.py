"""A run's chain settings and the defaults every command that analyses a recording shares, in one place.

:func:`chain_numbers` resolves the sprocket's teeth and the chain's links per step once, in one order of
precedence: what the user gives, else the escalator profile's, else the scene's (the escalator simulated beside
the recording), else what the recording states (a vibkit simulation's ``sprocket_teeth`` and ``links_per_step``),
else :data:`DEFAULT_TEETH` and :data:`DEFAULT_LINKS_PER_STEP` (the study's escalator).  ``vibkit pitch``,
``spectrum``, ``report`` and ``fleet add`` take them from here, so the same recording and profile are analysed
with the same numbers by each.  The elongation limits' default is :data:`DEFAULT_LIMITS_PERCENT`.
"""

from __future__ import annotations

from .decision import DEFAULT_LIMITS_PERCENT

__all__ = ["DEFAULT_LIMITS_PERCENT", "DEFAULT_LINKS_PER_STEP", "DEFAULT_TEETH", "chain_numbers", "recording_chain"]

#: the study's sprocket: 28 teeth (the shaft hypothesis of a pitch estimate reads them)
DEFAULT_TEETH = 28
#: the study's chain: 3 links per step
DEFAULT_LINKS_PER_STEP = 3


def recording_chain(recording) -> tuple[int | None, int | None]:
    """``(sprocket teeth, links per step)`` a recording states (a vibkit simulation's ``sprocket_teeth`` and
    ``links_per_step``), None for each it does not state as a whole number of at least 1."""
    out = []
    for key in ("sprocket_teeth", "links_per_step"):
        try:
            v = int(getattr(recording, "attrs", {}).get(key))
        except (TypeError, ValueError):
            v = None
        out.append(v if v is not None and v >= 1 else None)
    return out[0], out[1]


def chain_numbers(*, teeth=None, links_per_step=None, profile=None, scene=None, recording=None) -> tuple[int, int]:
    """``(teeth, links per step)`` of a run: each as given, else the profile's, else the scene's, else the
    recording's (:func:`recording_chain`), else the defaults (:data:`DEFAULT_TEETH`, :data:`DEFAULT_LINKS_PER_STEP`)."""
    stated = recording_chain(recording) if recording is not None else (None, None)

    def first(given, of_profile, of_scene, of_file, default):
        for v in (given, of_profile, of_scene, of_file):
            if v is not None:
                return int(v)
        return default

    return (
        first(
            teeth,
            getattr(profile, "teeth", None),
            scene.sprocket.teeth if scene is not None else None,
            stated[0],
            DEFAULT_TEETH,
        ),
        first(
            links_per_step,
            getattr(profile, "links_per_step", None),
            scene.chain.links_per_step if scene is not None else None,
            stated[1],
            DEFAULT_LINKS_PER_STEP,
        ),
    )
