"""``simulate(scene) -> xarray.Dataset``: the one orchestrator of the three analyses."""

from __future__ import annotations

import os
from typing import TYPE_CHECKING

from ..model.escalator import EscalatorModel
from ..model.scene import Scene, load_scene
from ..runtime import budget
from .convergence import checked_forward
from .forward import forward_dynamics
from .health import physics_notes, physics_warnings, unchecked_physics
from .integrate import IntegrationError
from .inverse import inverse_dynamics
from .kinematics import kinematic_sweep

if TYPE_CHECKING:  # for the annotations only
    import xarray as xr

__all__ = ["simulate"]


def simulate(
    scene: Scene | str | os.PathLike[str],
    *,
    duration: float | None = None,
    progress: bool = True,
    max_result_bytes: float | str | None = None,
    max_wall_time: float | None = None,
    check: bool | None = None,
) -> xr.Dataset:
    """Run a scene.

    Parameters
    ----------
    scene : Scene or str or Path
        A scene, or the path of a TOML scene file.
    duration : float, optional
        Overrides the scene's length: the time span of an inverse or forward run [s], or the range
        of advance of a kinematic sweep [m].
    progress : bool
        Show progress on stderr: a bar on a terminal, else one line every few seconds once the
        work has lasted more than a few seconds.
    max_result_bytes : float or str, optional
        Refuse, before any work, a run whose result arrays would be larger [bytes]; default the
        scene's ``[solver] max_result_bytes``, else ``$VIBKIT_MAX_RESULT_BYTES``, else 2 GiB
        (see :mod:`vibkit.runtime.budget`).
    max_wall_time : float, optional
        Wall-time budget of a forward integration [s]; default the scene's
        ``[solver] max_wall_time``, else ``$VIBKIT_MAX_WALL_TIME``, else 600 s.
    check : bool, optional
        Forward runs: say whether the result has converged (:mod:`vibkit.analyses.convergence`):
        run again at tighter tolerances and compare the contact history, ripples, peak tension and
        dominant frequencies. The verdict is in ``attrs["convergence"]`` (JSON) and
        ``attrs["converged"]`` (1 or 0). Default the scene's ``[solver] check``, else False.

    Returns
    -------
    xarray.Dataset
        Kinematics: dimension ``advance`` [m]; inverse and forward dynamics: dimension ``time`` [s].
        Every variable carries ``units`` and ``long_name``; attrs carry the scene text and version, and
        ``scene_defaults``: the scene keys that took the schema's default (comma-separated).

    Raises
    ------
    vibkit.runtime.budget.BudgetError
        The run would exceed its result-size limit (or a step count past reason).
    vibkit.analyses.integrate.IntegrationError
        The integration failed or ran past its wall-time budget.
    """
    if not isinstance(scene, Scene):
        scene = load_scene(scene)
    if duration is not None and not duration > 0:
        raise ValueError(f"duration must be positive, got {duration!r}")
    budget.check_run(scene, duration=duration, limit_bytes=max_result_bytes)
    if scene.analysis == "forward":
        wall = budget.max_wall_time(scene, max_wall_time)
        if scene.solver.max_wall_time != wall:
            scene = scene.with_solver(max_wall_time=wall)
    if check and scene.analysis != "forward":
        raise ValueError(
            f"{scene.source}: the convergence check applies to forward scenes; this one is "
            f"'{scene.analysis}' (drop check / --check)"
        )
    model = EscalatorModel(scene)
    outputs = scene.outputs["variables"]
    rollers = scene.outputs["rollers"]
    if scene.analysis == "kinematics":
        k = scene.kinematics
        stop = k.stop if duration is None else k.start + duration
        ds = kinematic_sweep(model, k.start, stop, k.step, rollers=rollers, outputs=outputs, progress=progress)
        return _stamp_defaults(_warn(ds, scene, model), scene)
    if scene.analysis == "inverse":
        m = scene.motion
        ds = inverse_dynamics(
            model,
            speed=m.speed,
            duration=duration or m.duration,
            step=m.step,
            start=m.start,
            effects=scene.effects,
            outputs=outputs,
            rollers=rollers,
            progress=progress,
        )
        return _stamp_defaults(_warn(ds, scene, model), scene)
    if check is None:
        check = bool(scene.solver.check)
    try:
        if check:
            ds = checked_forward(model, duration=duration, progress=progress)
        else:
            ds = forward_dynamics(model, duration=duration, progress=progress)
        return _stamp_defaults(_warn(ds, scene, model), scene)
    except IntegrationError as exc:
        if "wall-time budget" not in str(exc):
            raise
        hint = IntegrationError(
            f"{scene.source}: {exc}; raise the budget with [solver] max_wall_time, "
            "VIBKIT_MAX_WALL_TIME or --max-wall-time (0: none), or check the scene "
            "(a stiff contact or a tiny max_step makes the steps small)"
        )
        hint.t, hint.y = exc.t, exc.y
        raise hint from None


def _warn(ds, scene, model):
    """Record in ``attrs["warnings"]`` (one per line) what the physics of the run says a user should not
    miss: links in compression, a stalled motor, a drooping speed; in ``attrs["notes"]`` what is no fault but
    worth knowing: a chain that coasts (:mod:`vibkit.analyses.health`)."""
    found = physics_warnings(ds, scene, model)
    if found:
        ds.attrs["warnings"] = "\n".join(found)
    notes = physics_notes(ds, scene)
    if notes:
        ds.attrs["notes"] = "\n".join(notes)
    skipped = unchecked_physics(ds, scene)
    if skipped:
        ds.attrs["unchecked"] = "\n".join(skipped)
    return ds


def _stamp_defaults(ds, scene):
    """Record in the result which scene keys were not given and took the schema's default."""
    ds.attrs["scene_defaults"] = ", ".join(scene.defaults)
    return ds
