"""Contract assertions shared by the reader tests."""

from __future__ import annotations

import pytest

from vibkit.io import RecordingError


def recording_error(path, fn, *words, line=None):
    """``fn()`` raises a :class:`RecordingError` of one line that starts with ``path`` (and ``, line N``
    where ``line`` is given) and holds every word; returns the error."""
    with pytest.raises(RecordingError) as info:
        fn()
    msg = str(info.value)
    assert "\n" not in msg and msg.startswith(f"{path}, line {line}: " if line else f"{path}: "), msg
    for w in words:
        assert w in msg, msg
    return info.value
