"""The pitch table's node spacing, checked against the exact closure when the table is built.

The table's error grows with how sharply the chain's accelerations change along its travel, and
that depends on the geometry: a worn chain that extends the tensioner by 0.1-0.2 m has accelerations
that change faster than the shipped chain's, and a table with the shipped chain's node spacing errs
6-27 times more there. So the spacing is not fixed: :func:`checked_table` builds the table at the
spacing :func:`vibkit.model.pitch_table.table_spacing` gives for the tolerance, compares the chain's
acceleration d2 s0_1/dt^2 of the table with that of the exact closure (:func:`vibkit.model.effects.evaluate`,
contact off: the contact forces are the same functions of the positions either way) at three points
of every piece, and halves the spacing while the r.m.s. difference is more than the shipped chain's
(:data:`ACC_RMS_TARGET`). Measured on the 3 % elongated chain at rtol 1e-7: at 2 mm the chain ends
a 44 s run 36 um off the converged one (the exact closure: 8 um), at 1 mm 8 um.
"""

from __future__ import annotations

import numpy as np

from .effects import Work, evaluate, reset_closure
from .pitch_table import build_table, table_delta, table_evaluate
from .slots import HEAD_PIECES, IP_CONTACT, PRM_IP, TB_HEAD, TB_UP

__all__ = ["checked_table", "table_error", "ACC_RMS_TARGET", "MAX_HALVINGS"]

#: the r.m.s. difference of the chain's acceleration between the table and the exact closure that a
#: table may keep: the shipped no-load scene's at 2 mm node spacing and 0.5 m/s is 6.9e-9 m/s^2 (4.5e-9
#: at 1 mm, 3.7e-9 at 0.5 mm: below that the difference no longer falls as h^4), with a margin of two.
#: A 3 % elongated chain (delta = -0.229 m) gives 6.0e-8 at 2 mm, 3.7e-8 at 1 mm; 156 links (delta =
#: +0.233 m) 1.1e-7 and 3.3e-8. [m/s^2]
ACC_RMS_TARGET = 1.5e-8
#: the spacing is halved at most this many times (a quarter of the tolerance's spacing), and no more
#: once a halving gains less than :data:`MIN_GAIN` (the difference has reached its floor)
MAX_HALVINGS = 2
MIN_GAIN = 2.0
CHECK_SPEED = 0.5  # [m/s] the chain speed at which the accelerations are compared (they scale as v^2)
POINTS = (0.25, 0.5, 0.75)  # where along each piece
SHORT_PIECE = 1e-4  # [m] pieces shorter than this (two breakpoints close together) are not sampled


def table_error(model, prm, tb, speed=CHECK_SPEED) -> float:
    """R.m.s. difference of d2 s0_1/dt^2 between the table ``tb`` and the exact closure at three points
    of every piece of the pitch (longer than :data:`SHORT_PIECE`), chain at ``speed`` [m/s], contact off. [m/s^2]"""
    ip = prm[PRM_IP].copy()
    ip[IP_CONTACT] = 0
    prm_free = prm[:PRM_IP] + (ip,) + prm[PRM_IP + 1 :]
    ws = Work(model.n, model.sprocket.teeth).arrays
    info = ws[-1]
    up = tb[TB_UP]
    npc = int(tb[TB_HEAD][HEAD_PIECES])
    y = np.array([0.0, speed, 0.0, 0.0, 0.0])
    exact, table = np.empty(5), np.empty(5)
    total, count = 0.0, 0
    for p in range(npc):
        if up[p + 1] - up[p] < SHORT_PIECE:
            continue
        for x in POINTS:
            y[0] = up[p] + x * (up[p + 1] - up[p])
            reset_closure(info, table_delta(tb, y[0]))
            if evaluate(0.0, y, exact, prm_free, ws, False) != 0:
                continue
            table_evaluate(0.0, y, table, prm_free, ws, False, tb)
            total += (table[1] - exact[1]) ** 2
            count += 1
    return float(np.sqrt(total / count)) if count else 0.0


def checked_table(model, prm, crossings, spacing):
    """The pitch table, its node ``spacing`` [m] (the tolerance's, :func:`vibkit.model.pitch_table.table_spacing`)
    halved while the table errs more than :data:`ACC_RMS_TARGET` (see the module's docstring).
    Returns (table, spacing [m], r.m.s. acceleration difference [m/s^2])."""
    tb = build_table(model, prm, crossings, spacing)
    err = table_error(model, prm, tb)
    for _ in range(MAX_HALVINGS):
        if err <= ACC_RMS_TARGET:
            break
        finer = build_table(model, prm, crossings, 0.5 * spacing)
        err_finer = table_error(model, prm, finer)
        gain = err / err_finer if err_finer > 0 else np.inf
        tb, spacing, err = finer, 0.5 * spacing, err_finer
        if gain < MIN_GAIN:
            break
    return tb, spacing, err
