"""The one error of the sweep layer."""

from __future__ import annotations

__all__ = ["SweepError"]


class SweepError(ValueError):
    """A sweep that cannot be planned or stored; the message names the key, value or path."""
