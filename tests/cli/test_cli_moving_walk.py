"""Moving walks as a firm describes them (a level 40 m walk, an inclined 12 deg walk), on tensioner recordings
made without vibkit's simulator (a link-pass line of known frequency, its harmonic and white noise): `scene`,
`pitch`, `links`, `fleet add/status/report` each give a result or a one-line refusal naming the key; the pitch
comes out within its stated sigma of the truth; the report of a walk says "moving walk" and shows no climb."""

import json
import re

import numpy as np
import pytest

from vibkit.diagnose.report import write_report
from vibkit.model.profile import load_profile
from vibkit.model.scene import parse_scene

LEVEL = """[escalator]
unit = "W40"
site = "Airport, pier B"
description = "horizontal pallet walk, 40 m"
[drive]
speed = 0.75
speed_uncertainty = 0.0015  # tachometer on a pallet, 0.2 %
teeth = 25
[chain]
nominal_pitch = 0.13333
links_per_step = 3
[geometry]
length = 40.0
incline_deg = 0
[sensor]
kind = "tensioner"
"""

INCLINED = """[escalator]
unit = "W12"
site = "Hypermarket, car park ramp"
[drive]
speed = 0.5
teeth = 23
[chain]
nominal_pitch = 0.13333
links_per_step = 3
[geometry]
length = 16.0
incline_deg = 12
[sensor]
kind = "tensioner"
"""

#: the chain's true pitch: 0.5 % longer than new
ELONGATION = 0.005


def _tensioner_csv(path, speed, pitch, seconds=60.0, fs=200.0, amp=20e-6, noise=2e-6, seed=7):
    """A tensioner displacement record of a chain of ``pitch`` at ``speed``: the link pass and its second
    harmonic, white noise; in mm, as a displacement sensor's CSV export."""
    rng = np.random.default_rng(seed)
    t = np.arange(int(seconds * fs)) / fs
    ph = 2 * np.pi * speed / pitch * t
    x = amp * np.sin(ph) + 0.3 * amp * np.sin(2 * ph + 1.0) + noise * rng.standard_normal(t.size)
    rows = ["time (s),tensioner_displacement (mm)"] + [f"{a:.3f},{1000 * b:.6f}" for a, b in zip(t, x)]
    path.write_text("\n".join(rows) + "\n")
    return path


@pytest.fixture(scope="module")
def walks(tmp_path_factory):
    d = tmp_path_factory.mktemp("walks")
    out = {}
    for name, text, speed in (("level", LEVEL, 0.75), ("inclined", INCLINED, 0.5)):
        prof = d / f"{name}.toml"
        prof.write_text(text)
        rec = _tensioner_csv(d / f"{name}.csv", speed, 0.13333 * (1 + ELONGATION))
        out[name] = (prof, rec)
    return out


@pytest.mark.parametrize("name, incline", [("level", 0.0), ("inclined", 12.0)])
def test_scene_of_a_walk(run, walks, name, incline):
    prof, _ = walks[name]
    rc, out, err = run("scene", prof, "-o", "-")
    assert rc == 0, err
    assert out.startswith(f"# The scene of moving walk W{40 if incline == 0 else 12}")
    scene = parse_scene(out, "walk scene")
    assert scene.guide.incline_angle == pytest.approx(np.radians(incline))
    assert scene.guide.sprocket_centre[0] == pytest.approx(40.0 if incline == 0 else 16.0, abs=1e-6)


@pytest.mark.parametrize("name", ["level", "inclined"])
def test_pitch_of_a_walk_is_the_truth_within_its_sigma(run, walks, name):
    prof, rec = walks[name]
    rc, out, err = run("pitch", rec, "--escalator", prof, "--json")
    # a stated speed gives a verdict (exit 0); the rated speed's +-5 % none (3: the pitch and its sigma, inconclusive)
    assert rc == (0 if name == "level" else 3), err
    d = json.loads(out)
    truth = 0.13333 * (1 + ELONGATION)
    assert d["speed_source"].startswith("moving walk profile")
    # the speed's sigma (0.2 % stated; 2.9 % the standard's where not) dominates: the pitch within 2 sigma
    assert abs(d["pitch_m"] - truth) < 2 * d["pitch_sigma_m"]
    assert abs(d["elongation_percent"] - 100 * ELONGATION) < 2 * d["elongation_sigma_percent"]
    if name == "level":  # a stated speed: a verdict
        assert d["pitch_sigma_m"] < 0.0005 and d["status"] == "ok"


def test_links_of_a_walk_too_short_a_record_is_one_line_saying_how_long(run, walks):
    prof, rec = walks["level"]
    rc, out, err = run("links", rec, "--escalator", prof)
    # the derived count is a note; the refusal one line naming the recording and how long to record
    note, line = err.strip().splitlines()
    assert rc == 1 and note.startswith("note: ") and "624 links, filled in from its geometry (whole pallets" in note
    assert line.startswith("vibkit links: ") and str(rec) in line and "record at least" in line
    # 624 links at 5.60 Hz: a loop is 111 s, two of them 223 s
    n = int(re.search(r"chain's (\d+) links", line).group(1))
    assert n == 624
    seconds = float(re.search(r"record at least ([\d.]+) s", line).group(1))
    assert seconds == pytest.approx(2 * n / (0.75 / (0.13333 * (1 + ELONGATION))), rel=0.01)


def test_fleet_of_walks_add_status_report(run, walks, tmp_path):
    db = tmp_path / "fleet.sqlite"
    prof, rec = walks["level"]
    later = _tensioner_csv(tmp_path / "later.csv", 0.75, 0.13333 * (1 + 2 * ELONGATION), seed=8)
    for path, date in ((rec, "2026-05-04"), (later, "2026-11-30")):
        rc, out, err = run("fleet", "add", path, "--escalator", prof, "--date", date, "--db", db)
        assert rc == 0, err
        assert "unit W40" in out and "links: too few loops" in out
    iprof, irec = walks["inclined"]
    rc, out, err = run("fleet", "add", irec, "--escalator", iprof, "--date", "2026-11-30", "--db", db)
    assert rc == 0, err
    rc, out, err = run("fleet", "status", "--db", db, "--json")
    assert rc == 0, err
    units = {u["unit"]: u for u in json.loads(out)["units"]}
    assert set(units) == {"W40", "W12"}
    pdf = tmp_path / "fleet.pdf"
    rc, out, err = run("fleet", "report", "--db", db, "-o", pdf)
    assert rc == 0, err
    assert pdf.read_bytes().startswith(b"%PDF")


def test_the_report_of_a_walk_says_walk_and_shows_no_climb(walks, tmp_path):
    prof, rec = walks["level"]
    rep = write_report(rec, tmp_path / "w40.pdf", profile=load_profile(prof))
    first_title, first = rep.pages[0]
    text = "\n".join(first)
    assert "Moving walk drive-chain diagnostic" in text
    assert "moving walk profile W40" in text or "W40" in text
    titles = [t for t, _ in rep.pages]
    assert "recording and escalator" in titles[1] or "Recording and moving walk" in "\n".join(rep.pages[1][1])
    everything = "\n".join("\n".join(t) for _, t in rep.pages)
    for word in ("climb", "escalator W40", "Escalator drive-chain"):
        assert word not in everything, word
    assert not re.search(r"\brises?\b", everything)


def test_ride_on_a_level_walk_is_the_whole_record_with_no_climb(run, tmp_path):
    """A phone on a pallet of the level walk: no incline to find (the escalator's rule refuses such a record);
    the walk's ride is the whole record, said so, and nothing speaks of a climb."""
    fs, f = 200.0, 0.75 / 0.13333
    t = np.arange(int(40 * fs)) / fs
    rng = np.random.default_rng(4)
    acc = {
        "acc_x": 0.02 * np.sin(2 * np.pi * f * t) + 0.005 * rng.standard_normal(t.size),
        "acc_y": 0.005 * rng.standard_normal(t.size),
        "acc_z": 9.81 + 0.03 * np.sin(2 * np.pi * f * t) + 0.005 * rng.standard_normal(t.size),
    }
    rec = tmp_path / "pallet.csv"
    rows = ["time (s),acc_x (m/s^2),acc_y (m/s^2),acc_z (m/s^2)"]
    rows += [f"{a:.3f},{x:.5f},{y:.5f},{z:.5f}" for a, x, y, z in zip(t, *acc.values())]
    rec.write_text("\n".join(rows) + "\n")
    prof = tmp_path / "w40.toml"
    prof.write_text(LEVEL.replace('kind = "tensioner"', 'kind = "step"\nstep = 3'))
    rc, out, err = run("ride", rec, "--escalator", prof, "--json")
    assert rc == 0, err
    d = json.loads(out)
    assert d["segment"]["method"] == "whole record" and d["segment"]["end_s"] == pytest.approx(40.0, abs=0.01)
    assert "level moving walk" in d["segment"]["note"]
    assert "climb" not in out.replace("no climb", "") and "incline" not in out
    # the escalator's rule on the same record: no incline found, refused naming --segment
    rc, _, err = run("ride", rec)
    assert rc == 1 and "no incline found" in err and "--segment" in err


def test_a_profile_with_links_alone_is_built_as_an_escalator_and_scene_says_so(run, tmp_path):
    """`chain.n_links` without geometry: a 30 deg escalator whose rise follows from the count, said on stderr (it
    was silent: a walk described so became an 18.7 m escalator)."""
    prof = tmp_path / "links-only.toml"
    prof.write_text(LEVEL.split("[geometry]")[0].replace("links_per_step = 3", "links_per_step = 3\nn_links = 624"))
    rc, out, err = run("scene", prof, "-o", "-")
    assert rc == 0, err
    note = next(line for line in err.splitlines() if "states no geometry" in line)
    rise = float(re.search(r"whose rise \(([\d.]+) m\)", note).group(1))
    assert rise > 15 and "geometry.length" in note and "30 deg" in note
    assert "# The scene of escalator W40" in out


@pytest.mark.parametrize(
    "geometry, key",
    [("rise = 0\nincline_deg = 0", "geometry.length"), ("length = 40.0\nincline_deg = 30", "12 deg at most")],
)
def test_scene_refuses_a_profile_that_is_neither_in_one_line(run, tmp_path, geometry, key):
    prof = tmp_path / "neither.toml"
    prof.write_text(LEVEL.split("[geometry]")[0] + "[geometry]\n" + geometry + "\n")
    rc, out, err = run("scene", prof, "-o", "-")
    lines = err.strip().splitlines()
    assert rc == 1 and out == "" and len(lines) == 1
    assert str(prof) in lines[0] and key in lines[0] and "geometry.incline_deg" in lines[0]
