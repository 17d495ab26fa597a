"""Which link is worn, on simulated recordings of the study's escalator: detection probability against
the excess pitch of one link for 2, 3 and 5 loops, how often the flagged number is the worn link, with
and without passengers aboard, at two noise levels; false alarms on healthy-chain recordings from many
independent simulations (what a step accelerometer sees: ``bench_links_step.py``).

Run:  python benchmarks/bench_links.py [--quick]

Writes ``benchmarks/results/links{,_quick}.{md,csv}``, ``links_false_alarms{,_quick}.csv`` and
``links{,_quick}.png``.

The recordings: ``sim/thesis-forward.toml`` (no load, 0.5 m/s) simulated once per excess pitch with
link 40 that much longer (exact closure), for five loops after one loop and 5 s of settling (the base
runs); with passengers, the same scene with passengers boarding the step at the lower landing at random
times (about one every 20 s, 50-100 kg, each riding to the upper landing).  Every recording is a base
run's tensioner displacement with its own realisation of white noise and of a speed wander (the
recording's time warped by a sinusoid of 1 % amplitude, random period 60-300 s and phase), cut to the
first 2, 3 or 5 loops.  The healthy recordings come from independent simulations (random start position
on the loop, speed within +-2 %, half of them with passengers), each with several noise and wander
draws.  `vibkit links` scans each with the no-load scene's signature at the nominal speed, as a user
who knows the escalator but not its load or its exact speed would.
"""

from __future__ import annotations

import argparse
import dataclasses
import time

import numpy as np

from _common import RESULTS, machine, markdown_table, today, write_csv, write_text

SCENE = "sim/thesis-forward.toml"
WORN = 40
SPEED = 0.5
FS = 200.0
NOISE = 1e-6  # tensioner displacement noise of the must-show [m]
FIELD_NOISE = 1.5e-6  # the Leon tensioner recording's noise (data/field/leon-tensioner.csv) [m]
WANDER = 0.01  # relative speed wander amplitude
PASSENGER_KP = 6000.0  # motor gain with passengers [N m s]
ALPHA = 0.01  # stated false-alarm probability per recording
REFUSED = []  # recordings refused


def variant(scene, *, excess=None, speed=SPEED, start=0.0, passengers=None, variables=("delta", "sprocket_angle")):
    """The scene with link ``WORN`` longer by ``excess`` (exact closure), its motor at ``speed``, roller 1
    at ``start`` and ``passengers`` (options) aboard."""
    effects = dict(scene.effects)
    effects["motor"] = dataclasses.replace(effects["motor"], speed=float(speed))
    if passengers is not None:
        effects["passengers"] = passengers
        # the study's loaded scene (sim/thesis-passengers.toml): kp 10x the unloaded scene's, or a passenger
        # slows the chain by half
        effects["motor"] = dataclasses.replace(effects["motor"], kp=PASSENGER_KP)
    sections = dict(scene.sections, run={**scene.section("run"), "start": float(start)})
    sc = dataclasses.replace(
        scene, effects=effects, sections=sections, outputs=dict(scene.outputs, variables=variables)
    )
    if excess is None:
        return sc
    pitch = scene.chain.link_pitch
    chain = dataclasses.replace(scene.chain, worn_links=((WORN, pitch + excess),))
    return dataclasses.replace(sc, chain=chain).with_solver(closure="exact")


def passengers_for(scene, *, speed, start, t0, t1, rng):
    """Passengers boarding at random times in ``[t0, t1]`` (gaps 8-32 s), each on the step whose middle
    roller is then at the lower landing, riding to the upper landing (by time: the chain's own speed)."""
    from vibkit.model.escalator import EscalatorModel
    from vibkit.model.schema import PassengersOptions

    m = EscalatorModel(scene)
    conf = m.chain.configure(float(start))
    p0 = m.guide.p0
    lower, upper = m.place("lower_landing"), m.place("upper_landing")
    n_steps = scene.chain.n_rollers // scene.chain.links_per_step
    u0 = np.array([conf.s0[int(m.step_rollers(s)[1])] for s in range(1, n_steps + 1)])
    masses, steps, board, alight = [], [], [], []
    t = t0 + rng.uniform(0.0, 16.0)
    while t < t1:
        gap = (lower - (u0 + speed * t)) % p0  # how far each step's middle roller is behind the landing
        s = int(np.argmin(np.minimum(gap, p0 - gap)))
        masses.append(float(rng.uniform(50.0, 100.0)))
        steps.append(s + 1)
        board.append(float(t))
        alight.append(float(t + (upper - lower) / speed))
        t += rng.uniform(8.0, 32.0)
    return PassengersOptions.from_mapping({"mass": masses, "step": steps, "board": board, "alight": alight})


def simulate(sc, loops):
    """Tensioner displacement after one loop and 5 s of settling, for ``loops`` loops and a few links more,
    and the sprocket turns' count of links passed before the cut."""
    import vibkit

    n, pitch = sc.chain.n_rollers, sc.chain.link_pitch
    speed = sc.effects["motor"].speed
    settle = n * pitch / speed + 5.0
    duration = settle + (loops * n + 24) * pitch / speed * (1.12 + 2 * WANDER)
    ds = vibkit.simulate(sc, duration=duration, progress=False)
    t = ds.time.values
    keep = t >= settle
    theta = ds.sprocket_angle.values
    passed = sc.sprocket.teeth * abs(float(theta[keep][0] - theta[0])) / (2 * np.pi)
    return t[keep] - t[keep][0], ds.delta.values[keep], passed


def worn_run(scene, excess, passengers, rng, loops=5):
    """A worn base run (start 0, nominal speed) and the worn link's number from the cut."""
    from vibkit.diagnose.links import link_number_of

    n, pitch = scene.chain.n_rollers, scene.chain.link_pitch
    settle = n * pitch / SPEED + 5.0
    pas = None
    if passengers:
        pas = passengers_for(
            scene, speed=SPEED, start=0.0, t0=settle - 10.0, t1=settle + loops * n * pitch / SPEED, rng=rng
        )
    t, x, passed = simulate(variant(scene, excess=excess, passengers=pas), loops)
    return t, x, link_number_of(WORN, passed, n)


def realisation(t, x, loops, n, rng, noise):
    """One recording: the base run warped by a speed wander, cut to ``loops`` loops, with noise."""
    period = rng.uniform(60.0, 300.0)
    ph = rng.uniform(0, 2 * np.pi)
    # loops + 3 links at the slowest wander, and 10 % more for a chain slowed by its passengers (each slows it
    # by about 5 % with the study's motor gain); the link map uses whole loops only
    span = (loops * n + 3) * 0.13333333333333333 / SPEED * (1 + WANDER) * 1.10
    tr = np.arange(0.0, span, 1.0 / FS)
    # the chain's own time runs at 1 + w(t): the signal at time tr is the base run at tau(tr)
    tau = tr + WANDER * period / (2 * np.pi) * (np.sin(2 * np.pi * tr / period + ph) - np.sin(ph))
    tau = tau - tau.min()
    y = np.interp(tau, t, x) + rng.normal(0.0, noise, tr.size)
    return tr, y


def scan(tr, y, n):
    import xarray as xr

    from vibkit.diagnose.links import find_worn_links

    rec = xr.Dataset({"delta": ("time", y, {"units": "m"})}, coords={"time": tr})
    try:
        return find_worn_links(rec, speed=SPEED, n_links=n, scene=SCENE, false_alarm=ALPHA)
    except ValueError:  # refused (the phase could not be followed): no flag, counted
        REFUSED.append(1)
        return None


def detection_rows(label, base, loops_list, trials, noise, n, rng):
    """Rows of one set: per excess and loops, the share of recordings with any flag, with the worn link
    alone flagged, and the median excess found."""
    rows = []
    for ex, (t, x, expected) in base.items():
        for loops in loops_list:
            det = right = top = near = alt = named = 0
            amps = []
            for _ in range(trials):
                res = scan(*realisation(t, x, loops, n, rng, noise), n)
                if res is not None and res.flagged:
                    det += 1
                    f = max(res.flagged, key=lambda f: f["t"])
                    top += f["link"] == expected
                    near += min((f["link"] - expected) % n, (expected - f["link"]) % n) <= 2
                    right += f["link"] == expected and len(res.flagged) == 1
                    alt += bool(f["alternatives"])
                    named += f["link"] == expected or expected in f["alternatives"]
                    amps.append(f["excess_pitch_mm"])
            rows.append(
                {
                    "load": label,
                    "noise [um]": 1e6 * noise,
                    "excess [mm]": 1e3 * ex,
                    "loops": loops,
                    "recordings": trials,
                    "detected": det / trials,
                    "strongest flag right": top / trials,
                    "strongest within 2 links": near / trials,
                    "right link alone": right / trials,
                    "with alternatives": alt / trials,
                    "worn link named": named / trials,
                    "median excess found [mm]": f"{np.median(amps):.3f}" if amps else "-",
                }
            )
            print(rows[-1], flush=True)
    return rows


def false_alarms(scene, n_sims, draws, loops, n, rng):
    """Healthy recordings from ``n_sims`` independent simulations (random start, speed within +-2 %, every
    other one with passengers), ``draws`` noise and wander realisations each (noise 1 or 1.5 um): one row
    per load and one for all."""
    pitch = scene.chain.link_pitch
    counts = {"none": [0, 0, 0, 0], "passengers": [0, 0, 0, 0]}  # simulations, recordings, flagged, under minimum
    cpu = 0.0
    for i in range(n_sims):
        speed = SPEED * rng.uniform(0.98, 1.02)
        start = rng.uniform(0.0, scene.chain.n_rollers * pitch)
        pas = None
        if i % 2:
            settle = n * pitch / speed + 5.0
            t1 = settle + loops * n * pitch / speed
            pas = passengers_for(scene, speed=speed, start=start, t0=settle - 10, t1=t1, rng=rng)
        c0 = time.process_time()
        t, x, _ = simulate(variant(scene, speed=speed, start=start, passengers=pas), loops)
        cpu += time.process_time() - c0
        c = counts["passengers" if i % 2 else "none"]
        c[0] += 1
        for j in range(draws):
            res = scan(*realisation(t, x, loops, n, rng, (NOISE, FIELD_NOISE)[j % 2]), n)
            c[1] += 1
            c[2] += bool(res is not None and res.flagged)
            c[3] += bool(res is not None and any("under" in s for s in res.notes))
    counts["all"] = [a + b for a, b in zip(counts["none"], counts["passengers"])]
    rows = []
    for load, (sims, total, hits, small) in counts.items():
        rate = hits / total
        sigma = (ALPHA * (1 - ALPHA) / total) ** 0.5
        rows.append(
            {
                "load": load,
                "loops": loops,
                "simulations": sims,
                "recordings": total,
                "false alarms": hits,
                "rate": rate,
                "stated": ALPHA,
                "binomial sigma": sigma,
                "within": rate <= ALPHA + 2 * sigma,
                "under the minimum excess": small,
            }
        )
        print(rows[-1], flush=True)
    return rows, cpu


def main():
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--quick", action="store_true", help="two excess pitches, 3 loops, few recordings")
    a = p.parse_args()
    from vibkit.diagnose.links import worn_link_signature
    from vibkit.model.scene import load_scene

    scene = load_scene(SCENE)
    n = scene.chain.n_rollers
    rng = np.random.default_rng(29)
    t0 = time.process_time()
    worn_link_signature(SCENE, speed=SPEED, fs=FS)  # simulated once, cached for every scan
    excesses = [0.3e-3, 1e-3] if a.quick else [0.1e-3, 0.2e-3, 0.3e-3, 0.5e-3, 1e-3, 3e-3]
    loops_list = [3] if a.quick else [2, 3, 5]
    trials = 4 if a.quick else 20
    n_sims, draws = (4, 5) if a.quick else (50, 20)
    sim_cpu = 0.0
    c0 = time.process_time()
    empty = {ex: worn_run(scene, ex, False, rng) for ex in excesses}
    loaded = {ex: worn_run(scene, ex, True, rng) for ex in excesses if ex >= 0.2e-3}
    sim_cpu += time.process_time() - c0
    rows = detection_rows("none", empty, loops_list, trials, NOISE, n, rng)
    rows += detection_rows("none", empty, [3], trials, FIELD_NOISE, n, rng)
    rows += detection_rows("passengers", loaded, loops_list, trials, FIELD_NOISE, n, rng)
    fa, fa_cpu = false_alarms(scene, n_sims, draws, 3, n, rng)
    sim_cpu += fa_cpu
    p90 = {}
    for key in (("none", 1e6 * NOISE), ("none", 1e6 * FIELD_NOISE), ("passengers", 1e6 * FIELD_NOISE)):
        three = [r for r in rows if r["loops"] == 3 and (r["load"], r["noise [um]"]) == key]
        p90[key] = next((r["excess [mm]"] for r in three if r["right link alone"] >= 0.9), None)
    suffix = "_quick" if a.quick else ""
    write_csv(RESULTS / f"links{suffix}.csv", rows)
    write_csv(RESULTS / f"links_false_alarms{suffix}.csv", fa)
    write_text(RESULTS / f"links{suffix}.md", _report(suffix, n, rows, fa, p90, t0, sim_cpu, n_sims, draws))
    _plot(rows, RESULTS / f"links{suffix}.png")
    print((RESULTS / f"links{suffix}.md").read_text())


def _report(suffix, n, rows, fa, p90, t0, sim_cpu, n_sims, draws):
    from vibkit.diagnose.links import MIN_EXCESS_M

    three = [r for r in rows if r["loops"] == 3]
    others = [r for r in rows if r["loops"] != 3]
    p90_lines = "\n".join(
        f"- {load}, {noise:g} um: {'%g mm' % v if v is not None else 'none of those tried'}"
        for (load, noise), v in p90.items()
    )
    return (
        f"# bench_links{suffix}\n\n{machine()}; {today()}; CPU {time.process_time() - t0:.0f} s "
        f"(simulations {sim_cpu:.0f} s)\n\n"
        f"Tensioner displacement of `{SCENE}` ({SPEED} m/s, {n} links), link {WORN} longer by the excess; "
        f"white noise {1e6 * NOISE:g} um (the must-show) or {1e6 * FIELD_NOISE:g} um (the Leon tensioner "
        f"recording's level); speed wander {100 * WANDER:g} % (sinusoid, period 60-300 s); *passengers*: "
        "50-100 kg passengers boarding at the lower landing about every 20 s (8-32 s apart), each riding "
        f"to the upper landing; false-alarm probability {ALPHA} per recording; `vibkit links` with the "
        "no-load scene's signature at 0.5 m/s.\n\n"
        "## Detection from 3 loops\n\n" + markdown_table(three) + "\n\n"
        "*detected*: any link flagged; *strongest flag right*: the link with the largest statistic is the worn "
        "one (other links may be flagged too), *within 2 links*: it is at most 2 links from it; *right link alone*: exactly one link flagged and it is the worn one; "
        "*with alternatives*: the strongest flag names other links where the signature fits nearly as well "
        "(`A or B`); *worn link named*: the worn link is the strongest flag's number or one of its alternatives; *median excess found*: over the recordings with a flag, `-` where none had one. Links under "
        f"the minimum excess ({1e3 * MIN_EXCESS_M:g} mm) are not flagged by design.\n\n"
        "Smallest excess found, and numbered right, with probability 0.9 from 3 loops:\n\n"
        + p90_lines
        + "\n\n"
        + ("## Detection from 2 and 5 loops\n\n" + markdown_table(others) + "\n\n" if others else "")
        + "## False alarms on the healthy chain\n\n"
        + markdown_table(fa)
        + "\n\n"
        f"{fa[-1]['recordings']} healthy recordings of 3 loops from {n_sims} independent simulations of the healthy "
        f"chain (start of roller 1 uniform over the loop, motor speed uniform within +-2 % of 0.5 m/s, every "
        f"other simulation with passengers as above), {draws} noise and speed-wander draws on each (noise "
        f"alternately {1e6 * NOISE:g} and {1e6 * FIELD_NOISE:g} um). *rate* must not exceed *stated* by more than "
        "two binomial sigmas (*within*). *under the minimum excess*: recordings where a link passed the "
        f"statistical threshold with an excess under {1e3 * MIN_EXCESS_M:g} mm (not flagged). Recordings refused "
        "(the phase could not be followed): "
        f"{len(REFUSED)}.\n\n"
        "A step accelerometer: `bench_links_step.py` (`links_step.md`).\n"
    )


def _plot(rows, path):
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, ax = plt.subplots(figsize=(6.4, 3.8))
    sets = sorted({(r["load"], r["noise [um]"], r["loops"]) for r in rows})
    for load, noise, loops in sets:
        rs = [r for r in rows if (r["load"], r["noise [um]"], r["loops"]) == (load, noise, loops)]
        style = "s--" if load == "passengers" else ("o-" if noise < 1.2 else "^:")
        label = f"{loops} loops, {noise:g} um" + (", passengers" if load == "passengers" else "")
        ax.plot([r["excess [mm]"] for r in rs], [r["right link alone"] for r in rs], style, label=label)
    ax.set_xscale("log")
    ax.set_xlabel("excess pitch of one link [mm]")
    ax.set_ylabel("probability: the worn link, alone")
    ax.axhline(0.9, color="0.6", lw=0.8, ls="--")
    ax.set_ylim(-0.02, 1.02)
    ax.legend(fontsize=7)
    ax.grid(alpha=0.3)
    fig.tight_layout()
    path.parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(path, dpi=110)


if __name__ == "__main__":
    main()
