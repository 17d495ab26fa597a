"""Two revisions of vibkit side by side in one process: the 44 s no-load scene (healthy, and with three
worn links), the revisions taking turns, best CPU time of each.

This machine's speed varies by 10-40 % from one hour to the next, so two benchmark runs an hour apart
cannot tell a 20 % change from the weather; two copies of the package taking turns in one process can.
Each revision's ``vibkit/`` is exported with ``git archive`` into a temporary folder under its own
package name (its absolute ``vibkit`` imports renamed), compiled once (a warm-up), then timed.

With ``--errors`` it also compares what each revision computes: both chains at rtol 1e-6, 1e-7 and 1e-8,
their evaluations and largest errors of delta, sprocket speed and total contact force against the baseline at
rtol 1e-11 (the converged run both should approach).

Run: ``python benchmarks/ab_forward.py main HEAD [--rounds 8] [--errors]``; writes
benchmarks/results/ab_forward.md.
"""

from __future__ import annotations

import argparse
import importlib
import importlib.util
import io
import json
import re
import subprocess
import sys
import tarfile
import tempfile
import time
from dataclasses import replace
from pathlib import Path

from _common import RESULTS, machine, markdown_table, today, write_text

ROOT = Path(__file__).resolve().parents[1]
SCENE = ROOT / "sim" / "thesis-forward.toml"
NO_LOAD = {
    "gravity": {"g": 9.81},
    "contact": {"stiffness": 1e6, "exponent": 1.5, "damping": 0.0},
    "motor": {"kp": 600.0, "speed": 0.5, "ki": 0.0},
}
WORN = [[40, 0.4 / 3 + 1e-3], [70, 0.4 / 3 + 1e-3], [100, 0.4 / 3 + 1e-3]]
IMPORT = re.compile(r"\b(from|import) vibkit\b")


def export(rev: str, name: str, where: Path) -> None:
    """``rev``'s package as ``where/name`` (its absolute imports of vibkit renamed)."""
    blob = subprocess.run(["git", "archive", rev, "vibkit"], cwd=ROOT, capture_output=True, check=True).stdout
    with tarfile.open(fileobj=io.BytesIO(blob)) as tar:
        tar.extractall(where, filter="data")
    (where / "vibkit").rename(where / name)
    for path in (where / name).rglob("*.py"):
        text = path.read_text()
        new = IMPORT.sub(lambda m: f"{m.group(1)} {name}", text).replace('"vibkit.', f'"{name}.')
        if new != text:
            path.write_text(new)


def load(name: str, where: Path):
    """The exported package ``where/name``, imported under its own name (no change to sys.path: its
    submodules are found through the package's own path)."""
    spec = importlib.util.spec_from_file_location(
        name, where / name / "__init__.py", submodule_search_locations=[str(where / name)]
    )
    module = importlib.util.module_from_spec(spec)
    sys.modules[name] = module
    spec.loader.exec_module(module)
    return module


def scene_for(name: str, worn: bool):
    sc = importlib.import_module(name + ".model.scene")
    scene = sc.load_scene(str(SCENE))
    if worn:
        text = scene.text.replace("n_rollers = 159", "n_rollers = 159\nworn_links = " + json.dumps(WORN))
        scene = sc.parse_scene(text, scene.source)
    scene = replace(scene, effects=NO_LOAD)
    return replace(scene, outputs=dict(scene.outputs, variables=("delta", "sprocket_speed", "contact_force")))


def error_rows(runs, baseline, worn):
    """Each revision at rtol 1e-6, 1e-7, 1e-8 against the baseline at 1e-11."""
    vk, scene = runs[baseline]
    ref = vk.simulate(scene.with_solver(rtol=1e-11, atol=1e-13), duration=44.0, progress=False)
    out = []
    for rtol in (1e-6, 1e-7, 1e-8):
        for rev, (vk, scene) in runs.items():
            ds = vk.simulate(scene.with_solver(rtol=rtol, atol=rtol * 1e-2), duration=44.0, progress=False)
            out.append(
                {
                    "chain": "three worn links" if worn else "healthy",
                    "rtol": rtol,
                    "revision": rev,
                    "evaluations": int(ds.attrs["solver_evaluations"]),
                    "delta_err_m": float(abs(ds.delta - ref.delta).max()),
                    "speed_err_rad_s": float(abs(ds.sprocket_speed - ref.sprocket_speed).max()),
                    "contact_force_err_N": float(
                        abs(ds.contact_force.sum("tooth") - ref.contact_force.sum("tooth")).max()
                    ),
                }
            )
    return out


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("a", help="the baseline revision (e.g. main)")
    ap.add_argument("b", help="the revision compared with it (e.g. HEAD)")
    ap.add_argument("--rounds", type=int, default=8)
    ap.add_argument("--errors", action="store_true", help="also each revision's errors against rtol 1e-11")
    args = ap.parse_args(argv)
    rows, errors = [], []
    with tempfile.TemporaryDirectory() as tmp:
        names = {}
        for i, rev in enumerate((args.a, args.b)):
            names[rev] = f"vibkit_ab{i}"
            export(rev, names[rev], Path(tmp))
        for worn in (False, True):
            runs = {}
            for rev, name in names.items():
                print(f"{rev} ({'worn' if worn else 'healthy'}): warm-up ...", file=sys.stderr, flush=True)
                vk = sys.modules.get(name) or load(name, Path(tmp))
                scene = scene_for(name, worn)
                vk.simulate(scene, duration=1.0, progress=False)  # compiles into the copy's own cache
                runs[rev] = (vk, scene)
            best = dict.fromkeys(names, float("inf"))
            for _ in range(args.rounds):
                for rev, (vk, scene) in runs.items():
                    c0 = time.process_time()
                    vk.simulate(scene, duration=44.0, progress=False)
                    best[rev] = min(best[rev], time.process_time() - c0)
            if args.errors:
                errors += error_rows(runs, args.a, worn)
            for rev in names:
                rows.append(
                    {
                        "chain": "three worn links (run by run)" if worn else "healthy (pitch table)",
                        "revision": rev,
                        "cpu_s": best[rev],
                        "realtime_factor_cpu": 44.0 / best[rev],
                        "ratio_to_baseline": best[rev] / best[args.a],
                    }
                )
    md = (
        f"# Two revisions side by side\n\n{machine()}; {today()}; the 44 s no-load scene (delta, sprocket speed, "
        f"contact force), `{args.a}` against `{args.b}` in one process taking turns, best CPU time of "
        f"{args.rounds} rounds each (`python benchmarks/ab_forward.py {args.a} {args.b}"
        f"{' --errors' if args.errors else ''}`).\n\n" + markdown_table(rows) + "\n"
    )
    if errors:
        md += (
            "\n## What each computes\n\nLargest difference over the run from the baseline at rtol 1e-11 (atol "
            "rtol / 100): delta [m], sprocket speed [rad/s], total contact force [N].\n\n"
            + markdown_table(errors)
            + "\n"
        )
    write_text(RESULTS / "ab_forward.md", md)
    print(md)
    return 0


if __name__ == "__main__":
    sys.exit(main())
