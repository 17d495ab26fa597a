"""vibkit: vibration of escalator drive chains.

Three layers, imports pointing one way:

* :mod:`vibkit.model`: the escalator (guide, chain, sprocket, effects, scenes);
* :mod:`vibkit.analyses`: what solves it (kinematics, inverse and forward dynamics) and :func:`vibkit.simulate`;
* :mod:`vibkit.signal` and :mod:`vibkit.io`: signals and recordings (never the model);
* :mod:`vibkit.diagnose`: pitch, comparison, ride quality, reports; :mod:`vibkit.fleet`, :mod:`vibkit.sweep`;
* :mod:`vibkit.cli`: the command line; :mod:`vibkit.runtime`: guards every layer shares.

The data path: scene -> model -> analyses -> Dataset -> signal -> diagnose -> report.

Everything is SI inside: metres, kilograms, seconds, radians, newtons.
"""

__version__ = "0.12.0"

__all__ = ["__version__", "load_scene", "simulate", "read_recording", "compare", "sweep", "signal", "io"]

# eager (it loads the standard library and vibkit's sweep, scene-schema and cluster modules, no third-party package;
# measured 2026-12-07: `import vibkit, vibkit.cli.app` 0.06 CPU-s with it and without it, the command line loading
# most of those modules anyway): a lazy name would be replaced by the module object the first time someone runs
# `import vibkit.sweep`; this way `vibkit.sweep` is the function
# a read-only install (root installs, a service account runs) must still find a writable kernel cache
from .runtime.kernel_cache import configure as _configure_kernel_cache  # noqa: E402
from .sweep.run import sweep  # noqa: E402

_configure_kernel_cache()


def __getattr__(name):  # lazy: `import vibkit` stays cheap (no numba, no obspy)
    if name == "load_scene":
        from .model.scene import load_scene

        return load_scene
    if name == "simulate":
        from .analyses.simulation import simulate

        return simulate
    if name == "read_recording":
        from .io import read_recording

        return read_recording
    if name == "compare":
        from .diagnose.comparison import compare

        return compare
    if name in ("signal", "io"):  # the public subpackages, as `vibkit.signal` without importing it first
        import importlib

        return importlib.import_module(f".{name}", __name__)
    raise AttributeError(f"module 'vibkit' has no attribute {name!r}")
