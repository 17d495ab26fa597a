"""Parameter sweeps: one scene, some of its keys varied, every run on Dask, results streamed to Zarr.

``vibkit.sweep(scene, {"chain.link_pitch": "0.1333:0.1373:9", "effects.contact.stiffness": [1e5, 1e6, 1e7]})``
runs the 27 varied scenes and returns one :class:`xarray.Dataset` whose dimensions are the varied
keys, holding per-run summaries (link-pass frequency, delta mean and ripple, peak link tension,
contact episodes, wall time ...), a ``status`` and an ``error`` per run, and the full time series of
the outputs asked for with ``keep``. With ``samples=N`` the keys are drawn at random (uniformly in
``A:B``, or among the listed values) and the dimension is ``sample``.

Keys are the scene TOML's dotted keys (``chain.link_pitch``, ``effects.contact.stiffness``,
``solver.rtol`` ...). A key the scene loader does not know, or an effect the scene does not switch
on, or a key the scene's analysis does not read (it would give identical runs), is an error naming
the key before any run starts, as is a sweep whose result would exceed the result budget
(:mod:`vibkit.sweep.limits`). Each varied scene is validated just before it is submitted (a bounded
number are in flight), and a varied value the loader refuses is recorded as that run's failure
(status ``invalid``), as is a run whose integration fails (status ``failed``): neither stops the sweep.

Storage (``output=...``, a Zarr directory): each finished run is written by the driver as it
arrives, a re-run of the same sweep on the same store resumes, and the whole result is consolidated
into the store's root group at the end; see :mod:`vibkit.sweep.store`. The workers never touch the
store, so a remote Dask cluster works without a shared file system.

This module holds the runs (:func:`summarize`, the worker-side ``_run_one``, the submission to Dask,
the progress report) and :func:`sweep` itself; the plan (``--vary``, axes, varied scene texts) is in
:mod:`vibkit.sweep.plan`, the status codes and summary names in :mod:`vibkit.sweep.records`.

Every module of :mod:`vibkit.sweep` imports only the standard library at load time (``vibkit/__init__``
imports the ``sweep`` function eagerly, so that ``vibkit.sweep`` is always the function; the modules
are ``sys.modules["vibkit.sweep.run"]`` and its neighbours, and ``from vibkit.sweep import parse_vary``
works as usual).
"""

from __future__ import annotations

import dataclasses
import errno
import itertools
import math
import os
import sys
import time
import traceback

from ..runtime.cluster import dask_client, dask_pays, default_workers, scheduler_address, warm_workers
from ..runtime.progress import Progress
from .plan import _PRODUCES, SweepError, _source_of, plan_sweep, varied_text
from .records import STATUS, SUMMARIES, _failed_record
from .store import _assemble, _Store

#: the errors of a store that takes no more bytes: a full disk, a file-size limit (ulimit -f), a used-up quota
_NO_ROOM = (errno.ENOSPC, errno.EFBIG, errno.EDQUOT)

__all__ = ["sweep", "summarize"]


# ------------------------------------------------------------------------------------------------ one run


def _settle_time(scene, t):
    if scene.analysis != "forward" or t.size < 2:
        return 0.0
    return 0.25 * float(t[-1] - t[0])


def summarize(ds, scene, *, settle: float | None = None) -> dict:
    """Per-run summaries of a :func:`vibkit.simulate` result (NaN where the outputs do not allow one).

    Parameters
    ----------
    ds : xarray.Dataset
        The run's result.
    scene : Scene
        The scene that gave it.
    settle : float, optional
        Start-up left out of the link-pass frequency, delta mean and ripple [s] (default: a
        quarter of a forward run, nothing for an inverse run or a kinematic sweep).

    Returns
    -------
    dict
        Names and units in :data:`SUMMARIES` (``wall_time`` excepted, measured by the caller).

    Notes
    -----
    Link-pass frequency f = (s(T) - s(t_s)) / (T - t_s) / L_mean: roller 1's advance along the
    deformed guide after the start-up (its arc length s from s0 and delta, loops counted), over the
    mean link pitch (one loop of the chain is one pass of every link). Roller 1's coordinate s0 on
    the undeformed guide alone would not do over short windows: on the telescopic runs its rate
    differs from the roller's speed by up to about delta / Lt (8 %). A contact episode is one
    interval in which a tooth carries force, counted per tooth; the back-flank episodes likewise,
    on the sum of the back-flank forces.
    """
    import numpy as np

    nan = float("nan")
    out = {k: nan for k in SUMMARIES if k != "wall_time"}
    mean_pitch = float(np.mean(scene.chain.pitches()))
    axis = "time" if "time" in ds.dims else "advance"
    t = np.asarray(ds[axis].values, dtype=float)
    ts = _settle_time(scene, t) if settle is None else float(settle)
    steady = t >= (t[0] + ts) if axis == "time" else np.ones(t.size, bool)
    if steady.sum() < 2:
        if settle is not None:
            raise ValueError(
                f"settle {ts:g} s leaves {int(steady.sum())} sample(s) of the run ({t[0]:g} to "
                f"{t[-1]:g} s); the summaries need at least two"
            )
        steady = np.ones(t.size, bool)
    if scene.analysis == "forward" and "s0" in ds and "delta" in ds:
        from ..model.guide import Guide

        s0 = np.asarray(ds["s0"].values)[steady]
        d = np.asarray(ds["delta"].values)[steady]
        tt = t[steady]
        g = Guide(scene.guide)
        loops = math.floor(s0[-1] / g.p0) - math.floor(s0[0] / g.p0)
        advance = float(g.s0_to_s(s0[-1], d[-1]) - g.s0_to_s(s0[0], d[0])) + loops * g.perimeter(0.5 * (d[0] + d[-1]))
        out["link_pass_frequency"] = abs(advance) / (tt[-1] - tt[0]) / mean_pitch
    elif scene.analysis == "inverse":
        out["link_pass_frequency"] = abs(float(scene.motion.speed)) / mean_pitch
    if "delta" in ds:
        d = np.asarray(ds["delta"].values)[steady]
        out["delta_mean"] = float(d.mean())
        out["delta_ripple"] = float(d.max() - d.min())
    if "link_tension" in ds:
        out["peak_link_tension"] = float(np.nanmax(ds["link_tension"].values))
    if "contact_force" in ds:
        on = np.asarray(ds["contact_force"].values) > 0.0  # (time, tooth)
        starts = on[0].sum() + np.count_nonzero(on[1:] & ~on[:-1])
        out["contact_episodes"] = float(starts)
        any_on = on.any(axis=1)
        out["last_contact_time"] = float(t[np.nonzero(any_on)[0][-1]]) if any_on.any() else nan
    if "back_flank_force" in ds:
        on = np.asarray(ds["back_flank_force"].values) > 0.0
        out["back_flank_episodes"] = float(int(on[0]) + np.count_nonzero(on[1:] & ~on[:-1]))
        out["last_back_flank_time"] = float(t[np.nonzero(on)[0][-1]]) if on.any() else nan
    if "closure_residual" in ds:
        out["closure_residual_max"] = float(np.max(ds["closure_residual"].values))
    elif "closure_residual_max" in ds.attrs:
        out["closure_residual_max"] = float(ds.attrs["closure_residual_max"])
    if "solver_steps" in ds.attrs:
        out["solver_steps"] = float(ds.attrs["solver_steps"])
    if "converged" in ds.attrs:
        out["converged"] = float(ds.attrs["converged"])
    return out


def _simulate(scene, duration):
    """One run (a module-level name, so that tests can count the calls in a threaded cluster)."""
    from ..analyses.simulation import simulate

    return simulate(scene, duration=duration, progress=False)


#: the moment of its base scene a worker simulates as it starts (:func:`_warm`): enough to load every kernel the
#: scene's runs call [s]
WARM_DURATION_S = 0.01


def _warm(text, source):
    """Worker side, once per worker (:func:`vibkit.runtime.cluster.warm_workers`): the base scene simulated for
    :data:`WARM_DURATION_S`, which imports the simulation and loads its compiled kernels before the first run."""
    from ..analyses.simulation import simulate
    from ..model.scene import parse_scene

    scene = parse_scene(text, source)
    if scene.analysis in ("forward", "inverse"):  # a kinematic sweep's runs call no compiled integrator
        simulate(scene, duration=min(WARM_DURATION_S, float(scene.run.duration or WARM_DURATION_S)), progress=False)


def _run_one(task: dict) -> dict:
    """Worker side: simulate one varied scene, summarise it, return plain numbers (never raises)."""
    t0 = time.perf_counter()
    rec = {"index": task["index"], "status": STATUS["ok"], "error": "", "summary": {}, "kept": {}, "pid": os.getpid()}
    try:
        from ..analyses.integrate import IntegrationError
        from ..model.scene import OUTPUTS, SceneError, parse_scene

        try:
            scene = parse_scene(task["text"], task["source"])
        except SceneError as exc:
            rec.update(status=STATUS["invalid"], error=" ".join(str(exc).split()))
            return rec
        # roller 1's advance and delta are cheap (never change which outputs need the forces)
        extra = [v for v in ("delta", "s0") if v in OUTPUTS[scene.analysis] and v not in scene.outputs["variables"]]
        if extra:
            scene = dataclasses.replace(
                scene, outputs={**scene.outputs, "variables": scene.outputs["variables"] + tuple(extra)}
            )
        try:
            ds = _simulate(scene, task["duration"])
        except (IntegrationError, ValueError, ArithmeticError) as exc:
            rec.update(status=STATUS["failed"], error=f"{type(exc).__name__}: {' '.join(str(exc).split())}")
            return rec
        rec["summary"] = summarize(ds, scene, settle=task["settle"])
        for name in task["keep"]:
            for var in _PRODUCES.get(name, (name,)):
                if var in ds:
                    da = ds[var]
                    rec["kept"][var] = {
                        "dims": list(da.dims),
                        "values": da.values,
                        "coords": {d: ds[d].values for d in da.dims if d in ds.coords},
                        "coord_attrs": {d: dict(ds[d].attrs) for d in da.dims if d in ds.coords},
                        "attrs": dict(da.attrs),
                    }
    except Exception as exc:  # noqa: BLE001 - a run's failure is data, not the sweep's end
        tb = traceback.extract_tb(exc.__traceback__)
        where = f" ({tb[-1].filename.rsplit(os.sep, 1)[-1]}:{tb[-1].lineno})" if tb else ""
        rec.update(
            status=STATUS["failed"],
            error=f"{type(exc).__name__}: {' '.join(str(exc).split())}{where}",
            summary={},
            kept={},
        )
    finally:
        rec["wall_time"] = time.perf_counter() - t0
    return rec


# ------------------------------------------------------------------------------------------------ progress


class _Report:
    """A bar on a terminal; a line every ``every`` seconds otherwise; nothing when disabled."""

    def __init__(self, total, done0, *, enabled, stream=None, every=5.0):
        self.stream = stream or sys.stderr
        self.total, self.done0, self.done, self.failed = total, done0, done0, 0
        self.enabled = bool(enabled)
        self.tty = self.enabled and hasattr(self.stream, "isatty") and self.stream.isatty()
        self.bar = Progress(total, "sweep", enabled=self.tty, stream=self.stream) if self.tty else None
        self.every = every
        self.t0 = self._last = time.perf_counter()

    def line(self, text):
        if self.enabled:
            if self.tty:
                self.stream.write("\n")
            self.stream.write(text + "\n")
            self.stream.flush()

    def update(self, rec=None):
        if rec is not None:
            self.done += 1
            self.failed += rec["status"] != STATUS["ok"]
        if not self.enabled:
            return
        if self.bar is not None:
            self.bar.update(self.done)
            return
        now = time.perf_counter()
        if now - self._last >= self.every or (rec is not None and self.done == self.total):
            self._last = now
            new = self.done - self.done0
            rate = new / max(now - self.t0, 1e-9)
            left = (self.total - self.done) / rate if rate > 0 else float("nan")
            eta = f", about {left:.0f} s left" if math.isfinite(left) and self.done < self.total else ""
            self.stream.write(
                f"sweep: {self.done}/{self.total} runs done ({self.failed} failed), {rate:.2f} runs/s{eta}\n"
            )
            self.stream.flush()

    def close(self):
        if self.bar is not None:
            self.bar.close()


# ------------------------------------------------------------------------------------------------ sweep()


def sweep(
    scene,
    vary: dict,
    *,
    output=None,
    samples: int | None = None,
    seed: int | None = None,
    keep=(),
    settle: float | None = None,
    duration: float | None = None,
    scheduler: str | None = None,
    n_workers: int | None = None,
    client=None,
    force: bool = False,
    progress: bool = True,
    max_runs: int | None = None,
    check: bool = False,
    max_result_bytes=None,
    parallel: bool | None = None,
):
    """Run a scene over a grid (or Monte Carlo draws) of its keys, on Dask where that pays.

    Parameters
    ----------
    scene : Scene or str or Path
        The base scene (a TOML file or a :class:`~vibkit.model.scene.Scene` from ``load_scene``).
    vary : dict
        Dotted scene key -> values: ``"A:B:N"`` (N values from A to B), ``"a,b,c"`` or a sequence
        of values; with ``samples``, ``"A:B"`` (drawn uniformly) or a list (drawn among).
    output : str or Path, optional
        Zarr directory the runs are streamed to (resumable); without it the results stay in memory.
    samples : int, optional
        Monte Carlo: number of scenes drawn; the dimension is then ``sample``.
    seed : int, optional
        Seed of the draws (default 0): the same scene, vary and seed give the same values.
    keep : sequence of str
        Outputs whose full series are kept (e.g. ``["delta"]``); the scene must output them.
    settle : float, optional
        Start-up left out of the summaries [s] (default: a quarter of a forward run).
    duration : float, optional
        Overrides every run's duration [s] (kinematics: range of advance [m]).
    scheduler : str, optional
        Address of a running Dask scheduler; default: Dask's configuration, else a local cluster.
    n_workers : int, optional
        Worker processes of the local cluster (default: one per core).
    client : distributed.Client, optional
        An existing client to submit to (then ``scheduler`` and ``n_workers`` are not used).
    force : bool
        Discard a store at ``output`` that holds a different sweep.
    progress : bool
        A bar on a terminal, a line every 5 s otherwise (on stderr); nothing when False.
    max_runs : int, optional
        Compute at most this many runs in this call and stop (the store stays resumable).
    check : bool
        Forward scenes: check every run's convergence (``[solver] check = true`` set in the base
        scene, so a store of a checked sweep is another sweep); the summary ``converged`` is 1 or 0.
    max_result_bytes : float or str, optional
        Limit of the sweep's result (runs x values x 8 bytes + bookkeeping; default the scene's
        ``[solver] max_result_bytes``, ``VIBKIT_MAX_RESULT_BYTES``, else 2 GiB), checked from the plan
        before anything is allocated.
    parallel : bool, optional
        Where the runs go.  None (default): to ``client`` or to a running scheduler (``scheduler``, Dask's
        configuration) when there is one; else the runs start in this process, and once two have run, the rest go
        to a fresh local cluster only when they would end sooner there
        (:func:`vibkit.runtime.cluster.dask_pays`: the runs left times their time here, less their share on
        ``n_workers`` workers, beyond the cluster's start-up); a sweep of a few short runs never waits for a
        cluster.  True: always on Dask.  False: every run in this process, one after another.  The results are
        the same wherever the runs go.

    Returns
    -------
    xarray.Dataset
        Dimensions: the varied keys (grid) or ``sample``. Variables: the :data:`SUMMARIES`,
        ``status`` (0 ok, 1 failed, 2 invalid; -1 pending when stopped early), ``error``, and the
        kept series. Attrs: the scene, the sweep's definition, the counts of runs, and
        ``runs_computed`` (by this call) and ``runs_reused`` (read back from the store).

    Raises
    ------
    SweepError
        A key the scene loader does not know or the scene's analysis does not read, a malformed value
        list, a ``settle`` that leaves fewer than two samples, an output to keep that the scene does
        not give, or a store that holds another sweep (without ``force``).
    vibkit.runtime.budget.BudgetError
        The result would exceed ``max_result_bytes``.

    Notes
    -----
    The local cluster's workers are separate processes that import the calling script again: a
    script that calls ``sweep`` needs the usual ``if __name__ == "__main__":`` guard. A remote
    cluster's workers need vibkit installed; they only receive scene texts and return numbers (the
    driver writes the store). Each worker imports the simulation and loads the compiled kernels once, as it
    joins, before its first run (:func:`vibkit.runtime.cluster.warm_workers`, with the base scene).

    Examples
    --------
    >>> ds = vibkit.sweep("sim/thesis-forward.toml",                        # doctest: +SKIP
    ...                   {"chain.link_pitch": "0.1333:0.1373:9", "effects.contact.stiffness": "1e5,1e6,1e7"},
    ...                   duration=10.0, keep=["delta"], output="sweep.zarr")
    >>> ds.delta_ripple.plot(x="chain.link_pitch", hue="effects.contact.stiffness")  # doctest: +SKIP
    """
    if check:
        scene = _checked(scene)
    plan = plan_sweep(
        scene,
        vary,
        samples=samples,
        seed=seed,
        keep=keep,
        settle=settle,
        duration=duration,
        max_result_bytes=max_result_bytes,
    )
    if max_runs is not None and (isinstance(max_runs, bool) or int(max_runs) != max_runs or max_runs < 0):
        raise SweepError(f"max_runs must be a whole number >= 0, got {max_runs!r}")
    if n_workers is not None and (isinstance(n_workers, bool) or int(n_workers) != n_workers or n_workers < 1):
        raise SweepError(f"n_workers must be a whole number >= 1, got {n_workers!r}")
    store = _Store(output, plan, force=force) if output is not None else None
    n = len(plan.points)
    try:
        if store is not None and store.complete:
            store.check_intact()
            return _reopen(store, n)
        records = store.done_runs() if store is not None else {}
        reused = len(records)
        report = _Report(n, len(records), enabled=progress)
        report.failed = sum(r["status"] != STATUS["ok"] for r in records.values())
        if reused:
            report.line(f"sweep: resuming {output}: {reused} of {n} runs already done")
        tasks = _tasks(plan, records, store, report)
        if max_runs is not None:
            tasks = itertools.islice(tasks, int(max_runs))
        first = next(tasks, None)  # validates varied scenes until one can run: no cluster for none
        computed = 0
        if first is not None:
            import contextlib

            tasks = itertools.chain([first], tasks)
            on_dask = parallel is True or (parallel is None and (client is not None or scheduler_address(scheduler)))
            if not on_dask:
                w = n_workers or default_workers()
                left = n - len(records) if max_runs is None else min(int(max_runs), n - len(records))
                pays = None if parallel is False else (lambda run_s, done: dask_pays(run_s * (left - done), w))
                computed, handed = _run_here(tasks, records, store, report, pays)
                nxt = next(tasks, None) if handed else None  # runs left that the loader took: no cluster for none
                on_dask = nxt is not None
                tasks = itertools.chain([nxt], tasks) if on_dask else tasks
            if on_dask:
                ctx = (
                    contextlib.nullcontext(client)
                    if client is not None
                    else dask_client(scheduler, n_workers=n_workers)
                )
                with ctx as cl:
                    warm_workers(cl, _warm, plan.text, plan.source)
                    computed += _submit(cl, tasks, records, store, report)
        report.close()
        complete = len(records) == n
        ds = _assemble(plan, records, complete=complete)
        if store is not None:
            if complete:
                if not store.finish(ds):  # another process consolidated the same sweep first
                    return _reopen(store, n, computed=computed, reused=reused)
                ds = store.open()
            else:
                store.snapshot(ds)  # xarray.open_zarr reads what the store holds so far
    except OSError as exc:
        if store is None or exc.errno not in _NO_ROOM:
            raise
        raise _no_room(exc, store, n) from None
    except KeyboardInterrupt as exc:
        if store is not None:
            done = store.count_done()
            note = f"{done} of {n} runs are stored in {store.path}" + (
                "" if store.complete else ": run the same sweep again to resume"
            )
            exc.vibkit_note = note  # what the CLI says instead of "nothing was written"
        raise
    ds.attrs.update(runs_computed=computed, runs_reused=reused)
    return ds


def _no_room(exc, store, n):
    """The error of a sweep whose store took no more bytes (a full disk, a file-size limit, a quota), naming the
    store: one that this run created and in which no run was stored is removed (:meth:`_Store.discard_if_unused`);
    one with finished runs stays, the point the same sweep resumes from (``vibkit_resume`` True)."""
    err = OSError(exc.errno, exc.strerror, str(store.path))
    err.vibkit_resume = False
    if store.discard_if_unused():
        err.vibkit_note = "nothing was kept: the store this sweep created held no finished run and was removed"
        return err
    try:
        done = store.count_done()
    except Exception:  # noqa: BLE001 - a store that cannot be read back on a full disk: say what is certain
        done = None
    stored = "its finished runs are" if done is None else f"{done} of {n} runs are"
    err.vibkit_note = f"{stored} stored there; free space, then run the same sweep again to resume"
    err.vibkit_resume = True
    return err


def _reopen(store, n, *, computed=0, reused=None):
    if (store.path / "runs").exists() or not (store.path / ".zmetadata").exists():
        store.tidy()  # a consolidation interrupted after its data were written
    ds = store.open()
    ds.attrs.update(runs_computed=computed, runs_reused=int(ds.attrs.get("runs", n)) if reused is None else reused)
    return ds


def _tasks(plan, records, store, report):
    """The runs still to do, one at a time: each varied scene is written and validated as it is needed (a
    value the loader refuses is that run's result, recorded at once)."""
    from ..model.scene import SceneError, parse_scene

    for i in range(len(plan.points)):
        if i in records:
            continue
        p = plan.points[i]
        text, src = varied_text(plan.text, p), _source_of(plan.source, p)
        try:
            parse_scene(text, src)
        except SceneError as exc:
            rec = _failed_record(i, STATUS["invalid"], " ".join(str(exc).split()), 0.0)
            records[i] = rec
            if store is not None:
                store.write_run(rec)
            report.update(rec)
            continue
        yield {
            "index": i,
            "text": text,
            "source": src,
            "duration": plan.duration,
            "settle": plan.settle,
            "keep": plan.keep,
        }


def _checked(scene):
    """The base scene with ``[solver] check = true`` (forward scenes only)."""
    from ..model.scene import Scene, load_scene, parse_scene

    base = scene if isinstance(scene, Scene) else load_scene(scene)
    if base.analysis != "forward":
        raise SweepError(
            f"{base.source}: check applies to forward scenes; this one is '{base.analysis}' (drop --check)"
        )
    return parse_scene(varied_text(base.text, {"solver.check": True}), base.source)


#: runs a sweep computes in this process before it judges whether the rest pay for a cluster (the first loads the
#: kernels: the least of their times is the estimate)
RUNS_BEFORE_CHOOSING = 2


def _run_here(tasks, records, store, report, pays=None):
    """Runs in this process, one after another, each written as it finishes; ``(computed, handed_over)``.

    ``pays(seconds_per_run, computed)``: after :data:`RUNS_BEFORE_CHOOSING` runs and after each later one, whether
    the rest should go to Dask (True: stop here, ``handed_over`` True, the remaining ``tasks`` not consumed)."""
    computed, fastest = 0, math.inf
    for t in tasks:
        t0 = time.perf_counter()
        rec = _run_one(t)
        fastest = min(fastest, time.perf_counter() - t0)
        records[t["index"]] = rec
        if store is not None:
            store.write_run(rec)
        computed += 1
        report.update(rec)
        if pays is not None and computed >= RUNS_BEFORE_CHOOSING and pays(fastest, computed):
            return computed, True
    return computed, False


def _submit(client, tasks, records, store, report):
    """Submit the runs (a bounded number in flight, so that a long sweep holds few scene texts at a time), write
    each as it finishes; returns how many were computed."""
    from distributed import as_completed

    token = f"vibkit-sweep-{os.getpid()}-{time.time_ns()}"
    try:
        threads = sum(client.nthreads().values())
    except Exception:  # noqa: BLE001 - a scheduler that cannot say: a fixed window
        threads = 0
    window = max(16, 4 * threads)
    futures = {}

    def submit_next(pool):
        t = next(tasks, None)
        if t is None:
            return False
        fut = client.submit(_run_one, t, key=f"{token}-{t['index']}", pure=False)
        futures[fut] = t["index"]
        if pool is not None:
            pool.add(fut)
        return True

    for _ in range(window):
        if not submit_next(None):
            break
    computed = 0
    try:
        pool = as_completed(list(futures))
        for fut in pool:
            i = futures.pop(fut)
            try:
                rec = fut.result()
            except Exception as exc:  # noqa: BLE001 - e.g. KilledWorker: the run is recorded as failed
                rec = _failed_record(i, STATUS["failed"], f"{type(exc).__name__}: {' '.join(str(exc).split())}")
            fut.release()
            records[i] = rec
            if store is not None:
                store.write_run(rec)
            computed += 1
            report.update(rec)
            submit_next(pool)
    finally:
        for fut in futures:
            if not fut.done():
                fut.cancel()
    return computed
