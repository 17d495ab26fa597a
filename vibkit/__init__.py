"""vibkit: vibration of escalator drive chains.

Three layers, imports pointing one way:

* physics: :mod:`vibkit.guide`, :mod:`vibkit.chain`, :mod:`vibkit.sprocket`, :mod:`vibkit.dynamics`
  and the orchestrator :func:`vibkit.simulate`;
* signals: :mod:`vibkit.signal` (numpy, scipy, xarray only; never the simulator);
* data and people: :mod:`vibkit.io`, :func:`vibkit.compare`, :mod:`vibkit.report`, :mod:`vibkit.cli`.

Everything is SI inside: metres, kilograms, seconds, radians, newtons.
"""

__version__ = "0.1.0"

__all__ = ["__version__", "load_scene", "simulate", "read_recording", "compare", "sweep"]

# eager (the module imports only the standard library): a lazy name would be replaced by the module
# object the first time someone runs `import vibkit.sweep`; this way `vibkit.sweep` is the function
from .sweep import sweep  # noqa: E402

# a read-only install (root installs, a service account runs) must still find a writable kernel cache
from .kernel_cache import configure as _configure_kernel_cache  # noqa: E402

_configure_kernel_cache()


def __getattr__(name):  # lazy: `import vibkit` stays cheap (no numba, no obspy)
    if name == "load_scene":
        from .scene import load_scene

        return load_scene
    if name == "simulate":
        from .simulation import simulate

        return simulate
    if name == "read_recording":
        from .io import read_recording

        return read_recording
    if name == "compare":
        from .comparison import compare

        return compare
    raise AttributeError(f"module 'vibkit' has no attribute {name!r}")
