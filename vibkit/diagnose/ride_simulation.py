"""A scene simulated for its ride: now :mod:`vibkit.diagnose.ride.simulation`, importable from here as it was
first published."""

from .ride.simulation import simulate_ride, with_ride_outputs

__all__ = ["simulate_ride", "with_ride_outputs"]
