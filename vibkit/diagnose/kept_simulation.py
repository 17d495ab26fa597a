"""A scene's simulation kept on disk: the report simulates a scene it has simulated before only once.

:func:`simulate_kept` gives what :func:`vibkit.simulate` gives for a scene and a duration, from the user's cache
folder (:mod:`vibkit.runtime.user_cache`, subfolder ``simulations``) where the same run was kept, else by simulating
it (and keeping it).  A run is kept under the text of what it is derived from (:func:`run_key`): the whole scene as
loaded (its text, its source and every setting, outputs included), the duration, the code that simulates it (a
fingerprint of every source file of the model, the analyses, the runtime and the signal layer), the versions of
Python, numpy, scipy, numba and xarray, and the machine.  Its arrays come back bit for bit, its attributes as they
were (``solver_wall_time_s`` is the kept run's).  The model (numba and the compiled kernels) is imported only where
no kept run serves, so that a warm ``vibkit report`` loads neither.

The file is an ``.npz`` of the arrays (no pickles) with the Dataset's layout as JSON; any file that fails a check is
ignored and replaced.  A run is kept only when its attributes are plain text and numbers and it is at most
:data:`vibkit.runtime.user_cache.MAX_BYTES`.
"""

from __future__ import annotations

import functools
import hashlib
import io
import json
import platform
import sys
from importlib import metadata

import numpy as np
import xarray as xr

from .. import __version__
from ..runtime.user_cache import MAX_BYTES, code_fingerprint, load_blob, private_folder, store_blob

__all__ = ["simulate_kept", "run_key"]

#: the cache's subfolder of kept simulations
FOLDER = "simulations"
#: vibkit's sub-packages whose sources a simulation depends on
CODE = ("model", "analyses", "runtime", "signal")
_PLAIN = (str, int, float, bool)


def simulate_kept(scene, *, duration=None, progress=False) -> xr.Dataset:
    """:func:`vibkit.simulate` of ``scene`` (a :class:`~vibkit.model.scene.Scene`) for ``duration`` [s] (None: the
    scene's own), the kept run where there is one (bit for bit the run that was kept), else simulated and kept."""
    key = run_key(scene, duration)
    folder = private_folder(FOLDER)
    kept = None if folder is None else _load(load_blob(folder, key, ".npz"))
    if kept is not None:
        return kept
    # the model (numba and its kernels) loaded only here, where no kept run serves
    from .fresh_simulation import simulate_fresh

    ds = simulate_fresh(scene, duration=duration, progress=progress)
    if folder is not None:
        payload = _dump(ds)
        if payload is not None:
            store_blob(folder, key, payload, ".npz")
    return ds


@functools.cache
def _code_fingerprint() -> str:
    """The sources a simulation depends on (:data:`CODE` and this module)."""
    return code_fingerprint(CODE, __file__)


def _version(package: str) -> str:
    try:
        return metadata.version(package)
    except metadata.PackageNotFoundError:
        return "absent"


@functools.cache
def _machine() -> str:
    """The machine's architecture and, on Linux, its processor's model (the kernels are compiled for it)."""
    cpu = platform.processor()
    try:
        with open("/proc/cpuinfo", encoding="utf-8", errors="replace") as f:
            cpu = next((line.split(":", 1)[1].strip() for line in f if line.startswith("model name")), cpu)
    except OSError:
        pass
    return f"{platform.machine()} {cpu}"


def run_key(scene, duration=None) -> str:
    """What a kept run is derived from, as text: the format, the code, the versions, the machine, the scene as loaded
    (the SHA-256 of its ``repr``: text, source, every setting and output) and the duration."""
    versions = " ".join(f"{p} {_version(p)}" for p in ("numpy", "scipy", "numba", "xarray"))
    return "|".join(
        [
            "simulation 1",
            f"vibkit {__version__} {_code_fingerprint()}",
            f"python {sys.version.split()[0]} {versions}",
            f"machine {_machine()}",
            f"scene {hashlib.sha256(repr(scene).encode()).hexdigest()}",
            f"duration {None if duration is None else float(duration)!r}",
        ]
    )


def _plain_attrs(attrs) -> bool:
    return all(isinstance(k, str) and type(v) in _PLAIN for k, v in attrs.items())


def _dump(ds) -> bytes | None:
    """The Dataset as ``.npz`` bytes: its variables' values (``v0``, ``v1`` ...) and its layout (``layout``, JSON);
    None where it cannot be kept exactly (an attribute that is not plain text or a number, an object array) or is
    too large to be read back."""
    names = list(ds.variables)
    if not _plain_attrs(ds.attrs) or any(not _plain_attrs(ds[n].attrs) for n in names):
        return None
    arrays = {}
    variables = []
    for i, name in enumerate(names):
        values = ds.variables[name].values
        if values.dtype.hasobject or not isinstance(name, str):
            return None
        arrays[f"v{i}"] = values
        var = ds.variables[name]
        variables.append({"name": name, "dims": list(var.dims), "attrs": dict(var.attrs), "coord": name in ds.coords})
    layout = {"attrs": dict(ds.attrs), "variables": variables, "data_vars": list(ds.data_vars)}
    buf = io.BytesIO()
    np.savez(buf, layout=np.array(json.dumps(layout)), **arrays)
    payload = buf.getvalue()
    return payload if len(payload) < MAX_BYTES - 1024 else None


def _load(payload) -> xr.Dataset | None:
    """The Dataset :func:`_dump` kept, or None where the bytes are not one."""
    if payload is None:
        return None
    try:
        with np.load(io.BytesIO(payload), allow_pickle=False) as z:
            layout = json.loads(str(z["layout"][()]))
            variables = layout["variables"]
            values = [z[f"v{i}"] for i in range(len(variables))]
        coords, data = {}, {}
        for var, v in zip(variables, values, strict=True):
            item = xr.Variable(tuple(var["dims"]), v, attrs=dict(var["attrs"]))
            (coords if var["coord"] else data)[var["name"]] = item
        order = [n for n in layout["data_vars"] if n in data]
        if len(order) != len(data):
            return None
        return xr.Dataset({n: data[n] for n in order}, coords=coords, attrs=dict(layout["attrs"]))
    except (OSError, ValueError, KeyError, TypeError, EOFError, AttributeError):
        return None
