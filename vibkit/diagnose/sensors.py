"""Which sensor a channel is: what a diagnosis may assume about where a channel's signal comes from.

:func:`is_tensioner_channel`: a displacement (a length unit) is the tensioner's sensor, fixed beside the chain,
the one the worn link's signature is known for; any other channel rides a step or the frame.
"""

from __future__ import annotations

__all__ = ["is_tensioner_channel"]


def is_tensioner_channel(recording, channel):
    """Whether ``channel`` is a displacement (a length unit): the sensor the worn link's signature is known for."""
    return str(recording[channel].attrs.get("units", "")) in ("m", "mm", "um")
