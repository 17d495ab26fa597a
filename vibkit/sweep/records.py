"""What one sweep run gives: its status codes, the names and units of its summaries, and the record of a
run that did not compute. Shared by :mod:`vibkit.sweep.run` and :mod:`vibkit.sweep.store`; standard
library only.
"""

from __future__ import annotations

__all__ = ["STATUS", "SUMMARIES"]

#: run status codes (the ``status`` variable; CF ``flag_values`` / ``flag_meanings``)
STATUS = {"ok": 0, "failed": 1, "invalid": 2}
PENDING = -1

#: per-run summaries: name -> (units, long_name)
SUMMARIES = {
    "link_pass_frequency": (
        "Hz",
        "link-pass frequency: forward, roller 1's advance along the guide after the "
        "start-up / time / mean pitch; inverse, imposed speed / mean pitch",
    ),
    "delta_mean": ("m", "mean tensioner displacement delta after the start-up"),
    "delta_ripple": ("m", "peak-to-peak of delta after the start-up"),
    "peak_link_tension": ("N", "largest link tension of the run (needs the link_tension output)"),
    "contact_episodes": ("1", "roller-tooth contact episodes, summed over teeth (needs the contact_force output)"),
    "last_contact_time": ("s", "last time any tooth carries a contact force (needs the contact_force output)"),
    "back_flank_episodes": ("1", "episodes of load on the back flanks (needs the flank_force output)"),
    "last_back_flank_time": ("s", "last time a back flank carries load (needs the flank_force output)"),
    "closure_residual_max": ("m", "largest closure residual of the run"),
    "solver_steps": ("1", "integrator steps (forward dynamics)"),
    "converged": (
        "1",
        "1: the run's convergence check found it converged at the scene's tolerance, 0: not "
        "(sweep --check; NaN unchecked)",
    ),
    "wall_time": (
        "s",
        "wall time of the run in its worker (the first run of a worker includes loading the compiled kernels)",
    ),
}


def _failed_record(index, status, error, wall=float("nan")):
    return {"index": index, "status": status, "error": error, "summary": {}, "kept": {}, "wall_time": wall, "pid": 0}
