"""What keeping the worn link's signature runs on disk saves ``vibkit links --escalator``.

The 90-link profile of the tests (28 teeth, 0.5 m/s, 133.33 mm, running down), link 40 one millimetre long,
recordings of 3 and 10 loops (after one loop of settling, 200 Hz, 1 um of noise).  Each ``vibkit links
REC --escalator P`` runs in a fresh process with an empty cache folder (cold: the three signature runs are
simulated and kept) and then twice more with the same folder (warm: read back, checked).  The CPU seconds are
the child process's (user + system), so the import of vibkit and its libraries is in every number; the
"no analysis" row is ``vibkit --version``-like import cost measured the same way (``python -c "import
vibkit.cli.links, vibkit.diagnose.links"``).  The link read is shown to check that every run gives the same.

Writes ``links_cache.md``.
"""

from __future__ import annotations

import dataclasses
import importlib
import os
import subprocess
import sys
import tempfile
from pathlib import Path

import numpy as np

from _common import RESULTS, machine, markdown_table, support, today, write_text

ROOT = Path(__file__).resolve().parents[1]
# tests/support, loaded by _common without touching sys.path
PROFILE_90 = importlib.import_module(f"{support.__name__}.profiles").PROFILE_90

SPEED = 0.5
WORN = 40


def _recording(folder, profile_text, loops):
    import xarray as xr

    import vibkit
    from vibkit.diagnose.links import profile_scene_file
    from vibkit.model.profile import parse_profile
    from vibkit.model.scene import load_scene

    scene = load_scene(profile_scene_file(parse_profile(profile_text, "E90.toml")))
    pitch, n = scene.chain.link_pitch, scene.chain.n_rollers
    sc = dataclasses.replace(
        scene,
        chain=dataclasses.replace(scene.chain, worn_links=((WORN, pitch + 1e-3),)),
        outputs=dict(scene.outputs, variables=("delta",)),
    ).with_solver(closure="exact")
    settle = n * pitch / SPEED + 5.0
    ds = vibkit.simulate(sc, duration=settle + (loops * n + 3) * pitch / SPEED, progress=False)
    keep = ds.time.values >= settle
    rng = np.random.default_rng(loops)
    rec = xr.Dataset(
        {"delta": ("time", ds.delta.values[keep] + rng.normal(0, 1e-6, keep.sum()), {"units": "m"})},
        coords={"time": ("time", ds.time.values[keep] - settle, {"units": "s"})},
    )
    path = folder / f"rec-{loops}.nc"
    rec.to_netcdf(path)
    return path


def _cpu(args, cache):
    env = dict(os.environ, XDG_CACHE_HOME=str(cache), PYTHONPATH=str(ROOT))
    before = os.times()
    p = subprocess.run([sys.executable, *args], env=env, capture_output=True, text=True, cwd=ROOT)
    after = os.times()
    cpu = after.children_user - before.children_user + after.children_system - before.children_system
    last = p.stdout.strip().splitlines()[-1] if p.stdout.strip() else p.stderr.strip()[-200:]
    return cpu, p.returncode, last


def main():
    with tempfile.TemporaryDirectory() as tmp:
        folder = Path(tmp)
        os.environ["XDG_CACHE_HOME"] = str(folder / "recordings-cache")  # the recordings' own scene: not the user's
        profile_text = PROFILE_90.replace("teeth = 28", 'teeth = 28\ndirection = "down"')
        profile = folder / "E90-down.toml"
        profile.write_text(profile_text)
        rows = []
        imp, _, _ = _cpu(["-c", "import vibkit.cli.links, vibkit.diagnose.links"], folder / "none")
        rows.append({"recording": "-", "run": "import only", "CPU s": round(imp, 2), "exit": 0, "link read": "-"})
        for loops in (3, 10):
            rec = _recording(folder, profile_text, loops)
            cache = folder / f"cache-{loops}"
            for label in ("cold", "warm", "warm"):
                cpu, rc, last = _cpu(["-m", "vibkit", "links", str(rec), "--escalator", str(profile)], cache)
                rows.append(
                    {
                        "recording": f"{loops} loops",
                        "run": label,
                        "CPU s": round(cpu, 2),
                        "exit": rc,
                        "link read": " ".join(last.split()[:3]),
                    }
                )
    text = (
        f"# `vibkit links --escalator`: the signature runs kept on disk\n\n{today()}, {machine()}\n\n"
        "CPU seconds of each `vibkit links` process (user + system, import included); cold: an empty cache folder, "
        "warm: the runs the cold call kept. 90-link profile running down, link 40 worn 1 mm "
        "(benchmarks/bench_links_cache.py).\n\n" + markdown_table(rows) + "\n"
    )
    write_text(RESULTS / "links_cache.md", text)
    print(text)


if __name__ == "__main__":
    main()
