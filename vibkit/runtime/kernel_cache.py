"""Where numba keeps vibkit's compiled kernels, so that a read-only install still runs.

vibkit's kernels are compiled with ``cache=True``.  Numba puts the cache in the package's own
``__pycache__`` when it can write there (a checkout, an editable or a user install), and otherwise
in a user-wide folder under ``$HOME``; when neither can be written (a package installed by root,
run by a service account, cron job or container user without a home) numba raises
``RuntimeError: cannot cache function ...: no locator available`` at import, and every command
fails.  :func:`configure` runs when ``vibkit`` is imported (before any kernel module) and, only
when the package folder is not writable, points numba's ``CACHE_DIR`` at the first of

1. ``$NUMBA_CACHE_DIR`` if the user set it (left alone);
2. ``$XDG_CACHE_HOME/vibkit/numba``, else ``~/.cache/vibkit/numba``;
3. ``<tempdir>/vibkit-numba-<uid>`` (created 0700 and used only if it is ours and not a link);

that can be created and written.  If none can, kernels are compiled in memory at every run
(no cache) and one line on stderr says so.  This module never imports numba unless that last
case needs it, so ``vibkit --version`` stays cheap.
"""

from __future__ import annotations

import hashlib
import os
import pickle
import stat
import sys
import tempfile

__all__ = ["configure", "cache_dir", "remove_orphans", "kernel_cached", "COMPILING_NOTE"]

#: what a progress bar says while kernels that are not cached yet compile
COMPILING_NOTE = "compiling the kernels first (after an install or an update: about a minute, then cached)"

_STATE = {"dir": None, "configured": False}


def _writable_dir(path: str) -> bool:
    """True when ``path`` is (or can be made) a folder we can create files in."""
    try:
        os.makedirs(path, exist_ok=True)
        with tempfile.TemporaryFile(dir=path):
            pass
    except OSError:
        return False
    return True


#: the subpackages whose modules hold ``cache=True`` kernels
KERNEL_PACKAGES = ("model", "analyses", "signal")


def _package_writable(pkg_dir: str) -> bool:
    for d in (pkg_dir, *(os.path.join(pkg_dir, sub) for sub in KERNEL_PACKAGES)):
        cache = os.path.join(d, "__pycache__")
        target = cache if os.path.isdir(cache) else d
        if not os.access(target, os.W_OK | os.X_OK):
            return False
    return True


def _private_temp_dir() -> str | None:
    uid = os.getuid() if hasattr(os, "getuid") else 0
    path = os.path.join(tempfile.gettempdir(), f"vibkit-numba-{uid}")
    try:
        os.mkdir(path, 0o700)
        _STATE["created"] = True
    except FileExistsError:
        pass
    except OSError:
        return None
    try:
        st = os.lstat(path)
    except OSError:
        return None
    # another user could have made it first (and planted pickles numba would load): refuse that
    if not stat.S_ISDIR(st.st_mode) or (hasattr(os, "getuid") and st.st_uid != uid) or st.st_mode & 0o022:
        return None
    return path if _writable_dir(path) else None


def _candidates():
    xdg = os.environ.get("XDG_CACHE_HOME", "")
    if xdg and os.path.isabs(xdg):
        yield os.path.join(xdg, "vibkit", "numba")
    home = os.path.expanduser("~")
    if home and home != "~" and os.path.isabs(home):
        yield os.path.join(home, ".cache", "vibkit", "numba")


def _disable_numba_cache(reason: str) -> None:
    """Last resort: compile in memory (``cache=True`` becomes a no-op) and say so once."""
    from numba.core import dispatcher
    from numba.core.caching import NullCache

    def enable_caching(self):
        self._cache = NullCache()

    dispatcher.Dispatcher.enable_caching = enable_caching
    print(
        f"vibkit: note: {reason}; compiled kernels are not cached (each run compiles them again, "
        "about a minute); set NUMBA_CACHE_DIR or XDG_CACHE_HOME to a writable folder",
        file=sys.stderr,
    )


def _set_numba_cache_dir(path: str) -> None:
    os.environ["NUMBA_CACHE_DIR"] = path
    numba_config = sys.modules.get("numba.core.config")
    if numba_config is not None:
        numba_config.CACHE_DIR = path


def configure(pkg_dir: str | None = None) -> str | None:
    """Choose where numba caches vibkit's kernels (see the module docstring); idempotent.

    Parameters
    ----------
    pkg_dir : str, optional
        The vibkit package folder (default: this module's folder).

    Returns
    -------
    str or None
        The cache folder chosen when it is not numba's default, else None.
    """
    if _STATE["configured"]:
        return _STATE["dir"]
    _STATE["configured"] = True
    pkg_dir = pkg_dir or os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
    if os.environ.get("NUMBA_CACHE_DIR"):
        return None
    if _package_writable(pkg_dir):
        remove_orphans(pkg_dir)
        return None
    for path in _candidates():
        if _writable_dir(path):
            _STATE["dir"] = path
            _set_numba_cache_dir(path)
            return path
    path = _private_temp_dir()
    if path is not None:
        _STATE["dir"] = path
        _set_numba_cache_dir(path)
        if _STATE.get("created"):  # said once, when the folder is made
            print(
                f"vibkit: note: the package folder and the home cache are not writable; compiled kernels "
                f"are cached in {path}",
                file=sys.stderr,
            )
        return path
    _disable_numba_cache(f"no writable folder for the kernel cache (package {pkg_dir}, home, {tempfile.gettempdir()})")
    return None


def remove_orphans(pkg_dir: str) -> list[str]:
    """Delete numba cache files in the package's ``__pycache__`` folders whose module is gone.

    Numba names a kernel's cache ``<module>.<function>-<line>.py<ver>.nbi`` (and ``.nbc``) in the
    ``__pycache__`` beside the module's source. When a module moves (``vibkit/chain.py`` became
    ``vibkit/model/chain.py``) an upgrade in place leaves the old files behind: never loaded again,
    but dead weight that would mislead whoever inspects the cache. Returns the paths removed.
    """
    # runs at every `import vibkit`: list the package's and its subpackages' __pycache__ folders only
    # (kernels live one level down at most), not the whole tree
    try:
        subs = [e.path for e in os.scandir(pkg_dir) if e.is_dir() and e.name != "__pycache__"]
    except OSError:
        return []
    removed = []
    for src_dir in (pkg_dir, *subs):
        root = os.path.join(src_dir, "__pycache__")
        try:
            files = [n for n in os.listdir(root) if n.endswith((".nbi", ".nbc"))]
            modules = {n[:-3] for n in os.listdir(src_dir) if n.endswith(".py")} if files else set()
        except OSError:
            continue
        for name in files:
            if name.split(".", 1)[0] in modules:
                continue
            try:
                os.remove(os.path.join(root, name))
            except OSError:
                continue
            removed.append(os.path.join(root, name))
    return removed


def cache_dir() -> str | None:
    """The folder chosen by :func:`configure` (None: numba's default, next to the sources)."""
    return _STATE["dir"]


def _index_current(index_path: str, source: str) -> bool:
    """Whether numba's index file was written for the source as it is now: numba keeps an index whose stamp differs
    from the source's as no cache at all, and compiles again.  The stamp is the SHA-256 digest of the source's bytes
    (numba 0.68 and later, numba pull request 10659), or its modification time and size (earlier numba)."""
    try:
        with open(index_path, "rb") as f:
            pickle.load(f)  # numba's version
            stamp, _overloads = pickle.loads(f.read())
        if isinstance(stamp, bytes):
            with open(source, "rb") as f:
                return stamp == hashlib.sha256(f.read()).digest()
        st = os.stat(source)
        return tuple(stamp) == (st.st_mtime, st.st_size)
    except Exception:  # an index numba itself could not read is no cache either
        return False


def kernel_cached(module_file: str, qualname: str) -> bool:
    """Whether numba's cache holds a current index for the kernel ``qualname`` of the module at ``module_file``
    (under the cache folder :func:`configure` chose or ``NUMBA_CACHE_DIR``, else in the module's ``__pycache__``;
    an index written for an earlier state of the source does not count); False before the first run after an
    install or an edit, when the kernels compile."""
    import glob

    stem = os.path.splitext(os.path.basename(module_file))[0]
    pattern = f"{stem}.{qualname}-*.nbi"
    root = _STATE["dir"] or os.environ.get("NUMBA_CACHE_DIR")
    if root:
        folders = [d for d, _sub, files in os.walk(root) if any(f.endswith(".nbi") for f in files)]
    else:
        folders = [os.path.join(os.path.dirname(os.path.abspath(module_file)), "__pycache__")]
    return any(
        _index_current(index, module_file)
        for f in folders
        for index in glob.glob(os.path.join(glob.escape(f), pattern))
    )
