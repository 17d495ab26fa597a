"""The report's ride-quality pages: ISO 2631-1 weighted step vibration of the recording (when it has x, y, z
acceleration channels) and of the simulation (when it has the step's motion); :func:`plot_ride` draws one."""

from __future__ import annotations

import os
import textwrap

from ..ride.figure import plot_ride
from .common import _PAGE, _page_title

__all__ = ["plot_ride", "ride_quality_pages", "ride_pages_absent"]


def ride_quality_pages(doc, ctx) -> list:
    """Ride-quality pages of the recording (when it has x, y, z acceleration channels) and of the
    simulation (when it has the step's motion); none when neither can be assessed.

    Returns
    -------
    list of RideQuality
        One per page drawn.
    """
    import matplotlib.pyplot as plt

    done = []
    for what, rq in ctx.ride:
        fig = plt.figure(figsize=_PAGE)
        scene_file = os.path.basename(str(ctx.scene.source)) if ctx.scene is not None else ""
        if " (scene built from the profile)" in scene_file:  # the profile's scene, in memory
            scene_file = f"SCENE` of `vibkit scene {scene_file.split(' (')[0]} -o SCENE"
        same = (
            (
                f"; the same figure as `vibkit ride {scene_file}"
                + (f" --duration {ctx.duration:g}`" if ctx.duration else "`")
            )
            if what == "simulation"
            else ""
        )
        _page_title(
            fig,
            f"Ride quality ({what})",
            f"{os.path.basename(rq.source)}: step vibration, ISO 2631-1 "
            f"weighted (x, y: Wd; z: Wk) and 0.4-10 Hz unweighted{same}",
        )
        notes = rq.notes + ([rq.segment.note] if rq.segment.note else [])
        text = "\n".join(textwrap.fill("- " + m, 115) for m in notes[:4])
        # the plots end above the notes (6.5 pt lines, about 0.0095 of the page each) and the time axis' label
        plot_ride(rq, fig, bottom=max(0.07, 0.025 + 0.0095 * (text.count("\n") + 1)))
        fig.text(
            0.06,
            0.015,
            text,
            fontsize=6.5,
            va="bottom",
            color="0.3",
        )
        doc.emit(fig, f"ride quality ({what})")
        done.append(rq)
    return done


def ride_pages_absent(ctx) -> str:
    """Why a ride-quality page (of the recording, of the simulation) is not in the report ("" when both are)."""
    drawn = {kind for kind, _ in ctx.ride}
    return "; ".join(w for w in ctx.ride_absent if w.split(":")[0] not in drawn)
