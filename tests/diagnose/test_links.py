"""Which link is worn, on simulated recordings of the study's escalator (no load, 0.5 m/s): three loops
of the tensioner (1 um noise) and a step accelerometer (5 mm/s^2 noise) after one loop of settling,
with link 40, then link 70, 1 mm long, and the healthy chain."""

import dataclasses
import json
import math
from pathlib import Path

import numpy as np
import pytest
import xarray as xr

import vibkit
from vibkit.cli import main
from vibkit.diagnose.links import find_worn_links, link_number_of
from vibkit.model.scene import load_scene

from support.profiles import PROFILE_90

pytestmark = pytest.mark.slow

SCENE = "sim/thesis-forward.toml"
N = 159
SPEED = 0.5
FS = 200.0


def _record(scene, worn, rng, excess=1e-3, loops=3, exact=False):
    """``loops`` loops after one loop and 5 s of settling, with noise; the links passed before it; and the
    tensioner's displacement without noise.  ``worn``: a link, or a tuple of links, each ``excess`` long."""
    pitch, n = scene.chain.link_pitch, scene.chain.n_rollers
    settle = n * pitch / SPEED + 5.0
    duration = settle + (loops * n + 3) * pitch / SPEED
    worn_links = () if worn is None else tuple((w, pitch + excess) for w in np.atleast_1d(worn).tolist())
    chain = scene.chain if worn is None else dataclasses.replace(scene.chain, worn_links=worn_links)
    sc = dataclasses.replace(
        scene,
        chain=chain,
        outputs=dict(scene.outputs, variables=("delta", "accel_step", "sprocket_angle")),
    )
    if exact:
        sc = sc.with_solver(closure="exact")  # as the signature's runs
    ds = vibkit.simulate(sc, duration=duration, progress=False)
    t = ds.time.values
    keep = t >= settle
    theta = ds.sprocket_angle.values
    passed = scene.sprocket.teeth * abs(float(theta[keep][0] - theta[0])) / (2 * np.pi)
    rec = xr.Dataset(
        {
            "delta": ("time", ds.delta.values[keep] + rng.normal(0, 1e-6, keep.sum()), {"units": "m"}),
            "accel_step": ("time", ds.accel_step.values[keep] + rng.normal(0, 5e-3, keep.sum()), {"units": "m/s^2"}),
        },
        coords={"time": ("time", t[keep] - t[keep][0], {"units": "s"})},
    )
    # the link-pass frequency the sprocket's mesh gives over the record: the truth of `vibkit pitch`
    f_true = (
        scene.sprocket.teeth
        * abs(float(theta[keep][-1] - theta[keep][0]))
        / (2 * np.pi)
        / float(t[keep][-1] - t[keep][0])
    )
    return rec, passed, ds.delta.values[keep], f_true


@pytest.fixture(scope="module")
def recordings(tmp_path_factory):
    scene = load_scene(SCENE)
    rng = np.random.default_rng(29)
    out = {}
    folder = tmp_path_factory.mktemp("links")
    for worn in (None, 40, 70):
        rec, passed, clean, f_true = _record(scene, worn, rng)
        path = folder / f"worn-{worn}.nc"
        rec.to_netcdf(path)
        out[worn] = (path, passed)
        out["f", worn] = f_true
        if worn is None:
            out["clean"] = (rec.time.values, clean)
    return out


def _links(path, capsys, *extra):
    rc = main(["links", str(path), "--speed", "0.5", "--links", str(N), "--scene", SCENE, "--json", *extra])
    assert rc == 0
    return json.loads(capsys.readouterr().out)


def test_one_worn_link_is_flagged_by_its_number(recordings, capsys):
    found = {}
    for worn in (40, 70):
        path, passed = recordings[worn]
        d = _links(path, capsys)
        assert len(d["flagged"]) == 1, d["flagged"]
        f = d["flagged"][0]
        # the data separate it from every other placement of the signature: one number, no alternative
        assert f["alternatives"] == []
        # the number in passing order from the link at the sensor when the recording starts
        assert f["link"] == link_number_of(worn, passed, N)
        assert f["loops"] == [1, 2, 3]
        # the excess pitch: 1 mm within the signature's model error (the signature is link 1's: 13 % low here)
        assert 0.75 < f["excess_pitch_mm"] < 1.25
        assert 0 < f["sigma_mm"] < 0.05
        found[worn] = f["link"]
    # links pass in decreasing model number: link 70 passes 30 links before link 40
    assert (found[40] - found[70]) % N == 30


def test_the_healthy_chain_flags_no_link(recordings, capsys):
    d = _links(recordings[None][0], capsys)
    assert d["flagged"] == []
    assert d["false_alarm"] == 0.01
    assert d["loops"] == 3


def test_a_marker_renumbers_from_the_marked_link(recordings, capsys):
    path, passed = recordings[40]
    plain = _links(path, capsys)["flagged"][0]["link"]
    # the marked link passed 10.5 link cycles after the start: it becomes link 1
    f_lp = SPEED / load_scene(SCENE).chain.link_pitch
    marked = _links(path, capsys, "--marker", str(10.5 / f_lp))["flagged"][0]["link"]
    assert (plain - marked) % N in (10, 11)
    # the report numbers from the same marker (`vibkit report --marker`)
    from vibkit.diagnose.report import write_report
    from vibkit.diagnose.report.common import PageSink

    texts = {}
    orig = PageSink.emit

    def emit(self, fig, title):
        found = (t.get_text() for t in fig.findobj(lambda a: hasattr(a, "get_text")))
        texts[title] = " ".join(x if isinstance(x, str) else x.get_text() for x in found)  # table cells hold Texts
        return orig(self, fig, title)

    out = path.parent / "marked.pdf"
    mp = pytest.MonkeyPatch()
    mp.setattr(PageSink, "emit", emit)
    try:
        rep = write_report(path, out, scene=SCENE, speed=SPEED, duration=2.0, marker_s=10.5 / f_lp, overwrite=True)
    finally:
        mp.undo()
    assert rep.summary["flagged_links"] == [marked]
    # and says so wherever the numbers are read (the links page said "link 1: the link at the sensor at the
    # start" with a marker, and no page named the marker: a stranger's technician counts from the wrong link)
    mark = f"{10.5 / f_lp:g} s"
    assert f"link 1: the link marked at {mark} (--marker)" in " ".join(texts["links"].split())
    assert "the link at the sensor at the start" not in texts["links"]
    assert f"from the link marked at {mark}" in texts["parameters"]
    assert rep.summary["marker_s"] == pytest.approx(10.5 / f_lp)
    assert rep.summary["link_numbers_from"] == f"the link marked at {mark}"
    # a marker outside the recording is the user's to mend: an error naming it, no page saying "not scanned"
    with pytest.raises(ValueError, match=r"marker_s=.* must lie within the recording"):
        write_report(path, path.parent / "far.pdf", scene=SCENE, speed=SPEED, duration=2.0, marker_s=1e4)
    assert not (path.parent / "far.pdf").exists()


def test_a_link_pass_no_chain_of_the_nominal_pitch_has_is_refused(recordings):
    """A stranger's profile gave the speed in km/h (2.34 for 0.65 m/s): the map took the link pass's second
    harmonic and flagged links. Given the nominal pitch, a pitch 80 % long (or 3.6 times short) is refused; the
    right speed is not."""
    rec = xr.open_dataset(recordings[40][0])
    nominal = load_scene(SCENE).chain.link_pitch
    for speed in (SPEED * 3.6, SPEED / 3.6):
        with pytest.raises(ValueError, match=r"from the nominal 133.33\d* mm .* not km/h"):
            find_worn_links(rec, speed=speed, n_links=N, scene=SCENE, nominal_pitch=nominal)
    # a rated speed 5 % off the chain's is still a chain
    res = find_worn_links(rec, speed=SPEED * 1.05, n_links=N, nominal_pitch=nominal)
    assert res.loops == 3


def test_the_step_channel_is_refused_with_or_without_a_scene(recordings):
    """The simulated step accelerometer (5 mm/s^2 noise) of the worn chain gets no link number: its passes
    round the heads change as much from run to run as the worn link changes them."""
    rec = xr.open_dataset(recordings[40][0])
    for scene in (SCENE, None):
        with pytest.raises(ValueError, match="step accelerometer gives no link number"):
            find_worn_links(rec, speed=SPEED, n_links=N, channel="accel_step", scene=scene)


def test_the_report_has_a_links_page_with_the_flagged_link(recordings, tmp_path):
    import importlib.util
    from pathlib import Path

    from vibkit.diagnose.report import write_report
    from vibkit.diagnose.report.common import PageSink

    spec = importlib.util.spec_from_file_location("layout", Path(__file__).with_name("test_report_layout.py"))
    layout = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(layout)
    problems = {}
    orig = PageSink.emit

    def emit(self, fig, title):
        if title in ("links", "verdict"):
            problems[title] = layout.layout_problems(fig)
            problems[title + " texts"] = " ".join(t.get_text() for t in fig.findobj(lambda a: hasattr(a, "get_text")))
        return orig(self, fig, title)

    path, passed = recordings[40]
    mp = pytest.MonkeyPatch()
    mp.setattr(PageSink, "emit", emit)
    try:
        rep = write_report(path, tmp_path / "r.pdf", scene=SCENE, speed=SPEED, duration=2.0, date="2026-11-26")
    finally:
        mp.undo()
    assert "links" in [t for t, _ in rep.pages]
    assert problems["links"] == [] and problems["verdict"] == []
    number = link_number_of(40, passed, N)
    assert f"link {number}:" in problems["links texts"]
    assert rep.summary["flagged_links"] == [number]
    assert rep.summary["flagged_links_detail"][0]["link"] == number
    # and the chain's mean elongation still gets its verdict: the scene's 159 links align the parts check
    # with the loops, so the worn link's once-a-loop pattern is not read as a wander
    assert (rep.summary["status"], rep.summary.get("verdict")) == ("ok", "ok"), rep.summary["reason"]
    # page 1 says it too: the elongation is the chain's mean, and an "OK" must not hide a worn link
    assert "1 WORN LINK FLAGGED" in problems["verdict texts"] and f"link {number}: +" in problems["verdict texts"]


def test_without_a_scene_a_worn_link_gives_no_number(recordings, capsys):
    """Without the scene's signature, each link's own cycle is tested: a worn link moves the tensioner over
    the links that follow it, so many links deviate; no link number is given (inconclusive, exit 3)."""
    path, _ = recordings[40]
    rc = main(["links", str(path), "--speed", "0.5", "--links", str(N), "--json"])
    d = json.loads(capsys.readouterr().out)
    assert (rc, d["status"], d["flagged"]) == (3, "inconclusive", []), d["reason"]
    assert "--scene or --escalator" in d["reason"]


def test_a_worn_link_keeps_the_elongation_verdict_given_the_number_of_links(recordings, run):
    """A worn link changes the tensioner's shape once a loop, and the link-pass frequency of parts of the record
    moves with it (0.12 %: "inconclusive, the frequency wanders" before).  With the number of links the parts
    are taken at the same places of every loop: around their places' means they scatter as their sigmas allow,
    so no wander and the verdict is given, with the frequency the sprocket's mesh frequency within its sigma;
    without it the same record is inconclusive.  The healthy chain reads no wander either way."""
    pitch = ["pitch", "--speed", "0.5", "--speed-uncertainty", "0.05%", "--nominal-pitch", "133.33mm", "--json"]
    for worn in (40, 70):
        path = str(recordings[worn][0])
        rc, out, _ = run(*pitch, "--channel", "delta", path, "--links", str(N))
        d = json.loads(out)
        assert (rc, d["status"], d["verdict"]) == (0, "ok", "ok"), d["reason"]
        parts = d["parts"]
        assert parts["aligned_to_loops_of_links"] == N
        assert parts["birge_ratio_around_places"] < parts["birge_limit_around_places"] < parts["birge_ratio"]
        assert parts["wander_percent"] == 0.0
        assert abs(d["fundamental_hz"] - recordings["f", worn]) < 3 * d["fundamental_sigma_hz"]
        # without the number of links the same pattern reads as a wander, and no verdict is given
        rc, out, _ = run(*pitch, "--channel", "delta", path)
        d = json.loads(out)
        assert (rc, d["status"]) == (3, "inconclusive") and "wanders" in d["reason"], d["reason"]
        assert any("--links N" in n for n in d["notes"])  # and the note says what would tell them apart
    # the healthy chain, every channel: the tensioner gives the numbers; the step accelerometer (whose link pass
    # reads 0.5 % low, its parts wandering 0.2 %) sees the same chain, not a second periodicity
    rc, out, _ = run(*pitch, str(recordings[None][0]), "--links", str(N))
    d = json.loads(out)
    assert (rc, d["channel"], d["verdict"]) == (0, "delta", "ok"), d["reason"]
    assert abs(d["fundamental_hz"] - recordings["f", None]) < 3 * d["fundamental_sigma_hz"]
    step = next(c for c in d["channels"] if c["channel"] == "accel_step")
    assert step["status"] == "inconclusive"


def _tensioner(t, x):
    return xr.Dataset({"delta": ("time", x, {"units": "m"})}, coords={"time": t})


def test_the_healthy_chain_has_no_special_link(recordings):
    """The simulated healthy chain fits no excess at any link: without noise at most 0.003 mm (it reads
    0.0004 mm), and with a slow 1 % speed wander at most 0.02 mm (it reads 0.009 mm; a phase tracked at
    f_lp / 100 reads 0.039 mm there). Nothing is flagged even without a minimum excess."""
    t, x = recordings["clean"]
    steady = find_worn_links(_tensioner(t, x), speed=SPEED, n_links=N, scene=SCENE, min_excess=0.0)
    assert steady.flagged == []
    assert np.max(np.abs(steady.excess_mm)) < 0.003
    # the chain's own time runs at 1 + 0.01 cos(2 pi t / 135 s + 2.66): the recording at t is the run at tau(t)
    period, phase = 135.0, 2.66
    tr = t[t < t[-1] - 0.01 * period / np.pi]
    tau = tr + 0.01 * period / (2 * np.pi) * (np.sin(2 * np.pi * tr / period + phase) - np.sin(phase))
    wander = find_worn_links(_tensioner(tr, np.interp(tau, t, x)), speed=SPEED, n_links=N, scene=SCENE, min_excess=0.0)
    assert wander.flagged == []
    assert wander.loops == 3
    assert np.max(np.abs(wander.excess_mm)) < 0.02


def test_a_link_one_tenth_of_a_millimetre_long_is_flagged_by_its_number():
    """With the default minimum excess (0.05 mm), a link 0.1 mm long is found alone, by its number, from
    three loops with 1 um of noise; its excess reads 0.1 mm within 0.03 mm."""
    scene = load_scene(SCENE)
    rec, passed, _, _ = _record(scene, 40, np.random.default_rng(40), excess=0.1e-3)
    res = find_worn_links(rec, speed=SPEED, n_links=N, scene=SCENE)
    assert [f["link"] for f in res.flagged] == [link_number_of(40, passed, N)]
    assert abs(res.flagged[0]["excess_pitch_mm"] - 0.1) < 0.03
    # once its change is taken out no link passes the threshold (what the report's links page draws below)
    assert res.residual_statistic.max() < res.threshold < res.statistic.max()


def test_two_worn_links_read_each_its_own_excess():
    """Links 40 and 70 each 1 mm long (exact closure, three loops, 1 um of noise): both are flagged by their
    numbers and each reads 1 mm within three of its sigmas and 0.03 mm.  The signature of one worn link overlaps
    its placement 30 links on by rho = -0.24: with the flags fitted one after the other the first flagged read that
    much low (0.75 +- 0.01 mm) and the second 0.93 mm; fitted together, as the scan does, 0.99 mm each."""
    scene = load_scene(SCENE)
    rec, passed, _, _ = _record(scene, (40, 70), np.random.default_rng(4070), exact=True)
    res = find_worn_links(rec, speed=SPEED, n_links=N, scene=SCENE)
    expected = {link_number_of(w, passed, N) for w in (40, 70)}
    assert {f["link"] for f in res.flagged} == expected
    for f in res.flagged:
        assert abs(f["excess_pitch_mm"] - 1.0) < min(3 * f["sigma_mm"], 0.03), f


@pytest.fixture(scope="module")
def profile_90(tmp_path_factory):
    from vibkit.model.profile import parse_profile

    path = tmp_path_factory.mktemp("e90") / "E90.toml"
    path.write_text(PROFILE_90)
    return path, parse_profile(PROFILE_90, "E90.toml").scene("forward")


@pytest.fixture(scope="module")
def coasting_90(tmp_path_factory):
    """The 90-link profile with no running resistance (``drive.no_load_power = 0``): its chain coasts, the teeth
    carry no load, and a worn link's signature on the sprocket is the one it has round the lower head."""
    from vibkit.model.profile import parse_profile

    text = PROFILE_90.replace("teeth = 28", "teeth = 28\nno_load_power = 0", 1)
    path = tmp_path_factory.mktemp("e90c") / "E90.toml"
    path.write_text(text)
    return path, parse_profile(text, "E90.toml").scene("forward")


def test_a_link_half_a_loop_from_its_twin_is_given_with_both_numbers(coasting_90, tmp_path, capsys):
    """On the 90-link profile's coasting scene a 0.5 mm link (link 20, 2.3 loops, 1 um noise) fits the 1 mm
    signature better half a loop away than at itself (the sprocket and the lower head, both unloaded, move the
    tensioner alike), and that signature differs from the 0.5 mm one by most of its norm: the flag names both
    numbers, the true one among them, in --json and in the table."""
    path, scene = coasting_90
    rec, passed, _, _ = _record(scene, 20, np.random.default_rng(5), excess=0.5e-3, loops=2.3, exact=True)
    rec.to_netcdf(tmp_path / "e90.nc")
    true = link_number_of(20, passed, 90)
    d = _links_with(tmp_path / "e90.nc", capsys, "--escalator", str(path), "--json")
    (f,) = d["flagged"]
    assert true in [f["link"], *f["alternatives"]]
    assert len(f["alternatives"]) >= 1 and f["link"] not in f["alternatives"]
    assert float(d["method"].split("relative error ")[1].split(")")[0]) > 0.5  # 0.84 (0.93 before 0.5.2's tracker)
    _links_with(tmp_path / "e90.nc", capsys, "--escalator", str(path))
    out, err = capsys.readouterr()
    assert " or ".join(str(k) for k in [f["link"], *f["alternatives"]]) in out
    assert "cannot tell them apart" in err


def test_on_a_driven_chain_the_worn_link_has_no_twin(profile_90, tmp_path, capsys):
    """The same 0.5 mm link on the 90-link profile's scene as built (a driven chain): on the sprocket the link is
    in the loaded strand on the teeth, round the lower head in the slack one, so its signature is not repeated half
    a loop later, and the flag names the true link alone."""
    path, scene = profile_90
    rec, passed, _, _ = _record(scene, 20, np.random.default_rng(5), excess=0.5e-3, loops=2.3, exact=True)
    rec.to_netcdf(tmp_path / "e90.nc")
    d = _links_with(tmp_path / "e90.nc", capsys, "--escalator", str(path), "--json")
    (f,) = d["flagged"]
    assert f["link"] == link_number_of(20, passed, 90) and not f["alternatives"]


def test_a_two_millimetre_link_is_fitted_again_with_a_longer_signature(coasting_90):
    """On the coasting 90-link scene the 1 mm signature reads a 2 mm link low (1.69 mm, 1.8 mm with 0.5.2's
    tracker); the fit repeated with the signature of a link that long reads it within 0.15 mm of the truth (noise
    0.03 mm), by the same number.  (On the driven scene the 1 mm signature reads it right, 2.02 mm, and the second
    fit is not needed.)"""
    from vibkit.diagnose.links import profile_scene_file
    from vibkit.model.profile import load_profile

    path, scene = coasting_90
    rec, passed, _, _ = _record(scene, 20, np.random.default_rng(6), excess=2e-3, loops=2.3, exact=True)
    res = find_worn_links(rec, speed=SPEED, n_links=90, scene=profile_scene_file(load_profile(path)))
    f = max(res.flagged, key=lambda f: f["t"])
    assert f["link"] == link_number_of(20, passed, 90)
    assert abs(f["excess_pitch_mm"] - 2.0) < 0.15
    refit = float(res.method.split("scene (")[1].split(" mm")[0])  # the signature the second fit used
    assert 1.5 <= refit <= 2.0


def test_a_wrong_number_of_links_gives_no_number_and_says_how_many(profile_90, tmp_path):
    """A stranger's profile said 360 links for a chain of 364: the worn link was flagged under a wrong number,
    exit 0. Counted as 92 links, the 90-link chain's worn link peaks 2 links earlier in every loop: no number, the
    status inconclusive, and the count the peaks give. (Counted as 94 or 86, its fits spread so thin over the loops
    that no link passes the threshold.)"""
    from vibkit.diagnose.links import profile_scene_file
    from vibkit.model.profile import parse_profile

    _, scene = profile_90
    rec, passed, _, _ = _record(scene, 20, np.random.default_rng(8), loops=3.2, exact=True)
    right = find_worn_links(rec, speed=SPEED, n_links=90, scene=profile_scene_file(parse_profile(PROFILE_90, "p")))
    assert [f["link"] for f in right.flagged] == [link_number_of(20, passed, 90)] and right.status == "ok"
    wrong = PROFILE_90.replace("n_links = 90", "n_links = 92")
    res = find_worn_links(rec, speed=SPEED, n_links=92, scene=profile_scene_file(parse_profile(wrong, "w")))
    assert res.status == "inconclusive" and res.flagged == []
    assert "counted as 92 links" in res.reason and "about 90 links" in res.reason


def test_a_scene_with_worn_links_is_refused_as_the_signature_s_chain(recordings, tmp_path):
    """A stranger gave `--scene` the very scene his worn recording came from: the excess read half, and a wrong
    alternative. The signature is a worn link's change of the healthy chain: such a scene is refused."""
    worn = tmp_path / "worn.toml"
    text = Path(SCENE).read_text().replace("n_rollers = 159", "n_rollers = 159\nworn_links = [[40, 0.134333]]")
    worn.write_text(text)
    rec = xr.open_dataset(recordings[40][0])
    with pytest.raises(ValueError, match=r"has worn links \(40\).*without worn_links"):
        find_worn_links(rec, speed=SPEED, n_links=N, scene=str(worn))


def test_a_report_from_the_escalator_profile_alone_scans_the_links(profile_90, tmp_path):
    """`vibkit report --escalator` without a scene simulates the profile's scene in memory: the links are scanned
    with the profile's scene file, as `vibkit links --escalator` does (they were not: page 1 said OK and nothing
    of a worn link); and page 1 says when the links are not scanned, and why."""
    from vibkit.diagnose.report import write_report
    from vibkit.model.profile import load_profile

    path, scene = profile_90
    rec, passed, _, _ = _record(scene, 20, np.random.default_rng(7), loops=2.3, exact=True)
    rec.to_netcdf(tmp_path / "e90.nc")
    rep = write_report(tmp_path / "e90.nc", tmp_path / "r.pdf", profile=load_profile(path), duration=2.0)
    assert "links" in [t for t, _ in rep.pages]
    true = link_number_of(20, passed, 90)
    assert true in [rep.summary["flagged_links"][0], *rep.summary["flagged_links_detail"][0]["alternatives"]]
    # a recording under two loops: no links page, and page 1 says why
    short = rec.isel(time=slice(0, rec.sizes["time"] // 3))
    short.to_netcdf(tmp_path / "short.nc")
    rep = write_report(tmp_path / "short.nc", tmp_path / "s.pdf", profile=load_profile(path), duration=2.0)
    page1 = "\n".join(dict(rep.pages)["verdict"])
    assert "links" not in [t for t, _ in rep.pages] and "worn links" in page1 and "record at least" in page1


def _links_with(path, capsys, *args):
    rc = main(["links", str(path), *args])
    assert rc == 0
    if "--json" in args:
        return json.loads(capsys.readouterr().out)
    return None


X65 = """
[escalator]
unit = "X65"
[drive]
speed = 0.65
speed_uncertainty = 0.00065
teeth = 24
[chain]
nominal_pitch = 0.13546
links_per_step = 3
n_links = 120
"""


def test_the_number_is_the_link_at_the_sensor_wherever_the_recording_starts_within_its_passage(tmp_path):
    """A 120-link scene at 0.65 m/s (4.8 Hz: the signature's runs start after 5 s, 24 links, on a link boundary) and
    a 1 mm link 40: recordings started at several places within one link's passage at the sensor number it as
    the link at the sensor then counts it (link_number_of).  The map counts links between the instants a roller
    reaches the sensor (the offset the scene gives), not between the signal's cycle boundaries, which fall half-way
    through a passage here: before, a recording started a fifth or a half of the way through read 84 for 83, and the
    signature's own start on a boundary put every number one too high."""
    from vibkit.diagnose.links import profile_scene_file
    from vibkit.model.profile import parse_profile

    scene_file = profile_scene_file(parse_profile(X65, "X65.toml"))
    scene = load_scene(scene_file)
    pitch = scene.chain.link_pitch
    sc = dataclasses.replace(
        scene,
        chain=dataclasses.replace(scene.chain, worn_links=((40, pitch + 1e-3),)),
        outputs=dict(scene.outputs, variables=("delta", "sprocket_angle")),
    )
    ds = vibkit.simulate(sc, duration=80.0, progress=False)
    t, theta = ds.time.values, ds.sprocket_angle.values
    passed = scene.sprocket.teeth * np.abs(theta - theta[0]) / (2 * np.pi)
    rec = xr.Dataset({"delta": ("time", ds.delta.values, {"units": "m"})}, coords={"time": ("time", t, {"units": "s"})})
    for start in (0.05, 0.1, 0.15, 0.2, 0.3):
        res = find_worn_links(rec.sel(time=slice(start, None)), speed=0.65, n_links=120, scene=scene_file)
        (f,) = res.flagged
        p0 = float(np.interp(start, t, passed))
        assert f["link"] == link_number_of(40, p0, 120), (start, p0, f)


def test_a_marked_link_counts_the_worn_one_as_the_rollers_pass_the_top_of_the_lower_head():
    """The absolute count, from the rollers' own positions: link 50 marked (the time half-way between its rollers'
    arrivals at the top of the lower head, x = delta, z > 0, rollers arriving in decreasing number), link 40 worn
    1 mm: links 50, 49, ..., 40 pass in that order, so the worn link is link 11.  (The count once read 13: its
    link at the sensor was two links ahead of the one going over the top.)"""
    scene = load_scene(SCENE)
    pitch = scene.chain.link_pitch
    sc = dataclasses.replace(
        scene,
        chain=dataclasses.replace(scene.chain, worn_links=((40, pitch + 1e-3),)),
        outputs=dict(scene.outputs, variables=("delta", "roller_position"), rollers=(50, 51)),
    ).with_solver(closure="exact")
    settle = N * pitch / SPEED + 5.0
    ds = vibkit.simulate(sc, duration=settle + (2 * N + 30) * pitch / SPEED, progress=False)
    t, d = ds.time.values, ds.delta.values

    def arrival(roller, after):
        """The first time after ``after`` the roller's centre is over the lower head's centre (delta, 0)."""
        xz = ds.roller_position.sel(roller=roller).values
        rel = xz[:, 0] - d
        k = next(i for i in range(t.size - 1) if t[i] > after and xz[i, 1] > 0 and rel[i] < 0 <= rel[i + 1])
        return t[k] + (t[k + 1] - t[k]) * rel[k] / (rel[k] - rel[k + 1])

    keep = t >= settle
    rec = xr.Dataset({"delta": ("time", d[keep], {"units": "m"})}, coords={"time": ("time", t[keep] - settle)})
    first = arrival(51, settle + 5.0)
    marker = 0.5 * (first + arrival(50, first)) - settle  # roller 51 reaches the top first, then roller 50
    res = find_worn_links(rec, speed=SPEED, n_links=N, scene=SCENE, marker_s=marker)
    assert [(f["link"], f["alternatives"]) for f in res.flagged] == [(11, [])]


def test_a_channel_without_a_unit_is_told_how_to_give_one():
    """A stranger's `time,tensioner` CSV (no unit) was refused as 'not a tensioner displacement' without the fix."""
    t = np.arange(0.0, 100.0, 0.005)
    rec = xr.Dataset(
        {"tensioner": ("time", 1e-2 * np.sin(2 * np.pi * 3.75 * t), {"units": "unknown"})}, coords={"time": t}
    )
    with pytest.raises(ValueError, match=r"units 'unknown'.*give its unit \(--units mm\)"):
        find_worn_links(rec, speed=SPEED, n_links=N, channel="tensioner", scene=SCENE)
    rec["tensioner"].attrs["units"] = "m/s^2"  # an accelerometer's is refused as before, without the hint
    with pytest.raises(ValueError) as err:
        find_worn_links(rec, speed=SPEED, n_links=N, channel="tensioner", scene=SCENE)
    assert "--units" not in str(err.value)


def _arrivals(ds, roller, after):
    """The times after ``after`` at which the roller's centre passes over the lower head's centre (x = delta, z > 0),
    whichever way the chain runs."""
    t, d = ds.time.values, ds.delta.values
    xz = ds.roller_position.sel(roller=roller).values
    rel = xz[:, 0] - d
    out = []
    for i in range(t.size - 1):
        if t[i] > after and xz[i, 1] > 0 and (rel[i] < 0 <= rel[i + 1] or rel[i] > 0 >= rel[i + 1]):
            out.append(t[i] + (t[i + 1] - t[i]) * rel[i] / (rel[i] - rel[i + 1]))
    return out


@pytest.mark.parametrize("direction", ["up", "down"])
def test_a_worn_link_is_numbered_alike_whichever_way_the_chain_runs(direction, tmp_path, capsys):
    """The 90-link profile's chain with link 40 1 mm long, running up or down (drive.direction): a link marked by its
    rollers' arrivals at the top of the lower head numbers the worn link by how many links pass from it.  Running
    down the links pass in increasing number, so marking link 30 (rollers 30 then 31) makes link 40 the 11th;
    running up they pass in decreasing number, so marking link 50 (rollers 51 then 50) makes it the 11th too.  The
    unmarked number is the link at the sensor when the recording starts, counted the same way.  (The signature used to
    be simulated running up whatever the profile said: the down-running chain's link read 36 or 81 for 22.)"""
    from vibkit.diagnose.links import profile_scene_file
    from vibkit.model.profile import parse_profile

    text = PROFILE_90.replace("teeth = 28", f'teeth = 28\ndirection = "{direction}"')
    profile = tmp_path / f"E90-{direction}.toml"
    profile.write_text(text)
    scene = load_scene(profile_scene_file(parse_profile(text, "E90.toml")))
    pitch, n = scene.chain.link_pitch, scene.chain.n_rollers
    first, second = (51, 50) if direction == "up" else (30, 31)  # the marked link's rollers, in arrival order
    sc = dataclasses.replace(
        scene,
        chain=dataclasses.replace(scene.chain, worn_links=((40, pitch + 1e-3),)),
        outputs=dict(scene.outputs, variables=("delta", "sprocket_angle", "roller_position"), rollers=(first, second)),
    ).with_solver(closure="exact")
    settle = n * pitch / SPEED + 5.0
    ds = vibkit.simulate(sc, duration=settle + (3.2 * n + 3) * pitch / SPEED, progress=False)
    t = ds.time.values
    keep = t >= settle
    rng = np.random.default_rng(90)
    rec = xr.Dataset(
        {"delta": ("time", ds.delta.values[keep] + rng.normal(0, 1e-6, keep.sum()), {"units": "m"})},
        coords={"time": ("time", t[keep] - settle, {"units": "s"})},
    )
    rec.to_netcdf(tmp_path / "rec.nc")
    a = _arrivals(ds, first, settle + 5.0)[0]
    b = _arrivals(ds, second, a)[0]
    marker = 0.5 * (a + b) - settle
    marked = _links_with(
        tmp_path / "rec.nc", capsys, "--escalator", str(profile), "--marker", f"{marker:.6f}", "--json"
    )
    assert marked["direction"] == direction
    assert [f["link"] for f in marked["flagged"]] == [11]
    # unmarked: link 1 is the link at the sensor at the start; the rollers' positions give which one that is
    theta = ds.sprocket_angle.values
    passed = scene.sprocket.teeth * abs(float(np.interp(settle, t, theta) - theta[0])) / (2 * np.pi)
    at_start = link_number_of(40, passed, n, direction)
    # the same count from the marked link: it passed the sensor (marker - 0) * f_lp links after the start
    assert (at_start - 11 - math.floor(marker * SPEED / pitch)) % n in (0, n - 1, 1)
    plain = _links_with(tmp_path / "rec.nc", capsys, "--escalator", str(profile), "--json")
    assert [f["link"] for f in plain["flagged"]] == [at_start]
