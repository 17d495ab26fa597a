"""What a step accelerometer shows of a worn link, and why ``vibkit links`` refuses it.

``sim/thesis-forward.toml`` (no load, 0.5 m/s, 159 links), the accelerometer on step 20, exact closure,
three loops after one loop of settling, sampled at 200 Hz: healthy, and with link 40, 70 or 100 one
millimetre long.  Every comparison is made at the same sprocket angle (one loop: ``2 pi n / Z`` of it), not
at the same time, so that a slow drift of the chain's phase is not counted as a change.

1. The raw samples and the same low-passed at 15 Hz (4th-order Butterworth, zero phase; four link-pass
   harmonics): the healthy step's change from one loop to the next, where it sits (the share of it in the
   5 % of samples where the acceleration jumps most from one sample to the next), and what a worn link
   changes.
2. The best case a model could give: the simulated healthy step's own loop subtracted from the recording's
   mean loop (the same simulator, the same sprocket-angle clock), and the change of every possible worn
   link fitted, link by link.  The changes come from two runs that give every roller's acceleration
   (healthy, and link 1 worn): a step ``k`` links behind a worn link sees what roller ``k`` links behind
   link 1 sees, one link pass of sprocket angle later per roller.  10 noise draws (5 mm/s^2, the
   must-show's level) per recording: the link read and its fitted excess.

3. What a step sees without a model of its trip: the same link-pass cycle compared with its neighbours (the
   loop's mean cycle minus the median of the eight cycles around it), which takes out the step's own slow
   trip and leaves what changes from one cycle to the next: the curves' ends, and a worn link passing the
   sprocket.  The cycles where the healthy step's own deviation exceeds ``BLIND`` cannot show a link; in the
   others a template of the worn link's deviation (from a run with link ``TEMPLATE_LINK`` worn, a link that
   passes the sprocket while step 20 is on straight track) is fitted, and its chi-square compared with the
   threshold of a 1e-2 false alarm over the cycles tested.

4. Where a step sees a worn link, by its number and its excess (noise-free, the sprocket's clock): the place
   moves with the excess, so a step cannot number a link whose excess it does not know.

Writes ``links_step.md`` (``--quick``: 3 draws, ``links_step_quick.md``).
"""

from __future__ import annotations

import argparse
import dataclasses
import time

import numpy as np

from _common import RESULTS, machine, markdown_table, today, write_text

SCENE = "sim/thesis-forward.toml"
SPEED = 0.5
FS = 200.0
STEP = 20
LOOPS = 3
WORN = (40, 70, 100)
EXCESS = 1e-3  # [m]
NOISE = 5e-3  # step accelerometer noise of the must-show [m/s^2]
CUTOFF = 15.0  # [Hz]
GRID = 4000  # points per loop of sprocket angle
PER_CYCLE = 16  # samples per link-pass cycle in the local test
AROUND = 4  # cycles on each side that the local test compares a cycle with
WINDOW = (-1, 3)  # the cycles (from, to) around a link's pass of the sprocket that its template spans
BLIND = 0.5e-3  # healthy deviation from the neighbours above which a cycle cannot show a worn link [m/s^2]
TEMPLATE_LINK = 52
LOCAL_DRAWS = 100


def run(scene, *, worn=None, loops=LOOPS, every_roller=False, excess=EXCESS):
    """Time, sprocket angle (growing) and the step's acceleration (or every roller's, along its velocity)
    from the end of the settling loop on."""
    import vibkit

    n, pitch = scene.chain.n_rollers, scene.chain.link_pitch
    settle = n * pitch / SPEED + 5.0
    duration = settle + (loops * n + 3) * pitch / SPEED
    variables = ("accel_step", "sprocket_angle")
    outputs = dict(scene.outputs, variables=variables, step_accelerometer=STEP)
    if every_roller:
        outputs.update(variables=variables + ("roller_velocity", "roller_acceleration"), rollers=tuple(range(1, n + 1)))
    sc = dataclasses.replace(scene, outputs=outputs).with_solver(closure="exact")
    if worn is not None:
        sc = dataclasses.replace(sc, chain=dataclasses.replace(scene.chain, worn_links=((worn, pitch + excess),)))
    ds = vibkit.simulate(sc, duration=duration, progress=False)
    t = ds.time.values
    keep = t >= settle - 1.0
    theta = np.abs(ds.sprocket_angle.values[keep] - ds.sprocket_angle.values[0])
    if every_roller:
        v, a = ds.roller_velocity.values[keep], ds.roller_acceleration.values[keep]
        acc = np.sum(a * v, axis=-1) / np.linalg.norm(v, axis=-1)
    else:
        acc = ds.accel_step.values[keep]
    return t[keep], theta, acc, settle


def lowpass(x):
    from scipy import signal

    sos = signal.butter(4, CUTOFF, fs=FS, output="sos")
    return signal.sosfiltfilt(sos, x, axis=0)


def on_loop(theta, x, start, loop):
    """``x`` (sampled at sprocket angle ``theta``) on ``GRID`` angles from ``start``, one loop, wrapped into
    the angles ``theta`` covers."""
    q = start + np.linspace(0.0, loop, GRID, endpoint=False)
    q = theta[0] + (q - theta[0]) % loop
    return np.interp(q, theta, x)


def loops_of(theta, x, start, loop, count):
    """``count`` consecutive loops of ``x`` from sprocket angle ``start``."""
    g = np.linspace(0.0, loop, GRID, endpoint=False)
    return np.array([np.interp(start + k * loop + g, theta, x) for k in range(count)])


def raw_and_filtered(runs, loop, start):
    """Rows: the healthy step's loop-to-loop change and a worn link's change, raw and low-passed."""
    rows = []
    for label, f in (("raw samples", lambda x: x), (f"low-passed at {CUTOFF:g} Hz", lowpass)):
        t, th, a, _ = runs[None]
        h = loops_of(th, f(a), start, loop, LOOPS)
        change = np.diff(h, axis=0).ravel()
        raw = loops_of(th, a, start, loop, LOOPS)
        jump = np.abs(np.gradient(raw, axis=1)).ravel()[: change.size]
        big = jump >= np.quantile(jump, 0.95)
        row = {
            "signal": label,
            "healthy r.m.s. [m/s^2]": round(float(np.std(h)), 4),
            "healthy loop to loop r.m.s.": round(float(np.std(change)), 4),
            "max": round(float(np.max(np.abs(change))), 4),
            "share at the 5 % sharpest samples": f"{np.sum(change[big] ** 2) / np.sum(change**2):.0%}",
        }
        for w in WORN:
            tw, thw, aw, _ = runs[w]
            d = loops_of(thw, f(aw), start, loop, LOOPS) - h
            row[f"link {w} - healthy r.m.s."] = round(float(np.std(d)), 4)
            row[f"link {w} max"] = round(float(np.max(np.abs(d))), 4)
        rows.append(row)
    return rows


def template_trial(scene, runs, loop, start, draws, rng):
    """The best case: the simulated healthy loop subtracted, every worn link's change fitted."""
    from vibkit.model.escalator import EscalatorModel

    n, teeth = scene.chain.n_rollers, scene.sprocket.teeth
    per_link = 2 * np.pi / teeth
    mid = int(EscalatorModel(scene).step_rollers(STEP)[1])  # 0-based roller of the step's accelerometer
    _, th_h, a_h, _ = run(scene, loops=1, every_roller=True)
    _, th_w, a_w, _ = run(scene, worn=1, loops=1, every_roller=True)
    a_h, a_w = lowpass(a_h), lowpass(a_w)
    healthy = on_loop(th_h, a_h[:, mid], start, loop)
    # row k: the change that link (mid + 1 - k) worn makes at the step (roller k behind link 1 in the run)
    sig = np.empty((n, GRID))
    for k in range(n):
        at = start - (k - mid) * per_link
        sig[k] = on_loop(th_w, a_w[:, k], at, loop) - on_loop(th_h, a_h[:, k], at, loop)
    link_of_row = (mid + 1 - np.arange(n)) % n
    link_of_row[link_of_row == 0] = n
    unit = sig / EXCESS
    norm = np.sum(unit * unit, axis=1)
    neighbour = [float(np.corrcoef(sig[k], sig[(k + 1) % n])[0, 1]) for k in range(n)]
    rows = []
    for worn in (None,) + WORN:
        t, th, a, _ = runs[worn]
        found = []
        for _ in range(draws):
            rec = lowpass(a + NOISE * rng.standard_normal(a.size))
            resid = loops_of(th, rec, start, loop, LOOPS).mean(axis=0) - healthy
            excess = unit @ resid / norm
            k = int(np.argmax(excess))
            found.append((int(link_of_row[k]), 1e3 * float(excess[k])))
        links = [f for f, _ in found]
        mode = max(set(links), key=links.count)
        rows.append(
            {
                "recording": "healthy" if worn is None else f"link {worn}, 1 mm",
                "draws": draws,
                "link read (times)": ", ".join(f"{k} ({links.count(k)})" for k in sorted(set(links))),
                "right": "-" if worn is None else f"{links.count(worn)} of {draws}",
                "excess read [mm]": f"{min(e for _, e in found):.2f}-{max(e for _, e in found):.2f}",
                "most read": mode,
            }
        )
    return rows, float(np.median(neighbour))


def cycles_of(th, a, start, n, per, noise=0.0, rng=None):
    """The low-passed step acceleration on ``PER_CYCLE`` sprocket angles of each link pass (``per`` radians),
    ``LOOPS`` loops from ``start``. (L, n, M)"""
    if noise:
        a = a + noise * rng.standard_normal(a.size)
    g = start + np.arange(LOOPS * n * PER_CYCLE) * per / PER_CYCLE
    return np.interp(g, th, lowpass(a)).reshape(LOOPS, n, PER_CYCLE)


def local_deviation(m, skip=None):
    """Each cycle minus the median of the ``AROUND`` cycles on each side of it (axis -2 the cycles, wrapped);
    with ``skip`` (n,) the mean of those not skipped (linear in the noise: a median's bias where the neighbours
    differ grows with the noise)."""
    n = m.shape[-2]
    ref = np.empty_like(m)
    for c in range(n):
        around = [(c + j) % n for j in range(-AROUND, AROUND + 1) if j != 0]
        if skip is None:
            ref[..., c, :] = np.median(m[..., around, :], axis=-2)
        else:
            kept = [k for k in around if not skip[k]] or around
            ref[..., c, :] = np.mean(m[..., kept, :], axis=-2)
    return m - ref


def _windows(d, n):
    """Every cycle's window (``WINDOW``) of ``d`` (n, M), flattened. (n, W M)"""
    return np.stack([np.concatenate([d[(c + j) % n] for j in range(*WINDOW)]) for c in range(n)])


def local_trial(scene, runs, start, draws, rng):
    """The local test: blind cycles, the template's fit at every other cycle, the link read."""
    from scipy import stats

    n, per = scene.chain.n_rollers, 2 * np.pi / scene.sprocket.teeth
    _, th, a, _ = runs[None]
    h0 = local_deviation(cycles_of(th, a, start, n, per).mean(axis=0))  # the median of the neighbours
    blind_cycle = np.sqrt(np.mean(h0**2, axis=1)) > BLIND
    blind = np.array([any(blind_cycle[(c + j) % n] for j in range(*WINDOW)) for c in range(n)])
    h0 = local_deviation(cycles_of(th, a, start, n, per).mean(axis=0), blind_cycle)
    _, th_t, a_t, _ = run(scene, worn=TEMPLATE_LINK)
    dt = _windows(local_deviation(cycles_of(th_t, a_t, start, n, per).mean(axis=0), blind_cycle) - h0, n)
    c_t = int(np.argmax(np.where(blind, 0.0, np.sum(dt**2, axis=1))))
    u = dt[c_t] / np.linalg.norm(dt[c_t])
    # links pass the sprocket in decreasing number: link w's window starts (w - TEMPLATE_LINK) cycles before c_t
    cycle_of = {w: (c_t - (w - TEMPLATE_LINK)) % n for w in WORN}
    tested = int(np.count_nonzero(~blind))
    threshold = float(stats.chi2.isf(1.0 - (1.0 - 1e-2) ** (1.0 / tested), 1))
    rows = []
    facts = {
        "blind": int(np.count_nonzero(blind)),
        "blind cycles": int(np.count_nonzero(blind_cycle)),
        "threshold": threshold,
        "tested": tested,
        "n": n,
        "draws": draws,
    }
    for worn in (None,) + WORN:
        _, th, a, _ = runs[worn]
        found, at_link, variances, noise_mean = [], [], [], []
        for _ in range(draws):
            per_loop = local_deviation(cycles_of(th, a, start, n, per, NOISE, rng), blind_cycle)
            z = np.stack([_windows(x, n) @ u for x in per_loop])  # the template's fit in each loop (L, n)
            # the fit's noise from its scatter over the loops (the low-pass correlates neighbouring samples), the
            # median over the cycles: unbiased for a chi-square with L - 1 degrees of freedom
            var = np.median(np.var(z, axis=0, ddof=1)) / stats.chi2.median(LOOPS - 1) * (LOOPS - 1) / LOOPS
            chi = z.mean(axis=0) ** 2 / var
            variances.append(var)
            chi[blind] = np.nan
            noise_mean.append(float(np.nanmean(chi)))
            c = int(np.nanargmax(chi))
            found.append(((TEMPLATE_LINK + c_t - c - 1) % n + 1, float(chi[c])))
            if worn is not None:
                at_link.append(float(chi[cycle_of[worn]]))
        links = [f for f, _ in found]
        over = sum(x > threshold for _, x in found)
        clean = (_windows(local_deviation(cycles_of(th, a, start, n, per).mean(axis=0), blind_cycle), n) @ u) ** 2
        clean = np.where(blind, np.nan, clean / np.median(variances))
        if worn is None:
            facts["healthy mean"] = float(np.mean(noise_mean))
            facts["healthy over"] = over
            facts["healthy clean"] = float(np.nanmax(clean))
        rows.append(
            {
                "recording": "healthy" if worn is None else f"link {worn}, 1 mm",
                "seen": "-" if worn is None else ("no (blind)" if blind[cycle_of[worn]] else "yes"),
                "draws": draws,
                "largest chi-square": f"{min(x for _, x in found):.0f}-{max(x for _, x in found):.0f}",
                "largest without noise": f"{np.nanmax(clean):.1f}",
                "over the threshold": f"{over} of {draws}",
                "its link right": "-" if worn is None else f"{links.count(worn)} of {draws}",
                "chi-square at the link": "-"
                if worn is None or blind[cycle_of[worn]]
                else f"{min(at_link):.0f}-{max(at_link):.0f}",
            }
        )
    return rows, facts


#: (link, excess [m]) of the runs that show where a step sees a worn link
SHIFT_CASES = ((40, 0.5e-3), (40, 0.75e-3), (40, 1e-3), (40, 1.25e-3), (40, 1.5e-3), (40, 2e-3), (70, 1e-3), (70, 2e-3))


def shift_trial(scene, runs, start, quick=False):
    """Where in the loop (cycles of sprocket angle) a worn link changes the step most, by link and excess: the
    loops' mean cycle minus the median of its neighbours, the healthy run's taken away, the blind cycles left
    out; the largest cycle and the largest at least ``SEPARATE`` cycles from it."""
    n, per = scene.chain.n_rollers, 2 * np.pi / scene.sprocket.teeth
    _, th, a, _ = runs[None]
    h = local_deviation(cycles_of(th, a, start, n, per).mean(axis=0))
    blind = np.sqrt(np.mean(h**2, axis=1)) > BLIND
    rows, first = [], {}
    for link, excess in SHIFT_CASES[:3] if quick else SHIFT_CASES:
        _, thw, aw, _ = runs[link] if excess == EXCESS and link in runs else run(scene, worn=link, excess=excess)
        d = local_deviation(cycles_of(thw, aw, start, n, per).mean(axis=0)) - h
        size = np.where(blind, 0.0, np.sqrt(np.mean(d**2, axis=1)))
        c1 = int(np.argmax(size))
        away = np.abs((np.arange(n) - c1 + n // 2) % n - n // 2) >= SEPARATE
        c2 = int(np.argmax(np.where(away, size, 0.0)))
        first.setdefault(link, c1)
        rows.append(
            {
                "worn link": link,
                "excess [mm]": 1e3 * excess,
                "largest change at cycle": c1,
                "its size [mm/s^2]": round(1e3 * float(size[c1]), 2),
                "second place at cycle": c2,
                "its size": round(1e3 * float(size[c2]), 2),
            }
        )
    return rows


#: cycles between the two places a worn link shows at (its passes of the sprocket and of the lower head)
SEPARATE = 20


def main():
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--quick", action="store_true", help="3 noise draws a recording")
    a = p.parse_args()
    from vibkit.model.scene import load_scene

    t0 = time.process_time()
    scene = load_scene(SCENE)
    n, teeth = scene.chain.n_rollers, scene.sprocket.teeth
    loop = 2 * np.pi * n / teeth
    runs = {w: run(scene, worn=w) for w in (None,) + WORN}
    _, th, _, settle = runs[None]
    t = runs[None][0]
    start = float(np.interp(settle, t, th))  # the first loop after the settling, by sprocket angle
    rng = np.random.default_rng(29)
    draws = 3 if a.quick else 10
    first = raw_and_filtered(runs, loop, start)
    trial, neighbour = template_trial(scene, runs, loop, start, draws, rng)
    local, facts = local_trial(scene, runs, start, 5 if a.quick else LOCAL_DRAWS, rng)
    shifts = shift_trial(scene, runs, start, a.quick)
    suffix = "_quick" if a.quick else ""
    text = _report(suffix, first, trial, neighbour, time.process_time() - t0, local, facts, shifts)
    write_text(RESULTS / f"links_step{suffix}.md", text)
    print(text)


def _report(suffix, first, trial, neighbour, cpu, local, facts, shifts):
    raw, low = first
    worn = [low[f"link {w} - healthy r.m.s."] for w in WORN]
    low_worn = ", ".join(f"{v}" for v in worn) + " m/s^2 r.m.s."
    low_ratio, high_ratio = (
        min(worn) / low["healthy loop to loop r.m.s."],
        max(worn) / low["healthy loop to loop r.m.s."],
    )
    healthy = next(r for r in trial if r["recording"] == "healthy")
    return (
        f"# bench_links_step{suffix}\n\n{machine()}; {today()}; CPU {cpu:.0f} s\n\n"
        f"`{SCENE}` ({SPEED} m/s), the accelerometer on step {STEP}, exact closure, {LOOPS} loops after one loop "
        f"of settling, {FS:g} Hz; worn links {', '.join(map(str, WORN))}, {1e3 * EXCESS:g} mm each, one at a "
        "time. Loops compared at the same sprocket angle.\n\n"
        "## The healthy step from loop to loop, and a worn link\n\n"
        + markdown_table(first)
        + "\n\n*share at the 5 % sharpest samples*: the part of the loop-to-loop change (its sum of squares) that "
        "falls on the 5 % of samples where the raw acceleration changes most from one sample to the next: the "
        "jumps where the step enters and leaves a curve and where a roller meets a tooth, which a few "
        f"milliseconds of phase move from one sample to the next. Low-passed, the healthy step's change falls from "
        f"{raw['healthy loop to loop r.m.s.']} to {low['healthy loop to loop r.m.s.']} m/s^2 r.m.s. (at most "
        f"{raw['max']} to {low['max']}), and a worn link's change ({low_worn}) is "
        f"{low_ratio:.1f} to {high_ratio:.1f} times the healthy step's own, in r.m.s.\n\n"
        "## The best case a model could give\n\n"
        f"The simulated healthy step's own loop subtracted from the recording's mean loop, and every link's change "
        f"fitted; {NOISE * 1e3:g} mm/s^2 of noise, low-passed at {CUTOFF:g} Hz. *link read*: the link whose change "
        "fits with the largest excess.\n\n"
        + markdown_table(trial)
        + f"\n\nThe changes of neighbouring links correlate at {neighbour:.3f} (median over the links), so the "
        "number is unsure by a link or two even here; and the healthy step, its own simulated loop subtracted, "
        f"still reads a worn link of {healthy['excess read [mm]']} mm: the simulated step does not repeat itself "
        "from loop to loop to better than that. On an escalator the healthy step's loop would come from a model of "
        f"that escalator, whose trip (the step's own acceleration, {low['healthy r.m.s. [m/s^2]']} m/s^2 r.m.s. "
        f"here) no model predicts to the {min(worn)} m/s^2 r.m.s. a millimetre changes. The tensioner needs no "
        "such pattern: it sees every link at the same place, and its links are compared with one another.\n\n"
        "## Without a model of the trip: each cycle against its neighbours\n\n"
        f"Each link-pass cycle of the loops' mean ({PER_CYCLE} samples, low-passed) minus its {2 * AROUND} "
        "neighbours takes out the step's own slow trip and the few milliseconds by which a worn link moves the "
        "trip against the sprocket's clock; what is left is what changes from one cycle to the next. On the "
        f"healthy step {facts['blind cycles']} of {facts['n']} cycles deviate from the median of their neighbours "
        f"by more than {BLIND * 1e3:g} mm/s^2 r.m.s.: the ends of the curves the step rides through, which come "
        "back every loop as a worn link would. They are *blind*; the other cycles are compared with the mean of "
        "their neighbours that are not blind (linear in the noise). A worn link passing the sprocket while the "
        "step is on straight track adds 2-3 mm/s^2 r.m.s. over two or three cycles. Its template (the run with "
        f"link {TEMPLATE_LINK} worn; cycles {WINDOW[0]} to {WINDOW[1] - 1} around its pass) is fitted at every "
        f"cycle whose window holds no blind cycle ({facts['tested']} of {facts['n']}: the other {facts['blind']} "
        f"links cannot be seen from this step), with {NOISE * 1e3:g} mm/s^2 of noise; the fit's noise from its "
        "scatter over the loops; chi-square with one degree of freedom, threshold "
        f"{facts['threshold']:.1f} for a false alarm of 1e-2 over the cycles tested.\n\n"
        + markdown_table(local)
        + "\n\n*largest without noise*: the same fit on the recording without noise (the step's own trip left "
        f"beside the blind cycles, and the worn link). The healthy step leaves {facts['healthy clean']:.1f}; with "
        f"noise its fit's chi-square averages {facts['healthy mean']:.2f} over the cycles tested, and its largest "
        f"passes the threshold in {facts['healthy over']} of {facts['draws']} draws. A 1 mm link whose pass of the "
        "sprocket the step sees stands far out, its number right. But the links whose pass falls where the step "
        "rides through a curve's end are not seen at all: one step covers part of the chain (here link 40, not 70 "
        "or 100), and which part depends on the step and on the guide. This is the path a step sensor could take: "
        "the template, the blind cycles and the threshold from the escalator's scene (simulated healthy "
        "recordings, not the chi-square alone, for a stated false alarm), the step's place in the loop found from "
        "its trip, and a second step for the links the first cannot see.\n\n"
        "## Where a step sees a worn link: its number and its excess together\n\n"
        "The same comparison without noise, by the sprocket's own angle (so no clock of the recording's is in "
        "question), for link 40 from 0.5 to 2 mm and link 70 at 1 and 2 mm: the cycle where the worn link "
        "changes the step most, and the largest change at least "
        f"{SEPARATE} cycles from it (the blind cycles left out).\n\n"
        + markdown_table(shifts)
        + "\n\nOne millimetre more moves both places by about the same number of cycles as a worn link "
        "numbered that much higher would, and the chain does not slip: the rollers of the 0, 1 and 2 mm runs are "
        "within 5 mm of each other at 50 s (measured while building a step path). So the step alone cannot tell "
        "a link's number from its excess. A step path that fits every link's change as a 1 mm link makes it "
        "(commit `42560c4`, withdrawn; its clock followed the speed by the step's trip) numbered 1 mm links 40, "
        "70 and 100 right from step 20 in 96 to 97 of 100 draws each, but a 2 mm link 40 as link 52 or 53 and a "
        "0.5 mm one as link 25, as confidently; templates for every excess from 0.25 to 3 mm fitted together "
        "chose a wrong pair of number and excess even without noise. `vibkit links` refuses a step "
        "accelerometer. The tensioner sees every link at the same place: its flagged number is right at every "
        "excess from 0.1 to 3 mm (`links.md`).\n"
    )


if __name__ == "__main__":
    main()
