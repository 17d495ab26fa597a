"""A sweep's Zarr store, and the assembling of the runs' records into one Dataset.

Storage (``output=...``, a Zarr directory, format 2): the root group's attrs hold the sweep's
definition; each finished run is written by the driver to its own group ``runs/rNNNNNN`` (kept
series first, then the summaries and ``done = true`` in the group's attrs, one atomic file
replace), so a run counts as done only when both are on disk. Re-running the same sweep on the same
store resumes: finished runs are read back, only the others are computed. When every run is done
the results are consolidated into the root group (``xr.open_zarr(path)`` reads them), the per-run
groups are removed and the metadata consolidated. A store that holds a different sweep is refused
unless ``force=True``. The workers never touch the store, so a remote Dask cluster works without a
shared file system.

Imports only the standard library at load time (zarr, numpy and xarray inside the functions).
"""

from __future__ import annotations

import contextlib
import json
import os
import shutil
from pathlib import Path

from .. import __version__
from ..model.schema import key_units
from .plan import SweepError, _jsonval, plan_sweep
from .records import PENDING, STATUS, SUMMARIES, _failed_record

# units of the scene keys a sweep can vary (the coordinates' ``units``), from the scene schema
KEY_UNITS = key_units()


# ------------------------------------------------------------------------------------------------ the store


_RUNNING = (
    "a vibkit sweep in progress or interrupted: its finished runs are under runs/; "
    "open_sweep(path) (from vibkit.sweep import open_sweep) reads them, the same sweep again resumes it"
)


def _zarr():
    """The zarr module (the ``parallel`` extra), or a one-line error naming the extra."""
    from ..runtime.extras import require

    return require("zarr", "parallel", "sweep stores")


def _zkw():
    zarr = _zarr()

    return {"zarr_format": 2} if int(zarr.__version__.split(".")[0]) >= 3 else {}


def _run_group(i):
    return f"runs/r{i:06d}"


class _Store:
    """A sweep's Zarr directory: definition in the root attrs, one group per finished run."""

    def __init__(self, path, plan, *, force):
        zarr = _zarr()

        self.path = Path(path)
        self.plan = plan
        definition = plan.definition()
        self.complete = False
        #: ``(st_dev, st_ino)`` of the store's folder when this process created it (None: it was there before, or
        #: another process made it): :meth:`discard_if_unused` removes only that folder, and only while it is unused
        self.created = None
        if self.path.exists():
            existing = self._definition()
            if existing is None:
                raise SweepError(
                    f"{self.path}: exists and is not a vibkit sweep store; choose another output (nothing was changed)"
                )
            if existing == definition and force and self._state() == "complete" and self.damage():
                shutil.rmtree(self.path)  # a damaged result, recomputed as asked
            elif existing != definition:
                if not force:
                    raise SweepError(
                        f"{self.path}: holds a different sweep ({_differences(existing, definition)}); "
                        f"give a new output, or force=True (--force) to discard it"
                    )
                shutil.rmtree(self.path)
        if not self.path.exists():
            self.path.parent.mkdir(parents=True, exist_ok=True)
            tmp = self.path.with_name(f".{self.path.name}.{os.getpid()}.partial")
            if tmp.exists():
                shutil.rmtree(tmp)
            try:
                root = zarr.open_group(str(tmp), mode="w", **_zkw())
                root.attrs.update(
                    {"vibkit_sweep": json.dumps(definition), "vibkit_sweep_state": "running", "comment": _RUNNING}
                )
                zarr.open_group(str(tmp), path="runs", mode="w", **_zkw())
                zarr.consolidate_metadata(str(tmp))  # xarray.open_zarr reads the (empty) root without a warning
                os.rename(tmp, self.path)  # the store appears whole, with its definition
                st = os.stat(self.path)
                self.created = (st.st_dev, st.st_ino)
            except OSError as exc:
                if not self.path.is_dir():
                    raise
                # another process made the store at the same moment: use it if it holds this sweep
                if self._definition() != definition:
                    raise SweepError(
                        f"{self.path}: another process made a different sweep store here at the same "
                        f"time; give another output"
                    ) from exc
            finally:
                if tmp.exists():
                    shutil.rmtree(tmp, ignore_errors=True)
        self.complete = self._state() == "complete"

    @contextlib.contextmanager
    def lock(self, exclusive):
        """An advisory lock on the store's folder: shared while a run is written, exclusive while the result
        is consolidated (several processes may run the same sweep at once)."""
        try:
            import fcntl
        except ImportError:  # pragma: no cover - not POSIX: no lock
            yield
            return
        fd = os.open(self.path, os.O_RDONLY)
        try:
            fcntl.flock(fd, fcntl.LOCK_EX if exclusive else fcntl.LOCK_SH)
            yield
        finally:
            os.close(fd)  # releases the lock

    def discard_if_unused(self) -> bool:
        """Remove the store if this process created it, it is still that folder (checked by identity, not by name)
        and no run is stored or being written in it (under the exclusive lock, which writers of runs share): a sweep
        that failed before its first run leaves nothing behind.  True when removed; a store with finished runs is
        kept (it is where the sweep resumes), as is one that another process made, replaced or writes into."""
        if self.created is None:
            return False
        try:
            with self.lock(exclusive=True):
                st = os.stat(self.path)
                if (st.st_dev, st.st_ino) != self.created or self._state() == "complete":
                    return False
                runs = self.path / "runs"
                # a run stored (by this process or another: the point the sweep resumes from), or one being written
                if runs.is_dir() and any(c.name not in (".zgroup", ".zattrs", ".zmetadata") for c in runs.iterdir()):
                    return False
                shutil.rmtree(self.path)
        except OSError:
            return False
        return True

    def count_done(self) -> int:
        """Runs stored (every run once the store is complete)."""
        if self._state() == "complete":
            self.complete = True
            return len(self.plan.points)
        return len(self.done_runs(read_data=False))

    def _attrs(self):
        zarr = _zarr()

        try:
            return dict(zarr.open_group(str(self.path), mode="r", **_zkw()).attrs)
        except Exception:  # noqa: BLE001 - anything unreadable is "not a sweep store"
            return None

    def _definition(self):
        attrs = self._attrs()
        if not attrs or "vibkit_sweep" not in attrs:
            return None
        try:
            return json.loads(attrs["vibkit_sweep"])
        except (TypeError, ValueError):
            return None

    def _state(self):
        return (self._attrs() or {}).get("vibkit_sweep_state")

    def damage(self) -> str | None:
        """What is missing or corrupt in a complete store's result (None: intact)."""
        return _damage(self.path, (self._attrs() or {}).get("vibkit_chunks"))

    def check_intact(self):
        """Refuse to read back a complete result whose chunks are missing or damaged (they would read as fill
        values, or fail to decompress)."""
        problem = self.damage()
        if problem:
            raise SweepError(
                f"{self.path}: the stored sweep is damaged: {problem}; give --force (force=True) to compute it "
                "again into this store, or choose another output"
            )

    def done_runs(self, *, read_data=True) -> dict:
        """Run index -> record, for every run whose done flag is on disk (without the kept series if not
        ``read_data``)."""
        import numpy as np

        zarr = _zarr()

        out = {}
        runs = self.path / "runs"
        if not runs.is_dir():
            return out
        for d in sorted(runs.iterdir()):
            if not (d.is_dir() and d.name.startswith("r") and d.name[1:].isdigit()):
                continue
            try:
                g = zarr.open_group(str(self.path), path=f"runs/{d.name}", mode="r", **_zkw())
                attrs = dict(g.attrs)
            except Exception:  # noqa: BLE001 - a half-written run is redone
                continue
            if attrs.get("done") is not True or _damage(d, attrs.get("chunks")):
                continue  # a run with a chunk missing or damaged is computed again
            rec = _failed_record(
                int(d.name[1:]), int(attrs["status"]), attrs.get("error", ""), _num(attrs.get("wall_time"))
            )
            rec["summary"] = {k: _num(v) for k, v in attrs.get("summary", {}).items()}
            rec["pid"] = attrs.get("pid", 0)
            for var in attrs.get("kept", []) if read_data else ():
                arr = g[var]
                dims = json.loads(attrs["kept_dims"])[var]
                coords = {c: np.asarray(g[f"coord_{c}"][...]) for c in dims if f"coord_{c}" in g}
                rec["kept"][var] = {
                    "dims": dims,
                    "values": np.asarray(arr[...]),
                    "coords": coords,
                    "coord_attrs": json.loads(attrs["kept_coord_attrs"]).get(var, {}),
                    "attrs": json.loads(attrs["kept_attrs"])[var],
                }
            out[rec["index"]] = rec
        return out

    def write_run(self, rec):
        """Kept series and attrs (summaries, done flag) into a temporary group, renamed into place in one step: a
        run's group is whole or absent.  A run another process stored first is left as it is (same sweep, same
        numbers)."""
        import numpy as np

        zarr = _zarr()

        final = self.path / _run_group(rec["index"])
        tmp = self.path / "runs" / f".r{rec['index']:06d}.{os.getpid()}.tmp"
        with self.lock(exclusive=False):
            if self._state() == "complete":
                return  # consolidated meanwhile by another process
            if tmp.exists():
                shutil.rmtree(tmp)
            try:
                g = zarr.open_group(str(tmp), mode="w", **_zkw())
                coords_written = set()
                for var, k in rec["kept"].items():
                    _array(g, var, np.asarray(k["values"]))
                    for c, vals in k["coords"].items():
                        if c not in coords_written:
                            coords_written.add(c)
                            _array(g, f"coord_{c}", np.asarray(vals))
                g.attrs.update(
                    {
                        "chunks": json.dumps(_chunk_manifest(tmp)),
                        "index": rec["index"],
                        "status": rec["status"],
                        "error": rec["error"],
                        "summary": {k: _jsonval(v) for k, v in rec["summary"].items()},
                        "wall_time": _jsonval(rec["wall_time"]),
                        "pid": rec.get("pid", 0),
                        "kept": list(rec["kept"]),
                        "kept_dims": json.dumps({v: k["dims"] for v, k in rec["kept"].items()}),
                        "kept_attrs": json.dumps({v: k["attrs"] for v, k in rec["kept"].items()}),
                        "kept_coord_attrs": json.dumps({v: k["coord_attrs"] for v, k in rec["kept"].items()}),
                        "done": True,
                    }
                )
                if final.exists() and (not _done(final) or _run_damage(final)):
                    shutil.rmtree(final, ignore_errors=True)  # half a run, or a damaged one: redone
                try:
                    os.rename(tmp, final)
                except OSError:
                    if not final.is_dir():
                        raise
            finally:
                if tmp.exists():
                    shutil.rmtree(tmp, ignore_errors=True)

    def snapshot(self, ds):
        """Write an incomplete result into the root group (``xarray.open_zarr`` then reads what is stored, with
        status -1 for the pending runs); the store stays resumable."""
        with self.lock(exclusive=True):
            if self._state() == "complete":
                return
            ds = ds.copy()
            ds.attrs.update(
                vibkit_sweep=json.dumps(self.plan.definition()), vibkit_sweep_state="running", comment=_RUNNING
            )
            self._clear_root()
            ds.to_zarr(str(self.path), mode="a", consolidated=False, **_zkw())
            zarr = _zarr()

            zarr.consolidate_metadata(str(self.path))

    def _clear_root(self):
        """Remove the root group's arrays (an earlier snapshot), keeping its attrs and the runs."""
        for child in self.path.iterdir():
            if child.is_dir() and child.name != "runs" and (child / ".zarray").exists():
                shutil.rmtree(child)
        zm = self.path / ".zmetadata"
        if zm.exists():
            zm.unlink()

    def finish(self, ds) -> bool:
        """Consolidate: the whole result in the root group, then the state, then drop the run groups.

        Returns False (and writes nothing) when another process consolidated the same sweep first.
        """
        zarr = _zarr()

        with self.lock(exclusive=True):
            if self._state() == "complete":
                self.complete = True
                return False
            ds = ds.copy()
            ds.attrs["vibkit_sweep"] = json.dumps(self.plan.definition())
            ds.attrs["vibkit_sweep_state"] = "consolidating"
            ds.attrs["comment"] = "a complete vibkit sweep (xarray.open_zarr reads it)"
            self._clear_root()
            ds.to_zarr(str(self.path), mode="a", consolidated=False, **_zkw())
            zarr.open_group(str(self.path), mode="r+", **_zkw()).attrs.update(
                {"vibkit_sweep_state": "complete", "vibkit_chunks": json.dumps(_chunk_manifest(self.path))}
            )
            self.complete = True
            self._tidy()
        return True

    def tidy(self):
        with self.lock(exclusive=True):
            self._tidy()

    def _tidy(self):
        zarr = _zarr()

        if (self.path / "runs").exists():
            shutil.rmtree(self.path / "runs")
        zarr.consolidate_metadata(str(self.path))

    def open(self):
        import xarray as xr

        return xr.open_zarr(str(self.path), chunks=None)


def open_sweep(path):
    """Open a sweep store as what it holds: the consolidated result of a complete sweep, else the runs stored so
    far (status -1 for the pending ones; ``runs_pending`` in the attrs says how many).

    Raises
    ------
    SweepError
        The path is not a vibkit sweep store (the message says what it is).
    """
    import math

    from ..model.scene import parse_scene

    path = Path(path)
    if not path.is_dir():
        raise SweepError(
            f"{path}: {'no such folder' if not path.exists() else 'not a folder'}; expected a vibkit "
            f"sweep store (a Zarr folder written by vibkit sweep)"
        )
    probe = _Store.__new__(_Store)
    probe.path = path
    definition = probe._definition()
    if definition is None:
        raise SweepError(f"{path}: not a vibkit sweep store (no sweep definition in its root attributes)")
    if probe._state() == "complete":
        import xarray as xr

        probe.check_intact()

        return xr.open_zarr(str(path), chunks=None)
    try:
        plan = plan_sweep(
            parse_scene(definition["scene"], f"{path} (its scene)"),
            {a["key"]: a["spec"] for a in definition["axes"]},
            samples=definition["samples"],
            seed=definition["seed"],
            keep=definition["keep"],
            settle=definition["settle"],
            duration=definition["duration"],
            max_result_bytes=math.inf,
        )
    except (ValueError, KeyError, TypeError) as exc:
        raise SweepError(f"{path}: its sweep definition cannot be read back ({exc})") from None
    probe.plan = plan
    records = probe.done_runs()
    ds = _assemble(plan, records, complete=len(records) == len(plan.points))
    ds.attrs.update(vibkit_sweep_state="running", comment=_RUNNING)
    return ds


def _chunk_manifest(root: Path, *, skip_runs=True) -> dict:
    """Relative path -> CRC-32 of every chunk file under ``root`` (metadata dot-files and, with ``skip_runs``, the
    per-run groups left out): written beside the data, checked when they are read back."""
    import zlib

    out = {}
    for dirpath, dirs, files in os.walk(root):
        rel_dir = os.path.relpath(dirpath, root)
        dirs[:] = sorted(
            d for d in dirs if not d.startswith(".") and not (skip_runs and rel_dir == "." and d == "runs")
        )
        for f in sorted(files):
            if f.startswith("."):
                continue
            with open(os.path.join(dirpath, f), "rb") as fh:
                crc = 0
                for block in iter(lambda: fh.read(1 << 20), b""):
                    crc = zlib.crc32(block, crc)
            out[os.path.relpath(os.path.join(dirpath, f), root).replace(os.sep, "/")] = crc
    return out


def _damage(root: Path, manifest) -> str | None:
    """What is wrong with the chunks under ``root`` against ``manifest`` (None: all there and intact; a store
    written before manifests were kept cannot be checked)."""
    if not manifest:
        return None
    if isinstance(manifest, str):
        manifest = json.loads(manifest)
    now = _chunk_manifest(root)
    missing = [k for k in manifest if k not in now]
    changed = [k for k in manifest if k in now and now[k] != manifest[k]]
    if not (missing or changed):
        return None
    parts = []
    if missing:
        parts.append(f"chunk(s) {', '.join(missing[:3])}{' ...' if len(missing) > 3 else ''} missing")
    if changed:
        parts.append(
            f"chunk(s) {', '.join(changed[:3])}{' ...' if len(changed) > 3 else ''} overwritten or damaged "
            "(their checksums differ from those written with them)"
        )
    return "; ".join(parts)


def _array(g, name, data):
    return g.create_array(name, data=data) if hasattr(g, "create_array") else g.create_dataset(name, data=data)


def _run_damage(group_dir):
    try:
        attrs = json.loads((group_dir / ".zattrs").read_text())
    except (OSError, ValueError):
        return "unreadable attributes"
    return _damage(group_dir, attrs.get("chunks"))


def _done(group_dir):
    try:
        return json.loads((group_dir / ".zattrs").read_text()).get("done") is True
    except (OSError, ValueError):
        return False


def _num(v):
    return float("nan") if v is None else float(v)


def _differences(a, b):
    keys = [k for k in sorted(set(a) | set(b)) if a.get(k) != b.get(k)]
    return "differs in: " + ", ".join(keys) if keys else "differs"


# ------------------------------------------------------------------------------------------------ the result


def _assemble(plan, records, *, complete):
    """One Dataset: dims are the varied keys (or ``sample``); summaries, status, error, kept series."""
    import numpy as np
    import xarray as xr

    n = len(plan.points)
    dims = plan.dims
    shape = plan.shape
    coords = {}
    if plan.samples is None:
        for a in plan.axes:
            coords[a.key] = xr.Variable(
                (a.key,),
                np.asarray(a.values),
                attrs={"units": KEY_UNITS.get(a.key, ""), "long_name": f"scene key {a.key}"},
            )
    else:
        coords["sample"] = xr.Variable(("sample",), np.arange(n), attrs={"units": "1", "long_name": "draw number"})
        for a in plan.axes:
            coords[a.key] = xr.Variable(
                ("sample",),
                np.asarray([p[a.key] for p in plan.points]),
                attrs={"units": KEY_UNITS.get(a.key, ""), "long_name": f"scene key {a.key} (drawn)"},
            )
    status = np.full(n, PENDING, dtype=np.int8)
    error = np.full(n, "", dtype=object)
    summ = {k: np.full(n, np.nan) for k in SUMMARIES}
    for i, rec in records.items():
        status[i] = rec["status"]
        error[i] = rec["error"]
        for k in SUMMARIES:
            v = rec["wall_time"] if k == "wall_time" else rec["summary"].get(k, np.nan)
            summ[k][i] = np.nan if v is None else v
    data = {}
    for k, (units, long_name) in SUMMARIES.items():
        data[k] = xr.Variable(dims, summ[k].reshape(shape), attrs={"units": units, "long_name": long_name})
    meanings = {v: k for k, v in STATUS.items()}
    if not complete:
        meanings[PENDING] = "pending"
    flags = sorted(meanings)
    data["status"] = xr.Variable(
        dims,
        status.reshape(shape),
        attrs={
            "long_name": "run status",
            "flag_values": np.array(flags, dtype=np.int8),
            "flag_meanings": " ".join(meanings[f] for f in flags),
        },
    )
    data["error"] = xr.Variable(
        dims,
        error.reshape(shape).astype(str).astype(object),
        attrs={"long_name": "why the run failed (empty when it did not)"},
    )
    ds = xr.Dataset(data, coords=coords)
    # kept time series: outer join over the runs' own coordinates, NaN where a run has none
    names = list(dict.fromkeys(v for rec in records.values() for v in rec["kept"]))
    for var in names:
        per = [(i, rec["kept"][var]) for i, rec in sorted(records.items()) if var in rec["kept"]]
        das = [
            xr.DataArray(
                np.asarray(k["values"], dtype=float), dims=k["dims"], coords={c: v for c, v in k["coords"].items()}
            )
            for _, k in per
        ]
        joined = xr.align(*das, join="outer", fill_value=np.nan) if len(das) > 1 else das
        first = joined[0]
        full = np.full((n,) + first.shape, np.nan)
        for (i, _), da in zip(per, joined):
            full[i] = da.values
        k0 = per[0][1]
        ds[var] = xr.Variable(dims + tuple(first.dims), full.reshape(shape + first.shape), attrs=k0["attrs"])
        for c in first.dims:
            if c in first.coords and c not in ds.coords:
                ds = ds.assign_coords({c: xr.Variable((c,), first[c].values, attrs=k0["coord_attrs"].get(c, {}))})
    counts = {name: int(np.count_nonzero(status == code)) for name, code in STATUS.items()}
    ds.attrs.update(
        {
            "vibkit_version": __version__,
            "scene": plan.text,
            "scene_source": plan.source,
            "analysis": plan.analysis,
            "sweep": "monte-carlo" if plan.samples is not None else "grid",
            "varied_keys": ", ".join(a.key for a in plan.axes),
            "vary": "; ".join(f"{a.key}={a.spec}" for a in plan.axes),
            "runs": n,
            "runs_ok": counts["ok"],
            "runs_failed": counts["failed"],
            "runs_invalid": counts["invalid"],
            "runs_pending": int(np.count_nonzero(status == PENDING)),
            "start_up_excluded": (
                "a quarter of each forward run" if plan.settle is None else f"the first {plan.settle:g} s of each run"
            ),
            "history": f"swept by vibkit {__version__}",
        }
    )
    if plan.samples is not None:
        ds.attrs["seed"] = int(plan.seed)
        ds.attrs["samples"] = int(plan.samples)
    if plan.duration is not None:
        ds.attrs["duration_override"] = float(plan.duration)
    return ds
