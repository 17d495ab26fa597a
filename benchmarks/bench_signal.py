"""Benchmark of vibkit.signal: speed against baselines, and estimator accuracy against the CRB.

Run:  python benchmarks/bench_signal.py [--quick]

Writes (atomically) into benchmarks/results/:
  signal_benchmark.csv, signal_benchmark.md        speed, with machine info and date
  signal_estimator_accuracy.csv, .png              RMS error vs record length and vs SNR, with CRB

Baselines run in the same process, side by side: the ``hampel`` package from PyPI (install the
``bench`` extra), ``scipy.ndimage.median_filter``, ``scipy.sparse.linalg.spsolve``.
Timings are the best of several repeats after a warm-up (numba compilation excluded).
"""

from __future__ import annotations

import argparse
import csv
import datetime
import io
import os
import platform
import sys
import tempfile
import time
from pathlib import Path

import numpy as np
import scipy.linalg
import scipy.ndimage
import scipy.sparse.linalg
from numpy.lib.stride_tricks import sliding_window_view

import vibkit.signal as vs
from vibkit.signal.kernels import _vk_solve
from vibkit.signal.orders import _vk_banded, _vk_sparse

from _common import support

RESULTS = Path(os.environ.get("VIBKIT_BENCH_RESULTS") or Path(__file__).resolve().parent / "results")  # see _common.py


def atomic_write(path: Path, data: bytes) -> None:
    path.parent.mkdir(parents=True, exist_ok=True)
    fd, tmp = tempfile.mkstemp(dir=path.parent, prefix=path.name + ".", suffix=".tmp")
    try:
        with os.fdopen(fd, "wb") as fh:
            fh.write(data)
        os.chmod(tmp, 0o644)
        os.replace(tmp, path)
    except BaseException:
        if os.path.exists(tmp):
            os.unlink(tmp)
        raise


def best_time(fn, repeat=5):
    ts = []
    for _ in range(repeat):
        t0 = time.perf_counter()
        fn()
        ts.append(time.perf_counter() - t0)
    return min(ts)


def machine_info():
    import numba

    return {
        "date": datetime.datetime.now(datetime.timezone.utc).isoformat(timespec="seconds"),
        "machine": f"{platform.machine()} {platform.processor() or ''}".strip(),
        "cpus": os.cpu_count(),
        "numba_threads": numba.get_num_threads(),
        "python": platform.python_version(),
        "numpy": np.__version__,
        "scipy": scipy.__version__,
        "load_avg_1min_at_start": round(os.getloadavg()[0], 2),
    }


def ndimage_hampel(x, k, n_sigma):
    """Exact Hampel from scipy.ndimage.median_filter (median) + sliding windows (MAD)."""
    w = 2 * k + 1
    med = scipy.ndimage.median_filter(x, size=w, mode="nearest")
    for i in list(range(k)) + list(range(x.size - k, x.size)):  # truncated windows at the ends
        med[i] = np.median(x[max(0, i - k) : i + k + 1])
    pad = np.pad(x, k, mode="constant", constant_values=np.nan)
    dev = np.abs(sliding_window_view(pad, w) - med[:, None])
    sig = 1.4826 * np.nanmedian(dev, axis=1)
    out = np.abs(x - med) > n_sigma * sig
    return np.where(out, med, x), out


def bench_hampel(rows, quick):
    try:
        from hampel import hampel as pypi_hampel
    except ImportError:
        pypi_hampel = None
        print("hampel package not installed: pip install -e '.[bench]'", file=sys.stderr)
    rng = np.random.default_rng(0)
    vs.hampel(rng.standard_normal(100_000), 3, 3.0)  # compile
    for n in (100_000,) if quick else (100_000, 1_000_000):
        x = rng.standard_normal(n)
        x[::1000] += 20.0
        t_ours = best_time(lambda: vs.hampel(x, 3, 3.0))
        t_mf = best_time(lambda: scipy.ndimage.median_filter(x, size=7))
        t_ndh = best_time(lambda: ndimage_hampel(x, 3, 3.0), repeat=2)
        rows.append(("hampel", n, "vibkit.signal.hampel (k=3)", t_ours, 1.0))
        rows.append(("hampel", n, "scipy.ndimage.median_filter alone (size 7)", t_mf, t_mf / t_ours))
        rows.append(("hampel", n, "Hampel via ndimage.median_filter + sliding MAD", t_ndh, t_ndh / t_ours))
        if pypi_hampel is not None and not (quick and n > 100_000):
            xf = x.astype(np.float32)
            t_pkg = best_time(lambda: pypi_hampel(xf, window_size=7, n_sigma=3.0), repeat=1)
            rows.append(("hampel", n, "hampel 1.0.2 (PyPI, window_size=7)", t_pkg, t_pkg / t_ours))
        import numba

        nt = numba.get_num_threads()
        numba.set_num_threads(1)
        try:
            t_one = best_time(lambda: vs.hampel(x, 3, 3.0))
        finally:
            numba.set_num_threads(nt)
        rows.append(("hampel", n, "vibkit.signal.hampel, 1 thread", t_one, t_one / t_ours))


def bench_vk(rows, quick):
    rng = np.random.default_rng(1)
    fs = 2050.0
    for seconds in (60, 600):
        n = int(seconds * fs)
        y = rng.standard_normal(n) + 1j * rng.standard_normal(n)
        r2 = vs.orders.vk_bandwidth_to_r(0.5, fs) ** 2
        _vk_solve(y[:100], r2)
        rhs = np.column_stack([y.real, y.imag])
        t_penta = best_time(lambda: _vk_solve(y, r2))
        t_band = best_time(lambda: scipy.linalg.solveh_banded(_vk_banded(n, r2), rhs, check_finite=False), repeat=3)
        t_sp = best_time(lambda: scipy.sparse.linalg.spsolve(_vk_sparse(n, r2), rhs), repeat=2)
        label = f"VK system n={n}"
        rows.append(("vold_kalman_solve", n, "pentadiagonal LDL^T (numba), default", t_penta, 1.0))
        rows.append(("vold_kalman_solve", n, "scipy.linalg.solveh_banded", t_band, t_band / t_penta))
        rows.append(("vold_kalman_solve", n, "scipy.sparse.linalg.spsolve (incl. matrix build)", t_sp, t_sp / t_penta))
        t = np.arange(n) / fs
        phi = 2 * np.pi * 3.75 * t
        x = np.cos(phi) + rng.standard_normal(n)
        # 0.7 Hz: the narrowest band vold_kalman accepts at 2050 Hz is 0.65 Hz (condition number 1e12)
        t_full = best_time(lambda: vs.vold_kalman(x, fs, phi, bandwidth_hz=0.7), repeat=3)
        t_full_sp = best_time(lambda: vs.vold_kalman(x, fs, phi, bandwidth_hz=0.7, solver="sparse"), repeat=2)
        rows.append(("vold_kalman_call", n, "vold_kalman(), default solver", t_full, 1.0))
        rows.append(("vold_kalman_call", n, "vold_kalman(solver='sparse')", t_full_sp, t_full_sp / t_full))
        del label
        if quick:
            break


def synthetic_recording(seconds, fs, seed=2):
    rng = np.random.default_rng(seed)
    t = np.arange(int(seconds * fs)) / fs
    f_inst = 3.75 * (1 + 0.005 * np.sin(2 * np.pi * t / 40))
    phi = 2 * np.pi * np.cumsum(f_inst) / fs
    axes = []
    for a in range(3):
        s = support.chain.family_of_phase(phi, (1.0 - 0.2 * a, 0.5, 0.2), phases=(0, a, 0))
        x = s + rng.standard_normal(t.size) * np.std(s)
        x[rng.integers(0, t.size, 50)] += 20.0  # knocks
        axes.append(x)
    return axes


def bench_pipeline(rows, quick):
    fs = 2050.0
    seconds = 10.0 if quick else 600.0
    axes = synthetic_recording(60.0, fs)  # warm-up / compile on a short record
    pipeline(axes, fs)
    axes = synthetic_recording(seconds, fs)
    stages = {}
    t0 = time.perf_counter()
    pipeline(axes, fs, stages)
    total = time.perf_counter() - t0
    n = axes[0].size
    for name, t in stages.items():
        rows.append(("pipeline_stage", n, name, t, t / total))
    rows.append(("pipeline", n, f"{seconds:.0f} s x 3 axes at {fs:.0f} Hz: all stages", total, 1.0))


def pipeline(axes, fs, stages=None):
    stages = {} if stages is None else stages

    def timed(name, fn):
        t0 = time.perf_counter()
        out = fn()
        stages[name] = stages.get(name, 0.0) + time.perf_counter() - t0
        return out

    cleaned = []
    for x in axes:
        clean = timed("hampel (3 axes)", lambda: vs.hampel(x, 3, 3.0).filtered)
        timed("amplitude_spectrum (3 axes)", lambda: vs.amplitude_spectrum(clean, fs))
        timed("welch_psd (3 axes)", lambda: vs.welch_psd(clean, fs, nperseg=8192))
        timed("spectrogram (3 axes)", lambda: vs.spectrogram(clean, fs, nperseg=8192))
        cleaned.append(clean)
    # One chain, one link-pass phase: tracked on the first axis, used to order-track all three.
    tr = timed("track_phase (axis 0)", lambda: vs.track_phase(cleaned[0], fs, band=(2.0, 6.0)))
    for clean in cleaned:
        ang = timed(
            "resample_to_angle (3 axes)", lambda: vs.resample_to_angle(clean, fs, tr.phase_rad, samples_per_cycle=32)
        )
        timed("order_spectrum (3 axes)", lambda: vs.order_spectrum(ang))
    timed("link_pass_estimate (axis 0)", lambda: vs.link_pass_estimate(cleaned[0], fs, band=(2.0, 6.0), n_harmonics=3))


def accuracy(quick):
    """RMS frequency error of both estimators vs record length and SNR, against the CRBs."""
    fs = 256.0
    amps = np.array([1.0, 0.6, 0.3])
    f0 = 3.7512
    trials = 10 if quick else 300
    rng = np.random.default_rng(3)
    out = []

    def run(seconds, snr_db):
        n = int(seconds * fs)
        t = np.arange(n) / fs
        noise = np.sqrt(np.sum(amps**2) / 2 / 10 ** (snr_db / 10))
        e_ls, e_idft = [], []
        for _ in range(trials):
            ph = rng.uniform(0, 2 * np.pi, amps.size)
            x = sum(a * np.cos(2 * np.pi * (k + 1) * f0 * t + p) for k, (a, p) in enumerate(zip(amps, ph)))
            x = x + noise * rng.standard_normal(n)
            ide = vs.interpolated_dft(x, fs, band=(2.0, 6.0))
            e_idft.append(ide.frequency_hz - f0)
            ls = vs.harmonic_ls(x, fs, f_guess=ide.frequency_hz, n_harmonics=amps.size)
            e_ls.append(ls.frequency_hz - f0)
        crb_h = vs.crb_harmonic(n, fs, amps, noise)
        crb_1 = vs.crb_single_tone(n, fs, amps[0] ** 2 / 2 / noise**2)
        return {
            "seconds": seconds,
            "snr_db": snr_db,
            "n": n,
            "trials": trials,
            "rms_harmonic_ls_hz": float(np.sqrt(np.mean(np.square(e_ls)))),
            "crb_harmonic_hz": crb_h,
            "rms_interpolated_dft_hz": float(np.sqrt(np.mean(np.square(e_idft)))),
            "crb_single_tone_hz": crb_1,
        }

    for seconds in (2, 5, 10, 20, 60):
        out.append(dict(sweep="length", **run(seconds, 0.0)))
    for snr in (-15, -10, -5, 0, 10, 20):
        out.append(dict(sweep="snr", **run(10.0, float(snr))))
    return out


def write_accuracy(acc, suffix=""):
    buf = io.StringIO()
    w = csv.DictWriter(buf, fieldnames=list(acc[0].keys()))
    w.writeheader()
    w.writerows(acc)
    atomic_write(RESULTS / f"signal_estimator_accuracy{suffix}.csv", buf.getvalue().encode())
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, axs = plt.subplots(1, 2, figsize=(10, 4))
    for ax, sweep, key, label in (
        (axs[0], "length", "seconds", "record length [s]"),
        (axs[1], "snr", "snr_db", "SNR [dB]"),
    ):
        rows = [r for r in acc if r["sweep"] == sweep]
        xv = [r[key] for r in rows]
        ax.semilogy(xv, [r["rms_harmonic_ls_hz"] for r in rows], "o-", label="harmonic LS (RMS)")
        ax.semilogy(xv, [r["crb_harmonic_hz"] for r in rows], "k--", label="harmonic CRB")
        ax.semilogy(xv, [r["rms_interpolated_dft_hz"] for r in rows], "s-", label="interpolated DFT (RMS)")
        ax.semilogy(xv, [r["crb_single_tone_hz"] for r in rows], "k:", label="single-tone CRB")
        if sweep == "length":
            from matplotlib.ticker import NullFormatter

            ax.set_xscale("log")
            ax.set_xticks(xv)
            ax.set_xticklabels([f"{v:g}" for v in xv])
            ax.xaxis.set_minor_formatter(NullFormatter())
        ax.set_xlabel(label)
        ax.set_ylabel("frequency error [Hz]")
        ax.grid(True, which="both", alpha=0.3)
    axs[0].set_title("0 dB SNR (3 harmonics, fs 256 Hz)")
    axs[1].set_title("10 s record")
    axs[0].legend(fontsize=8)
    fig.tight_layout()
    buf = io.BytesIO()
    fig.savefig(buf, format="png", dpi=110)
    plt.close(fig)
    atomic_write(RESULTS / f"signal_estimator_accuracy{suffix}.png", buf.getvalue())


def main(argv=None):
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--quick", action="store_true", help="smaller sizes and fewer trials")
    args = p.parse_args(argv)
    info = machine_info()
    rows = []
    suffix = "_quick" if args.quick else ""  # a quick run never overwrites the full results
    bench_hampel(rows, args.quick)
    bench_vk(rows, args.quick)
    bench_pipeline(rows, args.quick)
    buf = io.StringIO()
    w = csv.writer(buf)
    w.writerow(["# " + "; ".join(f"{k}={v}" for k, v in info.items())])
    w.writerow(["benchmark", "n_samples", "implementation", "seconds", "ratio_to_first_of_group"])
    for r in rows:
        w.writerow([r[0], r[1], r[2], f"{r[3]:.6g}", f"{r[4]:.4g}"])
    atomic_write(RESULTS / f"signal_benchmark{suffix}.csv", buf.getvalue().encode())
    md = ["# vibkit.signal benchmark", "", ", ".join(f"{k}: {v}" for k, v in info.items()), ""]
    md += ["| benchmark | samples | implementation | time [s] | ratio |", "|---|---:|---|---:|---:|"]
    md += [f"| {r[0]} | {r[1]:,} | {r[2]} | {r[3]:.4g} | {r[4]:.3g} |" for r in rows]
    md += [
        "",
        "Ratio: time of the row over the first row of its group (vibkit's implementation), "
        "so > 1 means vibkit is faster; pipeline stages: share of the total.",
        "",
    ]
    atomic_write(RESULTS / f"signal_benchmark{suffix}.md", "\n".join(md).encode())
    print("\n".join(md))
    acc = accuracy(args.quick)
    write_accuracy(acc, suffix)
    for r in acc:
        print(r)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
