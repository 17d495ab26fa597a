"""What ``make demo`` runs: simulate the study's scenes, then report on both field cases.

Writes to ``reports/`` (next to the repository's ``sim/`` and ``data/``):

* ``thesis-kinematics.nc`` / ``.png``: the kinematic sweep, delta against the advance;
* ``thesis-inverse.nc`` / ``.png``: the inverse dynamics (42 s as the study; ``--inverse-duration``
  to shorten it), delta, drag force and link tension;
* ``las-palmas.pdf``, ``leon.pdf``: the diagnostic reports of the field cases with their scenes.

Progress bars only on a terminal; what was written is printed on stdout.
"""

from __future__ import annotations

import argparse
import os
import sys
import time
from pathlib import Path

from . import simulate
from .diagnose.report import atomic_path, write_report
from .io import write_result

__all__ = ["main"]


def _plot(ds, path, variables, xdim, zoom=None):
    """One panel per variable over the whole run; with ``zoom`` (a span of ``xdim``) a second column
    shows the same variables over that span, where a fast oscillation over a long run is visible."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    ncol = 2 if zoom else 1
    fig, axes = plt.subplots(
        len(variables), ncol, figsize=(9 if ncol == 1 else 13, 3 * len(variables)), sharex="col", squeeze=False
    )
    x = ds[xdim].values
    for j in range(ncol):
        sel_x = slice(None) if j == 0 else (x >= zoom[0]) & (x <= zoom[1])
        for ax, (name, sel) in zip(axes[:, j], variables):
            da = ds[name] if sel is None else ds[name].sel(sel)
            ax.plot(x[sel_x], da.values[sel_x], lw=0.8)
            ax.set_ylabel(f"{da.attrs.get('long_name', name)}\n[{da.attrs.get('units', '')}]", fontsize=8)
            ax.grid(alpha=0.3)
        unit = ds[xdim].attrs.get("units", "")
        label = f"{ds[xdim].attrs.get('long_name', xdim)} [{unit}]"
        axes[-1, j].set_xlabel(label if j == 0 else f"{label}: the first {zoom[1] - zoom[0]:g} {unit}")
    fig.suptitle(f"{ds.attrs.get('scene_name', '')}: {ds.attrs.get('analysis', '')}")
    fig.tight_layout()
    with atomic_path(path, ".png") as tmp:
        fig.savefig(tmp, format="png", dpi=110, metadata={"Software": None})
    plt.close(fig)


def main(argv=None) -> int:
    """Run the demo; returns 0, or 1 with a one-line message on failure."""
    p = argparse.ArgumentParser(prog="python -m vibkit.demo", description=__doc__.splitlines()[0])
    p.add_argument("--root", default=str(Path(__file__).resolve().parent.parent), help="repository root")
    p.add_argument("--out", default=None, help="output folder (default ROOT/reports)")
    p.add_argument(
        "--inverse-duration",
        type=float,
        default=None,
        help="inverse-dynamics time [s] (default: the scene's 42 s, as the study)",
    )
    p.add_argument(
        "--field-duration",
        type=float,
        default=None,
        help="simulated time of the field scenes [s] (default: the scenes')",
    )
    a = p.parse_args(argv)
    root = Path(a.root)
    out = Path(a.out) if a.out else root / "reports"
    out.mkdir(parents=True, exist_ok=True)
    progress = sys.stderr.isatty()
    written = []
    try:
        t0 = time.perf_counter()
        ds = simulate(root / "sim/thesis-kinematics.toml", progress=progress)
        written.append(write_result(ds, out / "thesis-kinematics.nc", overwrite=True))  # the demo's own
        _plot(ds, out / "thesis-kinematics.png", [("delta", None), ("closure_residual", None)], "advance")
        written.append(out / "thesis-kinematics.png")
        print(f"thesis-kinematics: {ds.sizes['advance']} configurations in {time.perf_counter() - t0:.1f} s")
        t0 = time.perf_counter()
        ds = simulate(root / "sim/thesis-inverse.toml", duration=a.inverse_duration, progress=progress)
        written.append(write_result(ds, out / "thesis-inverse.nc", overwrite=True))
        _plot(
            ds,
            out / "thesis-inverse.png",
            [("delta", None), ("drive_force", None), ("link_tension", {"link": 1})],
            "time",
            zoom=(0.0, 2.0),
        )
        written.append(out / "thesis-inverse.png")
        print(
            f"thesis-inverse: {float(ds.time[-1]):g} s of imposed motion, {ds.sizes['time']} steps, "
            f"in {time.perf_counter() - t0:.1f} s"
        )
        for w in (w for w in ds.attrs.get("warnings", "").split("\n") if w):
            # the study's scene has no tensioner preload (model.md, "Preload"): said, not hidden
            print(f"  warning: {w}", file=sys.stderr)
        for name, rec in (("las-palmas", "las-palmas-accelerometer.csv"), ("leon", "leon-tensioner.csv")):
            t0 = time.perf_counter()
            rep = write_report(
                root / "data/field" / rec,
                out / f"{name}.pdf",
                scene=root / "sim" / f"{name}.toml",
                duration=a.field_duration,
                progress=progress,
            )
            written.append(rep.path)
            s = rep.summary
            extra = ""
            if "pitch_m" in s:
                extra = f", pitch {1000 * s['pitch_m']:.2f} mm, pitch vs scene " + {
                    True: "consistent",
                    False: "NOT consistent",
                }.get(s.get("pitch_consistent"), "not judged (the recording states no speed)")
            print(
                f"{name}: link-pass {s['link_pass_hz']:.4f} Hz{extra}; {len(rep.pages)} pages "
                f"in {time.perf_counter() - t0:.1f} s"
            )
    except (ValueError, OSError, RuntimeError) as exc:
        print(f"vibkit demo: error: {' '.join(str(exc).split())}", file=sys.stderr)
        return 1
    print("wrote:")
    for w in written:
        print(f"  {os.path.relpath(w, Path.cwd())}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
