"""A recording file too large to hold whole: its head in memory, the rest read in blocks when needed.

:func:`vibkit.io.read_recording` hands a :class:`LargeFile` instead of the file's bytes to the text
reader for a plain text file over :data:`STREAM_BYTES`: the reader lays the file out from the head,
streams the rows through pandas' C reader in chunks into arrays of the final size, and hashes the
bytes as it streams them, so its memory is that of the samples, not of the file.  Every other reader
(and the text reader's line-by-line path) asks for :meth:`LargeFile.read_all`.
"""

from __future__ import annotations

import hashlib

from ..runtime.reader_options import either
from .errors import RecordingError
from .limits import _MAX_ENV, _gib

__all__ = ["LargeFile", "STREAM_BYTES", "BLOCK_BYTES"]

#: a text file larger than this is streamed rather than read whole [bytes]
STREAM_BYTES = 32 << 20
#: bytes read at a time while streaming [bytes]
BLOCK_BYTES = 8 << 20


class LargeFile:
    """A regular file on disk, known by its head, streamed block by block.

    Attributes
    ----------
    path : str
        The file as given (for messages).
    size : int
        Its size when opened. [bytes]
    head : bytes
        Its first bytes (at least the first MiB, or the whole file).
    limit : int
        The most bytes a recording may have (``max_bytes``). [bytes]
    """

    def __init__(self, path: str, size: int, head: bytes, limit: int):
        self.path = path
        self.size = size
        self.head = head
        self.limit = limit
        self._sha256 = None

    def __len__(self) -> int:
        return self.size

    def blocks(self, start: int = 0, size: int = BLOCK_BYTES):
        """The file's bytes from ``start`` on, ``size`` at a time; the file must not grow past the limit."""
        read = start
        try:
            with open(self.path, "rb") as f:
                f.seek(start)
                while True:
                    block = f.read(size)
                    if not block:
                        return
                    read += len(block)
                    if read > self.limit:
                        raise RecordingError(self.path, None, _too_large(self.limit))
                    yield block
        except OSError as exc:
            raise RecordingError(self.path, None, f"cannot be read: {exc.strerror or exc}") from None

    def open(self):
        """The file opened for reading bytes."""
        try:
            return open(self.path, "rb")
        except OSError as exc:
            raise RecordingError(self.path, None, f"cannot be read: {exc.strerror or exc}") from None

    def set_sha256(self, hexdigest: str) -> None:
        """The SHA-256 of the bytes, computed by whoever streamed them all."""
        self._sha256 = hexdigest

    def sha256(self) -> str:
        """The SHA-256 of the file's bytes (streamed once, unless already known)."""
        if self._sha256 is None:
            h = hashlib.sha256()
            for block in self.blocks():
                h.update(block)
            self._sha256 = h.hexdigest()
        return self._sha256

    def read_all(self) -> bytes:
        """The whole file's bytes."""
        data = b"".join(self.blocks())
        return data


def _too_large(limit: int) -> str:
    """What :func:`vibkit.io.read_recording` says of a file that grew past the limit while read."""
    return (
        f"holds more than the {_gib(limit)} limit for a recording "
        f"(raise it with {either('max_bytes', f'the environment variable {_MAX_ENV}')})"
    )
