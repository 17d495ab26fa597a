"""Every page of the diagnostic report is drawn and its text checked: no two text artists overlap,
none leaves the page, a text placed in an axes stays in it, a table cell's text stays in its cell.
Page 1 is the verdict: unit, dates, recording, the verdict with its uncertainty, the warnings."""

import re
from pathlib import Path

import pytest

from vibkit.diagnose.report import write_report
from vibkit.diagnose.report.common import PageSink, fmt_pm

LEON = "data/field/leon-tensioner.csv"
PHYPHOX = "data/field/layouts/phyphox.csv"
TOL = 1.0  # px at 72 dpi: touching is not overlapping


def _bbox(artist, renderer):
    bb = artist.get_window_extent(renderer)
    return (bb.x0, bb.y0, bb.x1, bb.y1)


def _overlap(a, b):
    return min(a[2], b[2]) - max(a[0], b[0]) > TOL and min(a[3], b[3]) - max(a[1], b[1]) > TOL


def _inside(inner, outer):
    return (
        inner[0] >= outer[0] - TOL
        and inner[1] >= outer[1] - TOL
        and inner[2] <= outer[2] + TOL
        and inner[3] <= outer[3] + TOL
    )


def layout_problems(fig):
    """Overlapping, clipped or escaped texts of a figure, as readable lines."""
    import matplotlib.text

    fig.set_dpi(72)
    fig.canvas.draw()
    r = fig.canvas.get_renderer()
    page = (0, 0, fig.bbox.width, fig.bbox.height)
    problems = []
    cells = set()
    for ax in fig.axes:
        for tab in ax.tables:
            for cell in tab.get_celld().values():
                t = cell.get_text()
                if not t.get_text():
                    continue
                cells.add(id(t))
                if not _inside(_bbox(t, r), _bbox(cell, r)):
                    problems.append(f"table cell text clipped: {t.get_text()!r}")
    # tick labels: only those drawn (the ticks inside the view); the others exist but are not drawn
    ticks, drawn = set(), set()
    for ax in fig.axes:
        for axis in (ax.xaxis, ax.yaxis):
            for tick in axis.get_major_ticks() + axis.get_minor_ticks():
                ticks.update((id(tick.label1), id(tick.label2)))
            if not (ax.axison and axis.get_visible()):
                continue
            for tick in axis._update_ticks():  # the ticks matplotlib draws (inside the view)
                drawn.update((id(tick.label1), id(tick.label2)))
    texts = []
    for t in fig.findobj(matplotlib.text.Text):
        if not t.get_visible() or not t.get_text().strip() or id(t) in cells:
            continue
        if id(t) in ticks and id(t) not in drawn:
            continue
        bb = _bbox(t, r)
        if bb[2] - bb[0] < 0.5:  # empty
            continue
        texts.append((t, bb))
        if not _inside(bb, page):
            problems.append(f"off the page: {t.get_text()[:60]!r}")
    for ax in fig.axes:
        abb = _bbox(ax, r)
        for t in ax.texts:
            if t.get_visible() and t.get_text().strip() and not _inside(_bbox(t, r), abb):
                problems.append(f"leaves its axes: {t.get_text()[:60]!r}")
    for i, (a, ba) in enumerate(texts):
        for b, bb in texts[i + 1 :]:
            if _overlap(ba, bb):
                # a legend or table draws its texts inside its own box; matplotlib's tick labels of one
                # axis never overlap each other at these sizes, so any overlap is a real collision
                problems.append(f"overlap: {a.get_text()[:50]!r} / {b.get_text()[:50]!r}")
    return problems


@pytest.fixture(scope="module")
def checked_reports(tmp_path_factory):
    """The Leon report (with its scene) and the phyphox report (x, y, z), every page checked as drawn."""
    problems = {}
    orig = PageSink.emit

    def emit(self, fig, title):
        problems[(len(self.pages) + 1, title)] = layout_problems(fig)
        return orig(self, fig, title)

    mp = pytest.MonkeyPatch()
    mp.setattr(PageSink, "emit", emit)
    d = tmp_path_factory.mktemp("layout")
    try:
        leon = write_report(LEON, d / "leon.pdf", scene="sim/leon.toml", duration=4.0, date="2020-02-14")
        phy = write_report(PHYPHOX, d / "phyphox.pdf", speed=0.5)
    finally:
        mp.undo()
    return leon, phy, problems


@pytest.mark.slow
def test_no_text_overlaps_or_leaves_its_place(checked_reports):
    _, _, problems = checked_reports
    bad = {f"page {n} ({t})": p for (n, t), p in problems.items() if p}
    assert bad == {}


@pytest.mark.slow
def test_page_one_is_the_verdict(checked_reports):
    leon, _, _ = checked_reports
    title, texts = leon.pages[0]
    text = "\n".join(texts)
    assert title == "verdict"
    assert "REPLACE" in text
    assert "138.4" in text and " mm" in text
    assert "2020-02-14 (given)" in text  # the measurement date
    assert re.search(r"report\n?.*\d{4}-\d{2}-\d{2} \d{2}:\d{2} UTC", text)  # the report date
    # no escalator profile: the unit is not named, and the scene's description is not taken for it
    assert "unit not named: --escalator FILE" in text and "Leon shopping centre" not in text
    assert "leon-tensioner.csv" in text
    # the file's speed states no uncertainty: said with each figure, not as a warning (none is true here)
    assert "WARNING" not in text and "speed uncertainty not stated" in text
    assert not re.search(r"\+- 0(\.0*)?(?![0-9.])", text)  # never +- 0.00
    # lengths in mm: the peak to peak of a displacement in m is shown in mm
    assert re.search(r"RMS / peak to peak\n?.*mm", text)


@pytest.mark.slow
def test_date_without_metadata_says_so(checked_reports):
    _, phy, _ = checked_reports
    assert "not stated in the file (give --date)" in "\n".join(phy.pages[0][1])


@pytest.mark.parametrize(
    "v, s, text",
    [
        (138.4163, 0.0213, "138.416 +- 0.021"),
        (0.49, 0.0, "0.49"),
        (3.8207, 0.31, "3.82 +- 0.31"),
        (1234.5, 56.0, "1234 +- 56"),
        (0.49, None, "0.49"),
        (3.5401234, 0.00123, "3.5401 +- 0.0012"),
        # a sigma that rounds up to a third digit keeps two (a stranger's "-0.014 +- 0.100")
        (-0.014, 0.09999, "-0.01 +- 0.10"),
        (5.0, 9.97, "5 +- 10"),
    ],
)
def test_numbers_rounded_to_their_uncertainty(v, s, text):
    assert fmt_pm(v, s) == text


def test_settings_and_rounding_are_not_given_as_measured_precision():
    from vibkit.diagnose.report.appendix import _band, _jitter
    from vibkit.diagnose.rounding import fmt_band, fmt_value

    assert fmt_band((3.9, 6.09375)) == "3.90-6.09 Hz" and _band((3.9, 6.09375)) == "3.90 - 6.09 Hz"
    assert _jitter(8.66e-11) == "under 0.001 % of the period" and _jitter(0.0123) == "0.012 % of the period"
    # a recorded harmonic known to +-0.18 of its ratio: 24.4 Hz, not 24.3632 Hz
    assert fmt_value(24.3632, 0.18 * 24.3, default_decimals=4) == "24.4"  # two digits of its sigma, 4.4 Hz
    assert fmt_value(3.75012, 1e-4, default_decimals=4) == "3.75012"
    # an amplitude difference and its 95 % interval, to the interval's width (was "+19.62 [-82.07, +121.30]")
    from vibkit.diagnose.rounding import fmt_interval

    assert fmt_interval(19.62, -82.07, 121.30) == "+20 [-80, +120]"
    assert fmt_interval(-0.33, -1.2, 0.55) == "-0.33 [-1.20, +0.55]"


def test_a_value_that_rounds_to_zero_has_no_minus_sign():
    from types import SimpleNamespace

    from vibkit.diagnose.report.common import elongation_figure

    assert fmt_pm(-0.0003, 0.01, "%", sign=True) == "+0.000 +- 0.010 %"
    pitch = SimpleNamespace(speed_sigma_stated=False, elongation_percent=-0.0003)
    assert elongation_figure(pitch).startswith("+0.00 %")


def _simulated_ride(variables, coords):
    import numpy as np
    import xarray as xr

    from vibkit.diagnose.ride import ride_quality_from_simulation

    t = np.arange(0.0, 12.0, 1 / 400.0)
    ds = xr.Dataset({k: (dims, f(t)) for k, (dims, f) in variables.items()}, coords={"time": t, **coords})
    return ride_quality_from_simulation(ds, segment=(0.0, 12.0) if "roller_acceleration" in ds else None)


def test_a_simulations_ride_table_fits_its_cells():
    """The ride page of a simulation: the axis "tangential" (accel_step alone, over a 12 s "whole simulated
    time" whose note is the longest) and a step roller's channel names each stay in their cell and on the page."""
    import matplotlib.pyplot as plt
    import numpy as np

    from vibkit.diagnose.report import plot_ride

    def wave(t):
        return 0.05 * np.sin(2 * np.pi * 3.9 * t)

    def rollers(t):
        return np.stack([wave(t), wave(t) - 9.80665], axis=-1)[:, None, :]

    tangential = _simulated_ride({"accel_step": ("time", wave)}, {})
    step = _simulated_ride(
        {"roller_acceleration": (("time", "roller", "axis"), rollers)}, {"roller": [59], "axis": ["x", "z"]}
    )
    assert [a.axis for a in tangential.axes] == ["tangential"]
    assert [a.channel for a in step.axes] == ["roller_acceleration[59, x]", "roller_acceleration[59, z] + g"]
    for rq in (tangential, step):
        fig = plot_ride(rq)
        try:
            assert layout_problems(fig) == []
        finally:
            plt.close(fig)


def test_a_profile_in_a_long_folder_keeps_the_parameters_table_in_its_cells(tmp_path):
    """A profile file deep in a folder with a long name: the parameters page names it by its file name (the
    recording page has the whole path) and no cell's text leaves its cell."""
    import shutil

    from vibkit.model.profile import load_profile

    folder = tmp_path / "a very long folder name for the escalator profiles of the north site" / "subfolder"
    folder.mkdir(parents=True)
    shutil.copy("data/fleet-example/escalators/E07.toml", folder / "E07-profile.toml")
    problems = {}
    orig = PageSink.emit

    def emit(self, fig, title):
        problems[title] = layout_problems(fig)
        return orig(self, fig, title)

    mp = pytest.MonkeyPatch()
    mp.setattr(PageSink, "emit", emit)
    try:
        profile = load_profile(folder / "E07-profile.toml")
        write_report("data/fleet-example/E07/2026-11-23.csv", tmp_path / "r.pdf", profile=profile, date="2026-11-23")
    finally:
        mp.undo()
    assert problems["parameters"] == [] and problems["recording"] == [], problems


def test_a_report_without_a_link_pass_draws_no_order_spectrum(tmp_path):
    """An order spectrum is the record resampled to the link-pass phase: without a link pass there is none to
    draw (the band's centre was drawn as if it were one, the same 3.9528 Hz for every refused file)."""
    rep = write_report("data/thirdparty/phyphox_elevator_linear_acc.csv", tmp_path / "e.pdf", speed=0.5)
    assert rep.summary["link_pass_hz"] is None and rep.summary["status"] == "no link-pass found"
    assert "order spectrum" not in [t for t, _ in rep.pages]


def test_a_ride_page_with_long_notes_keeps_them_under_its_time_axis():
    """Four long notes (a simulation's settling advice, a knock test, a roller, a vertical speed) took seven lines
    and ran into the time axis' label: the plots now end above the notes."""
    import types

    import numpy as np

    from vibkit.diagnose.report.ride_pages import ride_quality_pages
    from vibkit.diagnose.ride import ride_quality

    t = np.arange(0, 20, 1 / 200.0)
    z = 9.8 + 0.02 * np.sin(2 * np.pi * 5 * t)
    rq = ride_quality({"x": 0.01 * np.sin(2 * np.pi * 3 * t), "z": z}, 200.0, segment=(3.0, 17.0))
    rq.notes[:] = [f"note {k}: " + "a long line of words about the ride and its segment " * 4 for k in range(4)]
    found = {}

    class Doc:
        def emit(self, fig, title):
            found[title] = layout_problems(fig)

    ride_quality_pages(Doc(), types.SimpleNamespace(ride=[("recording", rq)], scene=None, duration=None))
    assert found == {"ride quality (recording)": []}, found


def test_the_parameters_page_lists_the_whole_scene(tmp_path):
    """'Everything needed to repeat this report': a stranger's scene lines were cut with '...' and its last lines
    left out. Long lines go on, indented, on the next line, and lines past the page on a continuation page."""
    sentence = "Leon shopping centre escalator, empty, 0.49 m/s; tensioner carriage displacement sensor"
    lines = Path("sim/leon.toml").read_text().replace(sentence, "; ".join([sentence] * 3)).splitlines()
    i = next(k for k, ln in enumerate(lines) if ln.startswith("variables"))
    lines[i : i + 1] = ["variables = ["] + ['  "delta",'] * 40 + ["]"]  # 41 more lines of the scene's own
    scene = tmp_path / "long.toml"
    scene.write_text("\n".join(lines) + "\n")
    rep = write_report(LEON, tmp_path / "r.pdf", scene=str(scene), duration=4.0, date="2020-02-14")
    pages = {title: "\n".join(texts) for title, texts in rep.pages}
    listed = pages["parameters"] + "\n" + pages["parameters (continued)"]
    assert "..." not in listed
    assert " ".join(listed.split()).count("tensioner carriage displacement sensor") == 3
    assert listed.count('"delta",') == 40


def test_a_start_without_its_zone_is_not_called_utc(tmp_path):
    """A German logger's 'Start: 04.05.2026 07:30:00' is local time: page 1 printed it as 07:30 UTC."""
    import numpy as np

    t = np.arange(0, 30, 0.005)
    p = tmp_path / "german.csv"
    p.write_text(
        "Start: 04.05.2026 07:30:00\ntime (s),disp (mm)\n"
        + "".join(f"{a:.3f},{0.05 * np.cos(2 * np.pi * 3.75 * a):.5f}\n" for a in t)
    )
    rep = write_report(str(p), tmp_path / "r.pdf", speed=0.5)
    page1 = " ".join(rep.pages[0][1])
    assert "2026-05-04 07:30 (the file's start time, its time zone not stated)" in page1
    assert "07:30 UTC" not in page1


def test_page_one_with_an_inconclusive_verdict_and_its_warnings_stays_on_the_page(tmp_path, monkeypatch):
    """An inconclusive verdict with its warnings (a step's accelerometer on an inclined walk whose profile states
    no speed uncertainty: the speed's +-5 % and the step's own 1 %), the pages left out and the notes ran off page
    1's bottom. Page 1 now shrinks its type to fit: every text on the page, none overlapping."""
    import numpy as np

    from vibkit.model.profile import parse_profile

    profile = parse_profile(
        '[escalator]\nunit = "W12"\nsite = "Hypermarket, car park ramp"\n'
        'description = "inclined pallet walk, 12 degrees"\n[drive]\nspeed = 0.5\nteeth = 23\n'
        "[chain]\nnominal_pitch = 0.13333\nlinks_per_step = 3\n[geometry]\nlength = 16.0\nincline_deg = 12\n"
        '[sensor]\nkind = "step"\nstep = 3\n',
        "w12.toml",
    )
    fs, f = 100.0, 0.5 / (0.13333 * 1.01)
    t = np.arange(int(60 * fs)) / fs
    z = 9.81 + 0.03 * np.sin(2 * np.pi * f * t) + 0.01 * np.sin(4 * np.pi * f * t)
    z += 0.003 * np.random.default_rng(3).standard_normal(t.size)
    rec = tmp_path / "pallet.csv"
    rec.write_text("time (s),acc_z (m/s^2)\n" + "".join(f"{a:.3f},{b:.5f}\n" for a, b in zip(t, z)))
    problems = {}
    orig = PageSink.emit

    def emit(self, fig, title):
        if title == "verdict":
            problems[title] = layout_problems(fig)
        return orig(self, fig, title)

    monkeypatch.setattr(PageSink, "emit", emit)
    rep = write_report(rec, tmp_path / "r.pdf", profile=profile)
    text = "\n".join(rep.pages[0][1])
    assert "INCONCLUSIVE" in text and "the sensor rides a step" in text
    # the two warnings; the inconclusive reason is the headline's line, not a third warning repeating it
    assert "2 WARNINGS" in text and "inconclusive: " not in text
    assert "Pages not in this report" in text and "note: " in text
    assert problems == {"verdict": []}
