"""How large a recording may be: the one size limit every reader and container unpacking checks."""

from __future__ import annotations

import math
import os
import re

__all__ = ["DEFAULT_MAX_RECORDING_BYTES", "max_recording_bytes"]

#: largest recording read unless ``max_bytes=`` or ``VIBKIT_MAX_RECORDING_BYTES`` says otherwise [bytes] (4 GiB)
DEFAULT_MAX_RECORDING_BYTES = 4 * 1024**3
_MAX_ENV = "VIBKIT_MAX_RECORDING_BYTES"


def _gib(n: int) -> str:
    return f"{n / 1024**3:.3g} GiB" if n >= 1024**3 else f"{n / 1024**2:.3g} MiB" if n >= 1024**2 else f"{n} bytes"


def max_recording_bytes(max_bytes=None) -> int:
    """The size limit for a recording file. [bytes]

    ``max_bytes`` if given, else the environment variable
    ``VIBKIT_MAX_RECORDING_BYTES`` (an integer number of bytes), else
    :data:`DEFAULT_MAX_RECORDING_BYTES` (4 GiB).

    Raises
    ------
    ValueError
        ``max_bytes`` or the environment variable is not a positive integer (named).
    """
    if max_bytes is None:
        env = os.environ.get(_MAX_ENV, "").strip()
        if not env:
            return DEFAULT_MAX_RECORDING_BYTES
        try:
            value = int(float(env)) if re.fullmatch(r"[0-9]+(\.0*)?(e[+]?[0-9]+)?", env, re.I) else -1
        except (ValueError, OverflowError):
            value = -1
        if value <= 0:
            raise ValueError(f"environment variable {_MAX_ENV}={env!r}: expected a positive number of bytes")
        return value
    if (
        isinstance(max_bytes, bool)
        or not isinstance(max_bytes, (int, float))
        or not max_bytes > 0
        or not math.isfinite(max_bytes)
    ):
        raise ValueError(f"max_bytes must be a positive number of bytes, got {max_bytes!r}")
    return int(max_bytes)
