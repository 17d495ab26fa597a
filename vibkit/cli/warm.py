"""``vibkit warm``: compile ahead every kernel the commands run (:mod:`vibkit.analyses.warm_up`)."""

from __future__ import annotations

import sys

from .options import add_command, add_json
from .output import msg, print_json, table

EPILOG = (
    "examples:\n"
    "  vibkit warm          # after an install or upgrade: about a minute once, then seconds\n"
    "  vibkit warm --json   # each step and its CPU seconds\n"
    "every command compiles the kernels it runs the first time anyway; this is for a site that\n"
    "would rather wait at install (an image build, a deployment step) than at a measurement"
)


def add_parser(subparsers):
    s = add_command(
        subparsers, "warm", "compile ahead the model's and filters' kernels for this machine (once per install)", EPILOG
    )
    add_json(s)
    s.set_defaults(func=run)
    return s


def run(a):
    from vibkit.analyses.warm_up import STEPS, warm_up

    def step(i, what):
        if sys.stderr.isatty():
            msg(f"[{i + 1}/{len(STEPS)}] {what}")

    cold, steps, folder = warm_up(step)
    total = sum(s.cpu_s for s in steps)
    where = folder or "numba's default: the __pycache__ folders beside vibkit's modules"
    if a.json:
        print_json(
            "warm",
            {
                "compiled": cold,
                "cache_folder": folder,
                "cpu_s": total,
                "steps": [{"what": s.what, "cpu_s": s.cpu_s} for s in steps],
            },
        )
        return 0
    print(table([(s.what, f"{s.cpu_s:.1f}") for s in steps], header=("kernels", "CPU [s]")))
    done = "compiled for this machine" if cold else "already compiled: loaded from the cache"
    msg(f"the kernels are {done} ({total:.0f} CPU s); cache: {where}")
    return 0
