"""Closure (position problem) cost: vibkit's link-by-link walk against the study's method.

The study (its chapter 5) solves all p coordinates together, s0_2..s0_p and delta, with a Newton /
fsolve-type solver and the analytic Jacobian of the p closure constraints. We time that method
side by side (dense Newton as in MATLAB's fsolve with a user Jacobian, and scipy.optimize.root
'hybr', the same MINPACK code fsolve wraps) on the same configurations.

Run: ``python benchmarks/bench_closure.py [--quick]``; writes benchmarks/results/closure.{csv,md,png}.
"""

from __future__ import annotations

import argparse
import dataclasses
import sys
import time

import numpy as np

from vibkit.model.chain import Chain
from vibkit.model.guide import Guide, local_map, locate, point_partials
from vibkit.model.params import ChainParams, reference_chain, reference_guide

from _common import RESULTS, best_of, machine, markdown_table, today, write_csv, write_text

L = 0.4 / 3


def scaled_chain(p: int) -> Chain:
    """The reference guide scaled in every length so that p whole links fit (the study's proportions)."""
    base = reference_guide()
    f = (p + 0.56) * L / base.perimeter
    guide = Guide(
        dataclasses.replace(
            base,
            **{
                k: getattr(base, k) * f
                for k in (
                    "tensioner_length",
                    "lower_landing",
                    "upper_landing",
                    "transition_radius",
                    "incline_length",
                    "head_radius",
                )
            },
        )
    )
    n = int(guide.p0 // L)
    return Chain(guide, ChainParams(link_pitch=L, roller_radius=0.035, roller_mass=8.0, n_rollers=n))


class StudyClosure:
    """All coordinates together: unknowns x = [s0_2 .. s0_p, delta] for a given s0_1."""

    def __init__(self, chain: Chain):
        self.tab, self.p0, self.n = chain.guide.table, chain.guide.p0, chain.n
        self.part = np.empty((self.n, 12))

    def _partials(self, s0, delta):
        for i, v in enumerate(s0):
            w = v % self.p0
            k = locate(self.tab, w)
            loc = w - self.tab[k, 0]
            point_partials(self.tab, k, local_map(self.tab, k, loc, delta)[0], loc, delta, self.part[i])
        return self.part

    def residual_jacobian(self, x, s0_1):
        n = self.n
        s0 = np.concatenate([[s0_1], x[:-1]])
        part = self._partials(s0, x[-1])
        r = part[:, 0:2]
        rs = part[:, 2:4]
        rd = part[:, 4:6]
        u = np.roll(r, -1, axis=0) - r  # u_i = r_{i+1} - r_i, the last one closing on roller 1
        res = np.sum(u * u, axis=1) - L * L
        jac = np.zeros((n, n))
        idx = np.arange(n)
        nxt = (idx + 1) % n
        # d C_i / d s0_i and d s0_{i+1}; column j-1 holds s0_j (roller 1 is not an unknown)
        d_i = -2 * np.sum(u * rs, axis=1)
        d_n = 2 * np.sum(u * rs[nxt], axis=1)
        for i in range(n):
            if i > 0:
                jac[i, i - 1] += d_i[i]
            if nxt[i] > 0:
                jac[i, nxt[i] - 1] += d_n[i]
        jac[:, -1] = 2 * np.sum(u * (rd[nxt] - rd), axis=1)
        return res, jac

    def newton(self, s0_1, x0, tol=1e-13):
        x = x0.copy()
        for _ in range(50):
            res, jac = self.residual_jacobian(x, s0_1)
            dx = np.linalg.solve(jac, -res)
            x += dx
            if np.max(np.abs(dx)) < tol:
                break
        return x

    def hybr(self, s0_1, x0):
        from scipy.optimize import root

        sol = root(lambda x: self.residual_jacobian(x, s0_1), x0, jac=True, method="hybr", options={"xtol": 1e-14})
        return sol.x


def run(quick: bool):
    rows = []
    ps = [50, 100, 159, 250, 500, 1000] if not quick else [50, 159]
    n_conf = 2000 if not quick else 50
    for p in ps:
        ch = scaled_chain(p)
        # a sweep at the study's 0.1 mm step from the start of the incline: the same work per
        # configuration (Newton iterations) whatever p, so the time shows the cost of one walk
        s0 = ch.guide.table[3, 0] + 1e-4 * np.arange(n_conf)
        ch.sweep(s0[:5])  # compile
        t_walk = best_of(lambda: ch.sweep(s0), repeat=3) / n_conf
        study = StudyClosure(ch)
        conf = ch.configure(float(s0[0]))
        # the study's solver on the same 0.1 mm steps, each warm-started from the last
        subset = s0[: (40 if p <= 250 else 8)]
        # each study solve starts from the previous configuration, as a sweep would
        x_prev = np.concatenate([conf.s0[1:], [conf.delta]])

        def study_sweep(method):
            x = x_prev.copy()
            for v in subset:
                x = (study.newton if method == "newton" else study.hybr)(float(v), x)
            return x

        t_newton = best_of(lambda: study_sweep("newton"), repeat=1) / subset.size
        t_hybr = best_of(lambda: study_sweep("hybr"), repeat=1) / subset.size if p <= 500 else float("nan")
        # agreement on delta at the last subset configuration
        xs = study.newton(float(subset[-1]), x_prev)
        d_walk = ch.configure(float(subset[-1])).delta
        rows.append(
            {
                "p": ch.n,
                "walk_us": t_walk * 1e6,
                "study_newton_us": t_newton * 1e6,
                "study_hybr_us": t_hybr * 1e6,
                "ratio_newton_over_walk": t_newton / t_walk,
                "ratio_hybr_over_walk": t_hybr / t_walk,
                "delta_difference_m": abs(xs[-1] - d_walk),
            }
        )
        print(rows[-1], flush=True)
    # the study's full-loop sweep at 0.1 mm with the reference escalator
    ch = Chain(Guide(reference_guide()), reference_chain())
    s0 = np.arange(0.0, ch.guide.p0, 1e-4 if not quick else 1e-2)
    t0 = time.perf_counter()
    d, resid = ch.sweep(s0)
    full = time.perf_counter() - t0
    sweep = {
        "configurations": s0.size,
        "step_m": s0[1] - s0[0],
        "wall_s": full,
        "us_per_configuration": full / s0.size * 1e6,
        "closure_residual_max_m": float(resid.max()),
        "delta_mean_mm": float(d.mean() * 1e3),
    }
    print(sweep, flush=True)
    return rows, sweep


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--quick", action="store_true", help="fewer sizes and configurations (CI)")
    args = ap.parse_args(argv)
    rows, sweep = run(args.quick)
    name = "closure_quick" if args.quick else "closure"  # a quick run never overwrites the full results
    write_csv(RESULTS / f"{name}.csv", rows)
    md = [
        f"# Closure benchmark\n\n{machine()}; {today()}; {'quick' if args.quick else 'full'} run.\n",
        "Time per configuration [us]: vibkit's link-by-link walk (Newton on delta alone, compiled) and the "
        "study's all-coordinates solve (dense Newton with the analytic Jacobian; scipy.optimize.root 'hybr', "
        "fsolve's MINPACK code), side by side in one process.\n",
        markdown_table(rows),
        "",
        f"Full-loop kinematic sweep of the reference escalator (p = 159): {sweep['configurations']} configurations "
        f"at {sweep['step_m'] * 1e3:.1f} mm in {sweep['wall_s']:.2f} s ({sweep['us_per_configuration']:.1f} us each), "
        f"closure residual at most {sweep['closure_residual_max_m']:.2g} m, mean delta {sweep['delta_mean_mm']:.3f} mm.\n",
    ]
    write_text(RESULTS / f"{name}.md", "\n".join(md))
    try:
        import matplotlib

        matplotlib.use("Agg")
        import matplotlib.pyplot as plt

        fig, ax = plt.subplots(figsize=(6, 4))
        p = [r["p"] for r in rows]
        ax.loglog(p, [r["walk_us"] for r in rows], "o-", label="vibkit walk")
        ax.loglog(p, [r["study_newton_us"] for r in rows], "s-", label="study: dense Newton")
        ax.loglog(p, [r["study_hybr_us"] for r in rows], "^-", label="study: hybr (fsolve)")
        ax.loglog(p, np.array(p) * rows[0]["walk_us"] / p[0], "k:", label="linear in p")
        ax.set_xlabel("rollers p")
        ax.set_ylabel("time per configuration [us]")
        ax.set_title(f"Closure cost ({today()})")
        ax.legend()
        ax.grid(True, which="both", alpha=0.3)
        fig.tight_layout()
        fig.savefig(RESULTS / f"{name}.png", dpi=110)
    except ImportError:
        pass
    return 0


if __name__ == "__main__":
    sys.exit(main())
