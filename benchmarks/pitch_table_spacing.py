"""What the pitch table's node spacing costs and buys.

The no-load scene (``sim/thesis-forward.toml``, 44 s) run with the closure read from tables of
4, 2, 1 and 0.5 mm spacing (each exactly that: the build-time check of
:mod:`vibkit.model.table_check`, which halves a spacing that errs more than the shipped chain's, is
bypassed) and solved exactly, at rtol 1e-7 and 1e-9; each run against the exact
closure at rtol 1e-11. After its last contact (7.855 s) the chain coasts in its backlash, so an
error in its forces integrates into a drift of its position: the largest difference of s0_1 over
the run is the sensitive measure; the sprocket speed's is the other. Also the table's build time
and pieces. CPU time of the whole call, one run each (the accuracy columns are what this table is
for; `bench_forward.py` measures speed).

Run: ``python benchmarks/pitch_table_spacing.py``; writes benchmarks/results/pitch_table_spacing.{csv,md}.
"""

from __future__ import annotations

import os
import sys
import time
from dataclasses import replace
from pathlib import Path

import numpy as np

import vibkit
import vibkit.analyses.forward as forward
from vibkit.analyses.forward import ForwardModel, _events
from vibkit.model.escalator import EscalatorModel
from vibkit.model.pitch_table import build_table
from vibkit.model.scene import load_scene

from _common import RESULTS, machine, markdown_table, today, write_csv, write_text

ROOT = Path(__file__).resolve().parents[1]
SPACINGS = (4e-3, 2e-3, 1e-3, 5e-4)


def scene_with(rtol, closure):
    sc = load_scene(ROOT / "sim" / "thesis-forward.toml")
    sc = replace(sc, outputs=dict(sc.outputs, variables=("delta", "sprocket_speed", "s0")))
    return replace(sc, sections=dict(sc.sections, solver=dict(sc.sections["solver"], rtol=rtol, closure=closure)))


def run(rtol, closure, spacing=None):
    """One whole call; with ``spacing`` the table is built at exactly that node spacing (the build-time
    check, which would halve a spacing that errs more than the shipped chain's, is bypassed: each row
    measures the spacing it names)."""
    original = forward.table_spacing, forward.checked_table
    if spacing is not None:
        forward.table_spacing = lambda r: spacing
        forward.checked_table = lambda model, prm, crossings, h: (build_table(model, prm, crossings, h), h, None)
    try:
        c0 = time.process_time()
        ds = vibkit.simulate(scene_with(rtol, closure), progress=False)
        return ds, time.process_time() - c0
    finally:
        forward.table_spacing, forward.checked_table = original


def build_cost(spacing):
    sc = scene_with(1e-7, "table")
    model = EscalatorModel(sc)
    fm = ForwardModel(model, sc.effects)
    cross = _events(model, fm)[0][0]
    c0 = time.process_time()
    tb = build_table(model, fm.prm, cross, spacing)
    return time.process_time() - c0, int(tb[0][2]), float(tb[0][4])


def main():
    load0 = os.getloadavg()[0]
    run(1e-7, "table", 2e-3)  # warm-up: the compiled kernels
    ref, _ = run(1e-11, "exact")
    rows = []
    for rtol in (1e-7, 1e-9):
        for spacing in (None,) + SPACINGS:
            ds, cpu = run(rtol, "exact" if spacing is None else "table", spacing)
            row = {
                "rtol": rtol,
                "closure": "exact" if spacing is None else f"table {spacing * 1e3:g} mm",
                "s0_drift_max_m": float(np.abs(ds.s0.values - ref.s0.values).max()),
                "sprocket_speed_diff_max_rad_s": float(
                    np.abs(ds.sprocket_speed.values - ref.sprocket_speed.values).max()
                ),
                "cpu_s": cpu,
            }
            if spacing is not None:
                row["build_s"], row["pieces"], row["link_length_error_m"] = build_cost(spacing)
            else:
                row["build_s"], row["pieces"], row["link_length_error_m"] = float("nan"), 0, float("nan")
            rows.append(row)
            print(row, file=sys.stderr, flush=True)
    write_csv(RESULTS / "pitch_table_spacing.csv", rows)
    md = (
        f"# Pitch table: node spacing against accuracy\n\n{machine()}; {today()}; the no-load scene, 44 s, "
        f"dopri5 with steps ended on the breakpoints, each run against the exact closure at rtol 1e-11; each "
        f"table at exactly the spacing named (the build-time check bypassed); "
        f"CPU time of one whole call; load average {load0:.1f} at the start, {os.getloadavg()[0]:.1f} at the "
        f"end.\n\n" + markdown_table(rows) + "\n"
    )
    write_text(RESULTS / "pitch_table_spacing.md", md)
    print(md)
    return 0


if __name__ == "__main__":
    sys.exit(main())
