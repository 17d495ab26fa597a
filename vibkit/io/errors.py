"""The one exception the readers raise for a file they cannot read honestly."""

from __future__ import annotations

import os

__all__ = ["RecordingError"]


class RecordingError(ValueError):
    """A recording file that cannot be read without guessing.

    ``str(err)`` is one line naming the file, the line (when one applies) and
    what was expected, e.g.
    ``"data/x.csv, line 17: expected a number in column 'acc_z', found 'abc'"``.

    Parameters
    ----------
    path : str or os.PathLike
        The file, as the caller named it.
    line : int or None
        1-based line number in the file, or None when no line applies.
    message : str
        What was expected and what was found.

    Attributes
    ----------
    path : str
    line : int or None
    message : str
    """

    def __init__(self, path: str | os.PathLike, line: int | None, message: str):
        self.path = os.fspath(path)
        self.line = None if line is None else int(line)
        # one line, always: a message from a library may carry newlines
        self.message = " ".join(str(message).split())
        super().__init__(self.__str__())

    def __str__(self) -> str:
        where = self.path if self.line is None else f"{self.path}, line {self.line}"
        return f"{where}: {self.message}"

    def __reduce__(self):
        return (type(self), (self.path, self.line, self.message))
