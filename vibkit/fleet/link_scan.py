"""The link scan of a scan's recording: which links are worn, stored with its measurement (:mod:`vibkit.fleet.links`).

:func:`link_scan_of` runs :func:`vibkit.diagnose.links.find_worn_links` on a recording already read, when the
number of links is known, and never raises: a recording shorter than two loops is ``too few loops``, an error is
``failed`` with its message, a missing number of links ``not run``; the measurement is stored whatever the scan
gives.  A tensioner displacement with the escalator's forward scene is fitted with the worn link's simulated
signature (seconds of CPU, simulated once per scene, speed and sample rate in a process and cached there); any
other channel, or no scene, tests each link's own cycle.
"""

from __future__ import annotations

from .links import LinkScan

__all__ = ["link_scan_of", "NO_LINK_COUNT"]

#: why a scan's recording was not scanned for worn links when the number of links is unknown
NO_LINK_COUNT = (
    "the number of links is not known (the catalogue's n_links column, or an escalator profile with chain.n_links)"
)


def _one_line(exc):
    return " ".join(str(exc).split()) or type(exc).__name__


def link_scan_of(recording, *, path, speed, n_links, channel=None, scene=None, marker_s=None) -> LinkScan:
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
    """
    if n_links is None:
        return LinkScan.not_run(NO_LINK_COUNT, marker_s=marker_s)
    from ..diagnose.links import (
        STEP_REFUSAL,
        TooFewLoops,
        find_worn_links,
        is_step_channel,
        is_tensioner_channel,
        links_channel,
    )

    keep = {"n_links": int(n_links), "marker_s": marker_s}
    try:
        ch = links_channel(recording, channel)
        if ch in recording and is_step_channel(recording, ch):
            return LinkScan.not_run(f"channel {ch}: {STEP_REFUSAL}", **keep)
        use_scene = scene if scene is not None and ch in recording and is_tensioner_channel(recording, ch) else None
        res = find_worn_links(
            recording, speed=speed, n_links=n_links, channel=ch, scene=use_scene, marker_s=marker_s, file=path
        )
    except TooFewLoops as exc:
        return LinkScan("too few loops", reason=_one_line(exc), **keep)
    except (ValueError, ArithmeticError, OSError) as exc:
        return LinkScan("failed", reason=_one_line(exc), **keep)
    except Exception as exc:  # noqa: BLE001 - the link scan never costs the pitch measurement
        return LinkScan("failed", reason=f"unexpected {type(exc).__name__}: {_one_line(exc)}", **keep)
    return LinkScan.from_result(res)
