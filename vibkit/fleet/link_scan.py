"""The link scan of a recording: which links are worn, stored with its measurement (:mod:`vibkit.fleet.links`).

:func:`measure_with_links` reads a recording once and gives its measurement and its link scan: ``fleet scan``'s
workers and ``fleet add`` (:meth:`vibkit.fleet.FleetDB.add`) both call it.  :func:`link_scan_of` runs :func:`vibkit.diagnose.links.find_worn_links` on a recording already read, when the
number of links is known, and never raises: a recording shorter than two loops is ``too few loops``, an error is
``failed`` with its message, a missing number of links ``not run``; the measurement is stored whatever the scan
gives.  A tensioner displacement with the escalator's forward scene is fitted with the worn link's simulated
signature (seconds of CPU, simulated once per scene, speed and sample rate in a process and cached there); any
other channel, or no scene, tests each link's own cycle.
"""

from __future__ import annotations

import math

import numpy as np

from ..diagnose.links import (
    STEP_REFUSAL,
    TooFewLoops,
    find_worn_links,
    is_step_channel,
    is_tensioner_channel,
    links_channel,
    profile_scene_file,
)
from ..diagnose.segment import cut_recording
from ..io import read_recording
from ..model.profile import load_profile
from ..model.schema import SceneError
from .links import LinkScan
from .measurement import analyse_recording

__all__ = ["link_scan_of", "measure_with_links", "profile_scene", "NO_LINK_COUNT", "NO_LINK_COUNT_ADD"]

#: why a scan's recording was not scanned for worn links when the number of links is unknown
NO_LINK_COUNT = (
    "the number of links is not known (the catalogue's n_links column, or an escalator profile with chain.n_links)"
)
#: the same for ``fleet add``: the options that give the number of links
NO_LINK_COUNT_ADD = "the number of links is not known (fleet add --links N, or --escalator FILE with chain.n_links)"


def _one_line(exc):
    return " ".join(str(exc).split()) or type(exc).__name__


def link_scan_of(
    recording,
    *,
    path,
    speed,
    n_links,
    channel=None,
    scene=None,
    marker_s=None,
    no_count=NO_LINK_COUNT,
    nominal_pitch=None,
    profile=None,
) -> LinkScan:
    """The :class:`~vibkit.fleet.links.LinkScan` of one recording (never raises).

    Parameters
    ----------
    recording : xarray.Dataset
        As :func:`vibkit.read_recording` gives.
    path : str
        The file, for messages.
    speed : float
        Chain speed. [m/s]
    n_links : int or None
        Links in the chain (None: not scanned, status ``not run``).
    channel : str, optional
    scene : str, optional
        The escalator's forward scene file: used for a tensioner displacement channel.
    marker_s : float, optional
        When the marked link passed the sensor (it is link 1). [s]
    no_count : str
        The reason stored when ``n_links`` is None (which options would give it).
    nominal_pitch : float, optional
        The unit's nominal pitch [m]: a link pass that gives no chain's pitch is a failed scan.
    profile : vibkit.model.profile.Profile, optional
        The unit's profile: its sensors say which channel is the tensioner's (:mod:`vibkit.diagnose.sensors`).
    """
    if n_links is None:
        # a step's sensor is refused whatever the count: that, not the count, is what the reason says
        try:
            ch = links_channel(recording, channel, profile)
            if ch in recording and is_step_channel(recording, ch, profile):
                return LinkScan.not_run(f"channel {ch}: {STEP_REFUSAL}", marker_s=marker_s)
        except ValueError:
            pass
        return LinkScan.not_run(no_count, marker_s=marker_s)

    keep = {"n_links": int(n_links), "marker_s": marker_s}
    try:
        ch = links_channel(recording, channel, profile)
        if ch in recording and is_step_channel(recording, ch, profile):
            return LinkScan.not_run(f"channel {ch}: {STEP_REFUSAL}", **keep)
        use_scene = (
            scene if scene is not None and ch in recording and is_tensioner_channel(recording, ch, profile) else None
        )
        res = find_worn_links(
            recording,
            speed=speed,
            n_links=n_links,
            channel=ch,
            scene=use_scene,
            marker_s=marker_s,
            file=path,
            nominal_pitch=nominal_pitch,
            profile=profile,
        )
    except TooFewLoops as exc:
        return LinkScan("too few loops", reason=_one_line(exc), **keep)
    except (ValueError, ArithmeticError, OSError) as exc:
        return LinkScan("failed", reason=_one_line(exc), **keep)
    except Exception as exc:  # noqa: BLE001 - the link scan never costs the pitch measurement
        return LinkScan("failed", reason=f"unexpected {type(exc).__name__}: {_one_line(exc)}", **keep)
    return LinkScan.from_result(res)


def measure_with_links(
    path, *, n_links=None, marker_s=None, scene=None, no_count=NO_LINK_COUNT, segment=None, **analysis
):
    """Read a recording once; its :class:`~vibkit.fleet.measurement.Measurement` and its link scan.

    Parameters
    ----------
    path : str
        The recording.
    n_links, marker_s, scene, no_count
        As :func:`link_scan_of` takes them.
    segment : (float, float), optional
        Only this part of the recording [s, in its own time] is analysed and scanned
        (:func:`vibkit.diagnose.segment.cut_recording`: outside the recording, a ValueError naming its span).
    **analysis
        :func:`vibkit.fleet.measurement.analyse_recording`'s keywords (``unit``, ``speed``, ``speed_sigma``,
        ``nominal_pitch``, ``date``, ``channel``, ``read_options`` ...).

    Returns
    -------
    (Measurement, LinkScan)
        The link scan never raises (a failure is its status); the analysis raises as ``analyse_recording`` does.
    """
    channel = analysis.get("channel")
    rec = read_recording(path, **{**(analysis.get("read_options") or {}), "channel": channel})
    rec = cut_recording(rec, segment)
    if marker_s is not None:
        # a marker outside the recording numbers the links from no link: the user's to mend before anything is
        # stored (a stored measurement cannot be scanned again)
        t = np.asarray(rec["time"].values, dtype=float)
        if not (math.isfinite(float(marker_s)) and 0.0 <= float(marker_s) <= float(t[-1])):
            raise ValueError(
                f"{path}: marker_s={float(marker_s):g} must lie within the recording, 0 to {float(t[-1]):.6g} s (the "
                "time the marked link passed the sensor); nothing stored"
            )
    m = analyse_recording(path, recording=rec, n_links=n_links, segment=segment, **analysis)
    scan = link_scan_of(
        rec,
        path=path,
        speed=analysis["speed"],
        n_links=n_links,
        channel=channel,
        scene=scene,
        marker_s=marker_s,
        no_count=no_count,
        nominal_pitch=analysis.get("nominal_pitch"),
        profile=analysis.get("profile"),
    )
    return m, scan


def profile_scene(escalator, notes):
    """The forward scene file of an escalator profile (a path), for a tensioner's worn-link signature; None, with
    a line appended to ``notes``, when the profile's geometry gives no scene (its links are scanned without it)."""
    try:
        return profile_scene_file(load_profile(escalator))
    except (SceneError, OSError, ValueError) as exc:
        notes.append(
            f"{escalator}: no scene for the worn link's signature ({' '.join(str(exc).split())}); "
            "its recordings' links are scanned without it"
        )
        return None
