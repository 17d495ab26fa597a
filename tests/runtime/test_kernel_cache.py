"""The kernel cache after the package moved: orphaned numba cache files are removed, live ones kept."""

import os

from vibkit.runtime.kernel_cache import KERNEL_PACKAGES, _package_writable, remove_orphans


def _touch(path):
    path.parent.mkdir(parents=True, exist_ok=True)
    path.write_bytes(b"")
    return path


def test_orphans_of_moved_modules_are_removed_and_live_caches_kept(tmp_path):
    pkg = tmp_path / "vibkit"
    _touch(pkg / "__init__.py")
    _touch(pkg / "model" / "chain.py")
    # an upgrade in place: the old flat layout's caches are still there
    old = [_touch(pkg / "__pycache__" / f"chain.solve_closure-219.py311.{ext}") for ext in ("nbi", "nbc")]
    old.append(_touch(pkg / "__pycache__" / "effects.evaluate-40.py311.1.nbc"))
    live = [_touch(pkg / "model" / "__pycache__" / f"chain.solve_closure-219.py311.{ext}") for ext in ("nbi", "nbc")]
    pyc = _touch(pkg / "__pycache__" / "chain.cpython-311.pyc")  # not numba's: left to Python
    removed = remove_orphans(str(pkg))
    assert sorted(removed) == sorted(str(p) for p in old)
    assert not any(p.exists() for p in old)
    assert all(p.exists() for p in live) and pyc.exists()
    assert remove_orphans(str(pkg)) == []  # idempotent


def test_every_kernel_folder_is_checked_for_writability(tmp_path):
    pkg = tmp_path / "vibkit"
    for sub in KERNEL_PACKAGES:
        (pkg / sub).mkdir(parents=True)
    assert _package_writable(str(pkg))
    if os.geteuid() == 0:
        return  # root writes anywhere; the read-only install test covers an unprivileged user
    os.chmod(pkg / "model", 0o555)
    try:
        assert not _package_writable(str(pkg))
    finally:
        os.chmod(pkg / "model", 0o755)


def test_the_shipped_kernels_live_in_the_kernel_folders():
    import re
    from pathlib import Path

    import vibkit

    root = Path(vibkit.__file__).parent
    decorator = re.compile(r"^\s*@.*jit\(.*cache=True", re.M)
    with_kernels = {p.relative_to(root).parts[0] for p in root.rglob("*.py") if decorator.search(p.read_text())}
    assert with_kernels and with_kernels <= set(KERNEL_PACKAGES), with_kernels
