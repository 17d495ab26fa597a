"""The command line's imports without collections: the modules imported with the collector off and what they made
frozen, the collector left as the caller had it.  Each case runs in a fresh interpreter (freezing is for the
process)."""

import os
import subprocess
import sys
import textwrap
from pathlib import Path

import vibkit

ROOT = Path(vibkit.__file__).resolve().parents[1]


def _run(code):
    env = dict(os.environ, PYTHONPATH=str(ROOT) + os.pathsep + os.environ.get("PYTHONPATH", ""))
    proc = subprocess.run([sys.executable, "-c", textwrap.dedent(code)], capture_output=True, text=True, env=env)
    assert proc.returncode == 0, proc.stderr
    return proc.stdout.split()


# modules of the standard library that a bare interpreter has not imported and that make thousands of objects
_MODULES = ("email.mime.multipart", "xml.dom.minidom", "http.client", "argparse", "decimal", "unittest")

_PROBE = f"""
    import gc, sys
    collections = []
    gc.callbacks.append(lambda phase, info: phase == "start" and collections.append(info["generation"]))
    {{setup}}
    from vibkit.runtime.frozen_imports import import_frozen
    before, n0 = gc.get_freeze_count(), len(collections)
    import_frozen({_MODULES!r})
    during = len(collections) - n0
    print(during, gc.get_freeze_count() > before, all(m in sys.modules for m in {_MODULES!r}), gc.isenabled())
    """


def test_the_modules_are_imported_without_a_collection_and_frozen():
    # the same imports with the collector on do collect (the check below can fail)
    plain = _run(
        f"""
        import gc, importlib
        collections = []
        gc.callbacks.append(lambda phase, info: phase == "start" and collections.append(info["generation"]))
        for m in {_MODULES!r}:
            importlib.import_module(m)
        print(len(collections))
        """
    )
    assert int(plain[0]) > 0
    during, frozen, imported, enabled = _run(_PROBE.format(setup="pass"))
    assert (during, frozen, imported, enabled) == ("0", "True", "True", "True")


def test_a_collector_switched_off_stays_off():
    during, frozen, imported, enabled = _run(_PROBE.format(setup="gc.disable()"))
    assert (during, frozen, imported, enabled) == ("0", "True", "True", "False")


def test_a_module_that_fails_to_import_leaves_the_collector_on():
    out = _run(
        """
        import gc
        from vibkit.runtime.frozen_imports import import_frozen
        try:
            import_frozen(["no_such_module_of_vibkit"])
        except ModuleNotFoundError:
            print(gc.isenabled())
        """
    )
    assert out == ["True"]
