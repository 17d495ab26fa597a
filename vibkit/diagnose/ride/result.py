"""What a ride's assessment gives: :class:`RideQuality` (the ride segment, each axis's :class:`AxisRide`, the
weighted signals for the plots), its dictionary for ``--json``, its figure and its notebook view.  Computed by
:mod:`~vibkit.diagnose.ride.quality`."""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from ...signal.ride import LOWPASS_HZ, PeakToPeak, RideSegment
from ..html import result_table_html
from .figure import plot_ride

__all__ = ["AxisRide", "RideQuality"]


def _three_digits(v) -> str:
    return f"{v:.3g}" if v is not None and math.isfinite(float(v)) else "n/a"


@dataclass(frozen=True)
class AxisRide:
    """Ride-quality values of one axis over the ride segment.

    Attributes
    ----------
    axis : str
        ``"x"``, ``"y"``, ``"z"`` or ``"tangential"``.
    channel : str
        The recording channel or simulation variable it came from.
    weighting : str
        ISO 2631-1 weighting applied (``"Wd"``, ``"Wk"`` ...).
    weighted : PeakToPeak
        Max pk-pk, A95, r.m.s., peak of the weighted acceleration. [m/s^2]
    lowpass : PeakToPeak
        The same of the 0.4-10 Hz band-passed, unweighted acceleration. [m/s^2]
    """

    axis: str
    channel: str
    weighting: str
    weighted: PeakToPeak
    lowpass: PeakToPeak

    def as_dict(self) -> dict:
        return {
            "axis": self.axis,
            "channel": self.channel,
            "weighting": self.weighting,
            "units": "m/s^2",
            "weighted": self.weighted.as_dict(),
            "lowpass_10hz": self.lowpass.as_dict(),
        }


@dataclass(frozen=True)
class RideQuality:
    """Ride quality of one ride.

    Attributes
    ----------
    source : str
        File, scene or description.
    kind : str
        ``"recording"`` or ``"simulation"``.
    fs : float
        Sample rate. [Hz]
    segment : RideSegment
        The ride segment assessed (times from the start of the record). [s]
    axes : tuple of AxisRide
    speed_m_s : float or None
        Mean speed over the segment, from a speed channel or the metadata. [m/s]
    time : numpy.ndarray
        Time of every sample of the record. [s]
    weighted : dict
        Axis -> weighted acceleration over the whole record (for plots). [m/s^2]
    notes : list of str
    """

    source: str
    kind: str
    fs: float
    segment: RideSegment
    axes: tuple
    speed_m_s: float | None = None
    time: np.ndarray = field(default_factory=lambda: np.zeros(0), repr=False)
    weighted: dict = field(default_factory=dict, repr=False)
    notes: list = field(default_factory=list)

    def axis(self, name) -> AxisRide:
        for a in self.axes:
            if a.axis == name:
                return a
        raise KeyError(f"no axis {name!r} (axes: {', '.join(a.axis for a in self.axes)})")

    def table_rows(self, channel_width=None) -> list:
        """One row a axis: axis, channel (cut to ``channel_width`` characters), weighting, weighted max pk-pk, A95,
        r.m.s., 10 Hz max pk-pk and A95, each to three digits (a ride statistic over a few hundred half-cycles is not
        known to four), ``n/a`` where the ride has none: the one printed form of the command's table and the
        report's."""
        return [
            [
                a.axis,
                a.channel[:channel_width] if channel_width else a.channel,
                a.weighting,
                *(
                    _three_digits(v)
                    for v in (a.weighted.max, a.weighted.a95, a.weighted.rms, a.lowpass.max, a.lowpass.a95)
                ),
            ]
            for a in self.axes
        ]

    def plot(self, fig=None):
        """The per-axis table and each axis's weighted acceleration (:func:`~.figure.plot_ride`); a Figure."""
        return plot_ride(self, fig)

    def _repr_html_(self) -> str:
        seg = self.segment
        cells = [
            (a.axis, [a.channel, a.weighting] + [f"{v:.3g}" for v in (a.weighted.max, a.weighted.a95, a.weighted.rms)])
            for a in self.axes
        ]
        title = f"Ride quality of {self.source} over {seg.start_s:.2f}-{seg.end_s:.2f} s ({seg.method}), m/s^2"
        return result_table_html(title, cells, columns=["channel", "weighting", "max pk-pk", "A95", "r.m.s."])

    def as_dict(self) -> dict:
        return {
            "source": self.source,
            "kind": self.kind,
            "sample_rate_hz": self.fs,
            "segment": {
                "start_s": self.segment.start_s,
                "end_s": self.segment.end_s,
                "duration_s": self.segment.duration_s,
                "method": self.segment.method,
                "note": self.segment.note,
            },
            "speed_m_s": self.speed_m_s,
            "axes": [a.as_dict() for a in self.axes],
            "definitions": {
                "pk_pk": "sum of the magnitudes of adjacent half-cycle peaks (one per zero crossing)",
                "a95": "smallest pk-pk value that 95 % of the pk-pk values do not exceed",
                "weighted": "ISO 2631-1 weighting (x, y: Wd; z: Wk)",
                "lowpass_10hz": f"unweighted, 0.4 Hz high-pass and {LOWPASS_HZ:g} Hz low-pass",
                "time_of_max_s": "time of the largest pk-pk value's second peak, from the segment's start",
            },
            "notes": list(self.notes),
        }
