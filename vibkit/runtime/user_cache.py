"""Files vibkit derives and keeps between runs, in the user's own cache folder, checked before they are read.

The folder is ``$XDG_CACHE_HOME/vibkit`` (an absolute path), else ``~/.cache/vibkit``: the same place the
compiled kernels go when the package folder cannot be written (:mod:`vibkit.runtime.kernel_cache`).  Each kind
of file has its own subfolder (``scenes``, ``signatures``), created 0700.  Nothing is ever read from or written
to a shared temporary folder under a name another user could guess.

A folder is used only when it is a real folder (not a link), owned by the user and writable by no one else (the
subfolder: not even readable); a file only when it is a regular file (opened without following links, never a
FIFO), owned by the user, writable by no one else and not larger than its kind allows.  What a file holds is
checked too: :func:`store_blob` writes the key it was derived from and the SHA-256 of its payload in a header
line, :func:`load_blob` gives the payload back only when both match.  A file that fails any check is ignored
(and replaced by the next store); the cache is an optimisation, so any failure to read or write it only costs
the time to derive the file again.  When no folder passes (a read-only home, no home), :func:`private_folder`
gives None and callers fall back to :func:`private_temp_folder`: a fresh folder of unpredictable name (0700),
removed when the process ends.
"""

from __future__ import annotations

import atexit
import hashlib
import os
import shutil
import stat
import tempfile
from pathlib import Path

__all__ = [
    "cache_root",
    "code_fingerprint",
    "private_folder",
    "private_temp_folder",
    "read_checked",
    "write_atomic",
    "store_blob",
    "load_blob",
]

#: the first line of a file :func:`store_blob` writes (the format's name and version)
MAGIC = b"vibkit-cache 1\n"
#: the largest cached file read [bytes] (a signature of a 1,000-link chain at 16 samples a cycle is 128 kB)
MAX_BYTES = 64 * 1024 * 1024

_TEMP = {}


def cache_root() -> Path | None:
    """``$XDG_CACHE_HOME/vibkit`` when that variable is an absolute path, else ``~/.cache/vibkit``; None without a
    home."""
    xdg = os.environ.get("XDG_CACHE_HOME", "")
    if xdg and os.path.isabs(xdg):
        return Path(xdg) / "vibkit"
    home = os.path.expanduser("~")
    if home and home != "~" and os.path.isabs(home):
        return Path(home) / ".cache" / "vibkit"
    return None


def _uid():
    return os.getuid() if hasattr(os, "getuid") else None


def _ours(st, *, private) -> bool:
    """Whether an ``lstat`` result is owned by this user and writable by no one else (``private``: no access at all
    for the group and others)."""
    uid = _uid()
    if uid is not None and st.st_uid != uid:
        return False
    return not st.st_mode & (0o077 if private else 0o022)


def _checked_dir(path: Path, *, private: bool) -> bool:
    try:
        os.mkdir(path, 0o700)
    except FileExistsError:
        pass
    except OSError:
        return False
    try:
        st = os.lstat(path)
    except OSError:
        return False
    return stat.S_ISDIR(st.st_mode) and _ours(st, private=private)


def private_folder(name: str) -> Path | None:
    """The cache's subfolder ``name`` (created 0700), or None when it (or the cache folder) cannot be created or
    is not the user's own: a link, another user's, or writable by others (the subfolder: accessible to others)."""
    root = cache_root()
    if root is None:
        return None
    try:
        os.makedirs(root.parent, mode=0o700, exist_ok=True)
    except OSError:
        return None
    if not _checked_dir(root, private=False):
        return None
    sub = root / name
    return sub if _checked_dir(sub, private=True) else None


def private_temp_folder(name: str) -> Path:
    """A folder of this process only (``tempfile.mkdtemp``: unpredictable name, 0700), one per ``name``, removed
    when the process ends: where derived files go when the cache folder cannot be used."""
    if name not in _TEMP:
        path = Path(tempfile.mkdtemp(prefix=f"vibkit-{name}-"))
        _TEMP[name] = path
        atexit.register(shutil.rmtree, path, ignore_errors=True)
    return _TEMP[name]


def read_checked(folder: Path, name: str, max_bytes: int = MAX_BYTES) -> bytes | None:
    """The bytes of ``folder / name`` when it is a regular file (not followed through a link, not a FIFO), the
    user's own, writable by no one else and at most ``max_bytes``; else None."""
    flags = os.O_RDONLY | getattr(os, "O_NOFOLLOW", 0) | getattr(os, "O_NONBLOCK", 0)
    try:
        fd = os.open(folder / name, flags)
    except OSError:
        return None
    try:
        st = os.fstat(fd)
        if not stat.S_ISREG(st.st_mode) or not _ours(st, private=False) or st.st_size > max_bytes:
            return None
        with os.fdopen(fd, "rb", closefd=False) as f:
            data = f.read(max_bytes + 1)
        return data if len(data) <= max_bytes else None
    except OSError:
        return None
    finally:
        os.close(fd)


def write_atomic(folder: Path, name: str, data: bytes) -> bool:
    """Write ``data`` to ``folder / name`` through a new private file renamed over it (a reader sees the old file or
    the whole new one, never a part); False when it cannot be written (the cache then only misses)."""
    try:
        fd, tmp = tempfile.mkstemp(dir=folder, prefix=".tmp-")
    except OSError:
        return False
    try:
        with os.fdopen(fd, "wb") as f:
            f.write(data)
        os.replace(tmp, folder / name)
    except OSError:
        try:
            os.unlink(tmp)
        except OSError:
            pass
        return False
    return True


def _name(key: str, suffix: str) -> str:
    return hashlib.sha256(key.encode()).hexdigest()[:40] + suffix


def store_blob(folder: Path, key: str, payload: bytes, suffix: str = ".bin") -> bool:
    """Keep ``payload`` under ``key`` (any text: what the payload was derived from): a header line with the key's
    and the payload's SHA-256, then the payload."""
    head = f"{hashlib.sha256(key.encode()).hexdigest()} {hashlib.sha256(payload).hexdigest()}\n".encode()
    return write_atomic(folder, _name(key, suffix), MAGIC + head + payload)


def load_blob(folder: Path, key: str, suffix: str = ".bin") -> bytes | None:
    """The payload :func:`store_blob` kept under ``key``, or None when there is none or the file fails a check (not
    the user's own regular file, another key, a payload whose hash differs: truncated, edited, planted)."""
    data = read_checked(folder, _name(key, suffix))
    if data is None or not data.startswith(MAGIC):
        return None
    head, sep, payload = data[len(MAGIC) :].partition(b"\n")
    if not sep:
        return None
    want = f"{hashlib.sha256(key.encode()).hexdigest()} {hashlib.sha256(payload).hexdigest()}".encode()
    return payload if head == want else None


def code_fingerprint(subpackages, *files) -> str:
    """SHA-256 of vibkit's sources that a kept result depends on: every module of ``subpackages`` (names under
    ``vibkit/``, their sub-packages included) and ``files`` (paths), each with its path under ``vibkit/``.  A key that
    carries it serves a kept result only to the code that made it."""
    root = Path(__file__).resolve().parents[1]
    paths = [f for sub in subpackages for f in sorted((root / sub).rglob("*.py"))]
    paths += [Path(f).resolve() for f in files]
    h = hashlib.sha256()
    for f in paths:
        h.update(str(f.relative_to(root)).encode() + b"\0" + f.read_bytes())
    return h.hexdigest()
