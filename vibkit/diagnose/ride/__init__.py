"""Ride quality of a step-riding accelerometer, as escalator ride-quality meters report it.

* :mod:`~vibkit.diagnose.ride.result`: the result, :class:`RideQuality` (each axis an :class:`AxisRide`), its
  dictionary, figure and notebook view;
* :mod:`~vibkit.diagnose.ride.quality`: the result from arrays
  (:func:`ride_quality`), a recording (:func:`ride_quality_from_recording`) or a simulation Dataset
  (:func:`ride_quality_from_simulation`);
* :mod:`~vibkit.diagnose.ride.simulation`: a scene simulated for its ride (:func:`simulate_ride`), the step
  roller's motion added to its outputs (:func:`with_ride_outputs`).

Every name is importable from here, as it was when the package was one module.
"""

from .quality import (  # noqa: F401 (the names of the module this package was)
    _AXIS_RE,
    DEFAULT_WEIGHTINGS,
    MIN_PK_PK_VALUES,
    SETTLE_S,
    START_UP_SHARE,
    G,
    _naming,
    _start_up,
    parse_channels,
    parse_segment,
    parse_weightings,
    ride_quality,
    ride_quality_from_recording,
    ride_quality_from_simulation,
)
from .result import AxisRide, RideQuality
from .simulation import simulate_ride, with_ride_outputs

__all__ = [
    "AxisRide",
    "RideQuality",
    "DEFAULT_WEIGHTINGS",
    "ride_quality",
    "ride_quality_from_recording",
    "parse_weightings",
    "ride_quality_from_simulation",
    "parse_channels",
    "parse_segment",
    "simulate_ride",
    "with_ride_outputs",
]
