"""Safe output files: nothing a user gave is overwritten by surprise, and nothing half-written is left.

Every file vibkit writes (``simulate -o``, ``report -o``, :func:`vibkit.io.write_result`, ...) goes
through :func:`atomic_output`:

* the target must be a new path or an existing **regular** file; a folder, a device (``/dev/null``),
  a FIFO, a socket or a symbolic link (``/dev/stdout`` is one) is refused, never followed or
  replaced;
* an existing file is replaced only with ``overwrite=True`` (the CLI's ``--force``), never when it
  is one of the command's inputs or read-only (mode without any write bit);
* the data go to a temporary file in the target's folder, named ``.NAME.vibkit-tmp-PID`` so a stale
  one is recognisable, which is flushed to disk (``fsync``) and then renamed onto the target in one
  step (``os.link`` when the target must not exist, so a file that appeared meanwhile is not
  clobbered; ``os.replace`` otherwise); readers never see half a file;
* the temporary file is removed on every error, on Ctrl-C (SIGINT) and on SIGTERM; one left by a
  process that was killed (SIGKILL, power cut) is removed by the next write to the same path once
  its process is gone.

:class:`OutputError` is a ``ValueError`` whose message is one line naming the path.
"""

from __future__ import annotations

import contextlib
import errno
import os
import re
import signal
import stat
import threading

__all__ = [
    "OutputError",
    "Interrupted",
    "check_output_path",
    "atomic_output",
    "write_bytes",
    "clean_stale_temporaries",
    "temporary_name",
    "handle_termination",
]

TMP_MARK = ".vibkit-tmp-"


class OutputError(ValueError):
    """An output path that cannot be written safely (the message names it)."""


class Interrupted(KeyboardInterrupt):
    """SIGTERM (or SIGINT) received; ``signum`` says which (exit status 128 + signum)."""

    def __init__(self, signum: int):
        super().__init__(f"interrupted by signal {signum}")
        self.signum = signum


def _describe(mode: int) -> str:
    for test, what in (
        (stat.S_ISDIR, "a folder"),
        (stat.S_ISCHR, "a character device"),
        (stat.S_ISBLK, "a block device"),
        (stat.S_ISFIFO, "a FIFO (named pipe)"),
        (stat.S_ISSOCK, "a socket"),
        (stat.S_ISLNK, "a symbolic link"),
    ):
        if test(mode):
            return what
    return "not a regular file"


def _same_file(a: str, b) -> bool:
    try:
        return os.path.samefile(a, os.fspath(b))
    except (OSError, TypeError, ValueError):
        return False


def check_output_path(path, *, overwrite: bool = False, inputs=()) -> str:
    """Check that ``path`` can be written safely, before any work is done.

    Parameters
    ----------
    path : str or os.PathLike
        The file to write.
    overwrite : bool
        Allow replacing an existing regular file (the CLI's ``--force``).
    inputs : iterable of paths
        The command's input files: never replaced, even with ``overwrite``.

    Returns
    -------
    str
        ``path`` as a string.

    Raises
    ------
    OutputError
        Empty path, missing or unwritable folder, or an existing target that is not a regular file,
        is a symbolic link, is an input, is read-only, or exists without ``overwrite``.
    """
    if path is None or not isinstance(path, (str, bytes, os.PathLike)):
        raise OutputError(f"output path must be a file path, got {path!r}")
    p = os.fspath(path)
    if isinstance(p, bytes):
        p = os.fsdecode(p)
    if not p.strip():
        raise OutputError("output path is empty; give a file name such as result.nc")
    if "\x00" in p:
        raise OutputError(f"output path {p!r} contains a NUL character")
    if p.endswith(os.sep) or (os.altsep and p.endswith(os.altsep)):
        raise OutputError(f"output {p}: names a folder; give a file name")
    try:
        st = os.lstat(p)
    except FileNotFoundError:
        st = None
    except OSError as exc:
        raise OutputError(f"output {p}: cannot be checked ({exc.strerror or exc})") from None
    if st is not None:
        if stat.S_ISLNK(st.st_mode):
            raise OutputError(
                f"output {p}: is a symbolic link (to {os.readlink(p)!r}); vibkit does not follow "
                "or replace links: give the real path"
            )
        if not stat.S_ISREG(st.st_mode):
            raise OutputError(f"output {p}: is {_describe(st.st_mode)}, not a regular file; refusing to write to it")
        for src in inputs:
            if src is not None and _same_file(p, src):
                raise OutputError(
                    f"output {p}: is an input of this command ({os.fspath(src)}); refusing to overwrite it"
                )
        if not overwrite:
            raise OutputError(
                f"output {p}: already exists; give --force (overwrite=True in Python) to replace it "
                "(or choose a new name)"
            )
        if not st.st_mode & 0o222:
            raise OutputError(
                f"output {p}: is read-only (mode {stat.S_IMODE(st.st_mode):04o}); refusing to "
                "replace it, even with --force"
            )
    folder = os.path.dirname(os.path.abspath(p))
    if not os.path.isdir(folder):
        raise OutputError(f"output {p}: folder {folder} does not exist")
    if not os.access(folder, os.W_OK | os.X_OK):
        raise OutputError(f"output {p}: folder {folder} is not writable")
    return p


def temporary_name(path, pid: int | None = None) -> str:
    """The temporary file used while writing ``path``: ``.NAME.vibkit-tmp-PID`` in the same folder."""
    p = os.path.abspath(os.fspath(path))
    return os.path.join(os.path.dirname(p), f".{os.path.basename(p)}{TMP_MARK}{os.getpid() if pid is None else pid}")


def _pid_alive(pid: int) -> bool:
    if pid <= 0:
        return False
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return False
    except PermissionError:
        return True
    except OSError:
        return True
    return True


def clean_stale_temporaries(path) -> list[str]:
    """Remove temporary files of ``path`` left by processes that no longer run; returns those removed."""
    p = os.path.abspath(os.fspath(path))
    folder, base = os.path.dirname(p), os.path.basename(p)
    pattern = re.compile(r"^\." + re.escape(base) + re.escape(TMP_MARK) + r"(\d+)$")
    removed = []
    try:
        names = os.listdir(folder)
    except OSError:
        return removed
    for name in names:
        m = pattern.match(name)
        if not m or int(m.group(1)) == os.getpid() or _pid_alive(int(m.group(1))):
            continue
        full = os.path.join(folder, name)
        try:
            if stat.S_ISREG(os.lstat(full).st_mode):
                os.unlink(full)
                removed.append(full)
        except OSError:
            pass
    return removed


def _umask() -> int:
    mask = os.umask(0)
    os.umask(mask)
    return mask


def _fsync_dir(folder: str) -> None:
    try:
        fd = os.open(folder, os.O_RDONLY)
    except OSError:
        return
    try:
        os.fsync(fd)
    except OSError:
        pass
    finally:
        os.close(fd)


def _raise_interrupted(signum, frame):
    raise Interrupted(signum)


@contextlib.contextmanager
def handle_termination():
    """Turn SIGTERM into :class:`Interrupted` (a KeyboardInterrupt) while the block runs.

    So ``finally`` blocks and context managers (the temporary files of :func:`atomic_output`) run
    on SIGTERM as they do on Ctrl-C.  Does nothing outside the main thread.
    """
    if threading.current_thread() is not threading.main_thread():
        yield
        return
    old = signal.signal(signal.SIGTERM, _raise_interrupted)
    try:
        yield
    finally:
        signal.signal(signal.SIGTERM, old)


@contextlib.contextmanager
def atomic_output(path, *, overwrite: bool = False, inputs=()):
    """Yield a temporary path to write; on success it becomes ``path`` in one step.

    Parameters
    ----------
    path : str or os.PathLike
        The file to write (checked by :func:`check_output_path`).
    overwrite : bool
        Replace an existing regular file (the CLI's ``--force``).
    inputs : iterable of paths
        Input files that must never be replaced.

    Yields
    ------
    str
        The temporary file (created empty, mode 0600) to write into.

    Raises
    ------
    OutputError
        The path is unsafe (see :func:`check_output_path`), or the target changed while writing.
    OSError
        Writing failed (disk full ...); the temporary file is removed first.
    """
    p = check_output_path(path, overwrite=overwrite, inputs=inputs)
    clean_stale_temporaries(p)
    tmp = temporary_name(p)
    if os.path.lexists(tmp):  # ours from an earlier write in this process that could not be removed
        os.unlink(tmp)
    fd = os.open(tmp, os.O_WRONLY | os.O_CREAT | os.O_EXCL | getattr(os, "O_NOFOLLOW", 0), 0o600)
    os.close(fd)
    done = False
    try:
        with handle_termination():
            yield tmp
            _commit(tmp, p, overwrite=overwrite, inputs=inputs)
            done = True
    finally:
        if not done:
            with contextlib.suppress(OSError):
                os.unlink(tmp)


def _commit(tmp: str, path: str, *, overwrite: bool, inputs) -> None:
    fd = os.open(tmp, os.O_RDONLY)
    try:
        os.fsync(fd)
    finally:
        os.close(fd)
    os.chmod(tmp, 0o666 & ~_umask())
    check_output_path(path, overwrite=overwrite, inputs=inputs)  # the target may have changed meanwhile
    if not overwrite:
        try:
            os.link(tmp, path)  # fails if the path appeared meanwhile: never clobbers
        except FileExistsError:
            raise OutputError(f"output {path}: appeared while writing; not replaced (give --force)") from None
        except OSError as exc:
            if exc.errno not in (errno.EPERM, errno.ENOTSUP, errno.EOPNOTSUPP, errno.EXDEV, errno.EMLINK):
                raise
            os.replace(tmp, path)  # a file system without hard links
        else:
            os.unlink(tmp)
    else:
        os.replace(tmp, path)
    _fsync_dir(os.path.dirname(os.path.abspath(path)))


def write_bytes(data, path, *, overwrite: bool = False, inputs=(), chunk: int = 1 << 22) -> str:
    """Write ``data`` (bytes-like) to ``path`` atomically (see :func:`atomic_output`); returns the path."""
    view = memoryview(data).cast("B")
    try:
        with atomic_output(path, overwrite=overwrite, inputs=inputs) as tmp:
            with open(tmp, "wb") as f:
                for i in range(0, len(view), chunk):
                    f.write(view[i : i + chunk])
                f.flush()
    except OSError as exc:
        if exc.errno is not None and not exc.filename:  # name the file the user asked for (disk full ...)
            raise OSError(exc.errno, exc.strerror or str(exc), os.fspath(path)) from None
        raise
    return os.fspath(path)
