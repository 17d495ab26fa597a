"""Report pages a firm can file: every page headed by unit, recording, date, speed and "page n of N"; the
spectrum page's peaks at the level the tables give; the time signal's zoom on a few link passes; spike counts
with what chance gives; no interval for an order not detected; page 1 says why a page is absent."""

import re
from pathlib import Path

import numpy as np
import pytest

from vibkit.diagnose.comparison import amplitude_diff_text
from vibkit.diagnose.report import write_report
from vibkit.diagnose.report.context import analyse
from vibkit.diagnose.report.signal_pages import ZOOM_CYCLES, envelope, spectrum_page, time_signal_page
from vibkit.diagnose.report.verdict import scene_pitch_text, spikes_text
from vibkit.model.profile import load_profile

E07 = "data/fleet-example/escalators/E07.toml"
E07_RECORD = "data/fleet-example/E07/2026-11-23.csv"

SPEED, PITCH = 0.65, 0.1016  # a metro unit's chain: link pass 6.398 Hz
AMPLITUDES = (22e-6, 6e-6, 3e-6)  # the tensioner's harmonics [m]


def _tensioner_csv(path, seconds=60.0, fs=100.0, noise=2e-6, seed=3):
    """A tensioner record at constant speed: three link-pass harmonics of known amplitude and white noise."""
    rng = np.random.default_rng(seed)
    t = np.arange(int(fs * seconds)) / fs
    ph = 2 * np.pi * SPEED / PITCH * t
    x = sum(a * np.cos((k + 1) * ph + k) for k, a in enumerate(AMPLITUDES)) + noise * rng.standard_normal(t.size)
    lines = ["time (s),tensioner_displacement (mm)"] + [f"{a:.3f},{1000 * b:.7f}" for a, b in zip(t, x)]
    path.write_text("\n".join(lines) + "\n")
    return path


class _Capture:
    """A page sink that keeps the figures (the artists' data are what the tests read)."""

    def __init__(self):
        self.figs = {}
        self.absent = []

    def emit(self, fig, title):
        self.figs[title] = fig


@pytest.fixture(scope="module")
def tensioner_ctx(tmp_path_factory):
    path = _tensioner_csv(tmp_path_factory.mktemp("rec") / "metro.csv")
    return analyse(path, speed=SPEED, nominal_pitch=PITCH)


def test_the_spectrum_page_draws_each_peak_at_its_tabled_amplitude(tensioner_ctx):
    """A 60 s record's lines are narrower than a 2000-point plotting grid's step: the page drew them up to 60
    times too low; the peak drawn is now the fitted amplitude (the tables', vibkit pitch's) and the truth."""
    import matplotlib.pyplot as plt

    ctx = tensioner_ctx
    doc = _Capture()
    spectrum_page(doc, ctx)
    fig = doc.figs["spectrum"]
    ax = fig.axes[0]
    assert ax.get_ylabel() == "amplitude [\u00b5m]"
    curve = next(ln for ln in ax.lines if ln.get_label() == "spectrum")
    f, a = (np.asarray(v, dtype=float) for v in curve.get_data())
    crosses = next(ln for ln in ax.lines if ln.get_label() == "fitted amplitude")
    for h, truth in zip(ctx.pitch.harmonics, AMPLITUDES):
        near = np.abs(f - h["frequency_hz"]) < 0.2 * ctx.f0
        peak = a[near].max()  # [um]
        tabled = 1e6 * h["amplitude"]
        assert peak == pytest.approx(tabled, rel=0.03), h["order"]  # flat-top: 0.1 dB; noise: 2 %
        assert peak == pytest.approx(1e6 * truth, rel=0.03), h["order"]
    # the crosses are the table's numbers themselves
    fx, ay = crosses.get_data()
    assert np.allclose(ay[:3], [1e6 * h["amplitude"] for h in ctx.pitch.harmonics[:3]])
    plt.close(fig)


def test_the_time_signal_zooms_on_a_few_link_passes(tensioner_ctx):
    import matplotlib.pyplot as plt

    ctx = tensioner_ctx
    doc = _Capture()
    time_signal_page(doc, ctx)
    fig = doc.figs["time signal"]
    overview, zoom = fig.axes
    lo, hi = zoom.get_xlim()
    assert hi - lo == pytest.approx(ZOOM_CYCLES * PITCH / SPEED, rel=1e-3)  # six link passes, 0.94 s
    assert overview.get_xlim()[1] - overview.get_xlim()[0] > 50  # the whole minute above
    # one tick a link pass
    ticks = zoom.get_xticks()
    assert np.allclose(np.diff(ticks), PITCH / SPEED, rtol=1e-3)
    plt.close(fig)


def test_a_long_signal_is_drawn_as_its_envelope_with_every_extreme_where_it_is():
    """The overview draws, in each of its columns, the column's least and largest sample at their own times: the
    line covers what every sample drawn covers (a one-sample spike included) in a few points a column."""
    rng = np.random.default_rng(5)
    t = np.arange(100_003) / 200.0
    x = rng.standard_normal(t.size)
    x[31_337] = 40.0  # a knock
    te, xe = envelope(t, x, 1000)
    assert te.size <= 2 * 1001 and np.all(np.diff(te) >= 0)  # a pair a column, in time order
    m = -(-t.size // 1000)
    for lo in range(0, t.size, m):  # each column's extremes, at their times
        col = slice(lo, lo + m)
        inside = (te >= t[col][0]) & (te <= t[col][-1])
        assert xe[inside].min() == x[col].min() and xe[inside].max() == x[col].max()
        assert set(te[inside]) == {t[col][np.argmin(x[col])], t[col][np.argmax(x[col])]}
    assert 40.0 in xe and te[np.argmax(xe)] == t[31_337]
    # a signal of at most two samples a column, or with a gap, is drawn whole
    for short in (x[:2000], np.where(t < 1.0, np.nan, x)):
        ts, xs = envelope(t[: short.size], short, 1000)
        assert ts.size == short.size


def test_spikes_are_counted_with_what_chance_gives(tensioner_ctx):
    ctx = tensioner_ctx
    # 6000 samples at 1e-4 a sample: 0.6 expected on pure noise
    assert ctx.spikes_expected == pytest.approx(6000 * 1e-4)
    text = spikes_text(ctx)
    assert "chance alone gives about 0.6" in text
    assert len(ctx.events) <= 3  # the record has no knock: at most the Poisson(0.6) 99 % bound
    assert "no more than chance alone gives" in text


def test_an_order_not_detected_gets_no_interval():
    row = {
        "detected_meas": False,
        "detected_sim": True,
        "amplitude_diff_db": -30.4,
        "amplitude_diff_db_ci": [-300, 230],
    }
    text = amplitude_diff_text(row)
    assert text == "not detected (< -30 dB)" and "[" not in text
    both = dict(row, detected_meas=True, amplitude_diff_db_ci=[-31.5, -29.3])
    assert "[" in amplitude_diff_text(both)


def test_a_scene_whose_pitch_differs_is_not_worded_as_a_fault():
    class Comp:
        pitch_ratio, pitch_ratio_sigma, pitch_consistent = 1.0382, 0.0001, False

    text = scene_pitch_text(Comp())
    assert "NOT consistent" not in text
    assert "judges the scene, not the chain" in text


@pytest.mark.slow
def test_every_page_is_headed_and_numbered(tmp_path):
    """Every page of a report of a named unit names the unit, the recording, its date and the chain speed and
    says "page n of N"; page 1 says why each absent page is absent; a glossary explains the words."""
    rep = write_report(E07_RECORD, tmp_path / "e07.pdf", profile=load_profile(E07))
    n = len(rep.pages)
    pdf_pages = len(re.findall(rb"/Type\s*/Page\b", Path(rep.path).read_bytes()))
    assert pdf_pages == n
    for i, (title, texts) in enumerate(rep.pages, 1):
        header = next((t for t in texts if t.startswith("unit E07")), None)
        assert header is not None, title
        assert "2026-11-23.csv" in header and "measured 2026-11-23" in header, title
        assert "chain speed 0.50000 +- 0.00050 m/s" in header, title
        assert f"page {i} of {n}" in texts, title
    titles = [t for t, _ in rep.pages]
    assert titles[-1] == "glossary"
    glossary = "\n".join(rep.pages[-1][1])
    for word in ("link pass", "delta", "harmonic SNR", "Birge ratio", "Hampel", "Cramer-Rao", "order spectrum"):
        assert word in glossary
    page1 = "\n".join(rep.pages[0][1])
    # no scene given: the comparison pages are absent, and page 1 says why
    assert "simulation against recording" not in titles
    assert "no simulation against recording page: no scene given" in page1
    assert "no ride quality page: recording:" in page1


def test_teeth_assumed_without_a_profile_or_scene_are_said(tensioner_ctx):
    assert any(n.startswith("sprocket teeth not known: 28 assumed") for n in tensioner_ctx.notes)
    assert not any("Z = 28" in n for n in tensioner_ctx.pitch.notes)


def test_a_derived_link_count_is_said_on_page_one_and_in_the_summary(tmp_path):
    from vibkit.diagnose.report.verdict import evidence_rows
    from vibkit.model.profile import parse_profile

    text = (
        '[escalator]\nunit = "M14"\n[drive]\nspeed = 0.65\nspeed_uncertainty = 0.0013\nteeth = 25\n'
        "[chain]\nnominal_pitch = 0.1016\nlinks_per_step = 4\n[geometry]\nrise = 8.46\nincline_deg = 30.0\n"
    )
    profile = parse_profile(text, "m14.toml")
    ctx = analyse(_tensioner_csv(tmp_path / "m14.csv", seconds=20.0), profile=profile)
    n, src = ctx.summary["n_links"], ctx.summary["n_links_from"]
    assert n == 412 and src.startswith("derived: whole steps of 4 links")  # the loop of 41.92 m
    assert any(note.startswith("the chain's 412 links are vibkit's count") for note in ctx.notes)
    assert ("links in the chain", f"412 ({src})") in evidence_rows(ctx)
