"""A maintenance firm's own units, end to end through the command line: three profiles written from the docs alone
(a down-running metro escalator of 101.6 mm chain, 4 links a step, 25 teeth and the drawings' 408 links; an
inclined 12 deg pallet walk; a 20 m level walk at 0.75 m/s) and tensioner recordings made without vibkit's
simulator, from the chain's kinematics: the link pass at v / p and its second harmonic, one worn link's loop-period
signature where `links` is to find it, white noise. `scene`, `simulate --check`, `pitch`, `links`, `report`,
`fleet add/status/report` each give a result that matches the synthesised truth within its stated sigma, or a
one-line refusal naming the key (no traceback, no solver message).

The worn link's signature is written from the geometry, not taken from the model: a link longer by ``e`` spans
an arc ``e / cos(pi / Z)`` on a head of ``Z`` teeth' pitch radius instead of ``e`` on a straight, so while it is
wrapped on the sprocket or on the lower head (``Z / 2`` link passes each, half a loop apart) the chain holds
``e (sec(pi / Z) - 1)`` more of its guide and the tension carriage moves in by half of that. (The model's
signature of a 1 mm link has the same two plateaus, 11-12 links long, at two thirds of this first estimate, its
kinematics alone too: the worn link also shifts the links straddling the heads' tangent points, whose share of the
guide follows the polygon's phase. So `links` reads a synthesised 1 mm link as about 1.4 mm; the 0.8 mm link
written here reads about 1.15 mm, within the 0.5 to 2 mm asserted below, and under the 1.25 mm above which `links`
fits again with a longer link's signature: two more of the driven chain's signature runs, which
`tests/diagnose/test_links.py` shows.)"""

import json
import math
import re

import numpy as np
import pytest

from vibkit.model.scene import parse_scene

METRO = """[escalator]
unit = "M7"
site = "Metro, line 2, Central station, exit B"
description = "down escalator, 101.6 mm chain, 4 links a step"

[drive]
speed = 0.65                # measured on the steps with a tachometer
speed_uncertainty = 0.0013  # [m/s], 0.2 %
teeth = 25
direction = "down"

[chain]
nominal_pitch = 0.1016
links_per_step = 4
n_links = 408               # from the drawings

[geometry]
rise = 8.35
incline_deg = 30

[sensor]
kind = "tensioner"
"""

LEVEL = """[escalator]
unit = "W20"
site = "Airport, pier B"
description = "horizontal pallet walk, 20 m"

[drive]
speed = 0.75
speed_uncertainty = 0.0015  # [m/s], measured on a pallet
teeth = 25

[chain]
nominal_pitch = 0.13333
links_per_step = 3          # links per pallet

[geometry]
length = 20.0               # [m] between the heads' axles
incline_deg = 0

[sensor]
kind = "tensioner"
"""

INCLINED = """[escalator]
unit = "W12"
site = "Hypermarket, car park ramp"
description = "inclined pallet walk, 12 degrees"

[drive]
speed = 0.5
speed_uncertainty = 0.001
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

#: the chain's true pitch in every recording: 1 % longer than new
ELONGATION = 0.01
FS = 100.0  # [Hz]: 16 or more samples a link pass (3.7-6.4 Hz), as `links` asks (80 Hz or more)
EXCESS = 0.8e-3  # [m]: the worn link's excess pitch

#: name: (profile, speed [m/s], nominal pitch [m], teeth, direction, the chain's true links, the worn link or None)
UNITS = {
    "metro": (METRO, 0.65, 0.1016, 25, "down", 408, 100),
    "level": (LEVEL, 0.75, 0.13333, 25, "up", 324, 200),  # 43.34 m of loop: 325.1 links, 108 whole pallets of 3
    "inclined": (INCLINED, 0.5, 0.13333, 23, "up", 267, None),  # a healthy chain: nothing to flag
}


def tensioner_csv(path, *, speed, pitch, n_links, teeth, direction, worn, loops, elongation=ELONGATION, seed=1):
    """A tensioner displacement record (mm, a displacement sensor's CSV) of a chain of ``n_links`` links of
    ``pitch x (1 + elongation)`` at ``speed``: 20 um at the link pass, 6 um at its second harmonic, 1 um of white
    noise, and link ``worn`` (1: the link at the sensor, over the lower head, at the start; None: none)
    ``EXCESS`` longer: the tension carriage in by ``EXCESS (sec(pi / Z) - 1) / 2`` while it is wrapped on the lower
    head (running up, the ``Z / 2`` passes before it reaches the sensor; down, those after) and on the sprocket
    (the same, half a loop away)."""
    rng = np.random.default_rng(seed)
    f = speed / (pitch * (1 + elongation))
    t = np.arange(int(loops * n_links / f * FS)) / FS
    ph = 2 * np.pi * f * t
    x = 20e-6 * np.sin(ph) + 6e-6 * np.sin(2 * ph + 1.0) + 1e-6 * rng.standard_normal(t.size)
    if worn is not None:
        u = (f * t + 0.37 - (worn - 1)) % n_links  # links since the worn one passed the sensor (0.37: mid-passage)
        half = teeth / 2
        if direction == "up":
            wrapped = (u > n_links - half) | ((u > n_links / 2 - half) & (u < n_links / 2))
        else:
            wrapped = (u < half) | ((u > n_links / 2) & (u < n_links / 2 + half))
        x -= EXCESS * (1 / math.cos(math.pi / teeth) - 1) / 2 * wrapped
    rows = ["time (s),tensioner_displacement (mm)"] + [f"{a:.3f},{1e3 * b:.6f}" for a, b in zip(t, x)]
    path.write_text("\n".join(rows) + "\n")
    return path


@pytest.fixture(scope="module")
def units(tmp_path_factory):
    """Each unit's profile and a recording of 3.2 loops (the level walk's loop is 58 s)."""
    d = tmp_path_factory.mktemp("firm")
    out = {}
    for name, (text, speed, pitch, teeth, direction, n, worn) in UNITS.items():
        prof = d / f"{name}.toml"
        prof.write_text(text)
        rec = tensioner_csv(
            d / f"{name}.csv", speed=speed, pitch=pitch, n_links=n, teeth=teeth, direction=direction, worn=worn,
            loops=3.2,
        )  # fmt: skip
        out[name] = (prof, rec)
    return out


def _no_solver_words(text):
    for word in ("Traceback", "converge", "s0_1", "status="):
        assert word not in text, text


@pytest.mark.parametrize("name", list(UNITS))
def test_scene_builds_the_unit_the_drawings_describe(run, units, name):
    _, speed, pitch, teeth, direction, n, _ = UNITS[name]
    prof, _ = units[name]
    rc, out, err = run("scene", prof, "-o", "-")
    assert rc == 0, err
    _no_solver_words(err)
    scene = parse_scene(out, f"{name} scene")
    assert scene.chain.n_rollers == n and scene.chain.link_pitch == pytest.approx(pitch)
    assert scene.sprocket.teeth == teeth
    assert scene.guide.incline_angle == pytest.approx(math.radians({"metro": 30, "level": 0, "inclined": 12}[name]))
    # the drawings' count is said as given; a derived one as derived
    assert ("# chain.n_links" in out) == (name == "metro")
    assert out.startswith("# The scene of " + ("escalator" if name == "metro" else "moving walk"))
    if name != "metro":
        # a walk: the heads' axles 'length' apart in plan
        assert scene.guide.sprocket_centre[0] == pytest.approx(20.0 if name == "level" else 16.0, abs=1e-6)


def test_a_drawn_count_that_cannot_close_is_refused_naming_the_keys(run, units, tmp_path):
    """The drawings' 408 links on a rise they cannot close (9 m): one line naming both keys and what closes."""
    prof = tmp_path / "m7-9m.toml"
    prof.write_text(METRO.replace("rise = 8.35", "rise = 9.0"))
    _, rec = units["metro"]
    for argv in (("scene", prof, "-o", "-"), ("pitch", rec, "--escalator", prof), ("links", rec, "--escalator", prof)):
        rc, out, err = run(*argv)
        if argv[0] == "pitch":  # pitch needs no closed loop: the link pass and the pitch only
            assert rc == 0, err
            continue
        lines = err.strip().splitlines()
        assert rc == 1 and len(lines) == 1, err
        assert str(prof) in lines[0] and "chain.n_links" in lines[0] and "geometry.rise" in lines[0]
        assert "408 links close on a rise of" in lines[0]
        _no_solver_words(lines[0])


@pytest.mark.parametrize("name", list(UNITS))
def test_simulate_check_of_the_scene(run, units, name, tmp_path):
    prof, _ = units[name]
    scene = tmp_path / "scene.toml"
    assert run("scene", prof, "-o", scene)[0] == 0
    rc, out, err = run("simulate", scene, "-o", tmp_path / "run.nc", "--duration", "1.5", "--check", "--json")
    assert rc == 0, err
    _no_solver_words(err)
    d = json.loads(out)
    check = d["convergence"]
    # converged at the defaults, or the check says at which rtol it is
    assert check["converged"] or re.search(r"rtol", check["message"]), check["message"]
    assert not d["warnings"], d["warnings"]


@pytest.mark.parametrize("name", list(UNITS))
def test_pitch_is_the_truth_within_its_sigma(run, units, name):
    _, speed, pitch, *_ = UNITS[name]
    prof, rec = units[name]
    rc, out, err = run("pitch", rec, "--escalator", prof, "--json")
    assert rc == 0, err
    d = json.loads(out)
    truth = pitch * (1 + ELONGATION)
    assert abs(d["pitch_m"] - truth) < 2 * d["pitch_sigma_m"] and d["pitch_sigma_m"] < 0.003 * truth
    assert abs(d["elongation_percent"] - 100 * ELONGATION) < 2 * d["elongation_sigma_percent"]
    # the link pass the recording was made with, within 3 of its (noise's) sigmas
    assert abs(d["fundamental_hz"] - speed / truth) < 3 * d["fundamental_sigma_hz"]
    assert d["status"] == "ok"


@pytest.mark.parametrize("name", list(UNITS))
def test_links_finds_the_worn_link_or_none(run, units, name):
    _, speed, pitch, teeth, direction, n, worn = UNITS[name]
    prof, rec = units[name]
    rc, out, err = run("links", rec, "--escalator", prof, "--json")
    assert rc == 0, err
    _no_solver_words(err)
    d = json.loads(out)
    assert d["n_links"] == n and d["direction"] == direction
    if worn is None:
        assert d["flagged"] == []
        return
    (flag,) = d["flagged"]
    # the worn link by number (or among the two the recording cannot tell apart, half a loop away)
    named = [flag["link"], *flag["alternatives"]]
    assert any(min(abs(k - worn), n - abs(k - worn)) <= 1 for k in named), named
    assert 0.5 < flag["excess_pitch_mm"] < 2.0 and flag["sigma_mm"] < 0.05


def test_report_of_the_metro_unit_says_its_count_and_link(run, units, tmp_path):
    prof, rec = units["metro"]
    pdf = tmp_path / "m7.pdf"
    rc, out, err = run("report", rec, "--escalator", prof, "-o", pdf, "--json")
    assert rc == 0, err
    _no_solver_words(err)
    d = json.loads(out)
    s = d["summary"] if "summary" in d else d
    assert s["n_links"] == 408 and s["n_links_from"] == "chain.n_links of the profile"
    assert abs(s["pitch_m"] - 0.1016 * (1 + ELONGATION)) < 2 * s["pitch_sigma_m"]
    assert s["verdict"] == "ok"
    assert pdf.read_bytes().startswith(b"%PDF")


def test_fleet_of_the_firms_units(run, units, tmp_path):
    """Four visits of the metro unit (0 to 1 % over two years: 0.5 %/year) and one of each walk: `fleet add`
    stores each; `status` gives the metro's rate within its sigma and a forecast of the next limit; `report`
    writes the PDF."""
    db = tmp_path / "fleet.sqlite"
    _, speed, pitch, teeth, direction, n, worn = UNITS["metro"]
    prof, rec = units["metro"]
    visits = [("2024-11-30", 0.0), ("2025-07-31", 0.00333), ("2026-03-31", 0.00667)]
    for i, (date, e) in enumerate(visits):  # the earlier visits' records shorter than two loops: links not scanned
        early = tensioner_csv(
            tmp_path / f"m7-{date}.csv", speed=speed, pitch=pitch, n_links=n, teeth=teeth, direction=direction,
            worn=worn, loops=1.0, elongation=e, seed=10 + i,
        )  # fmt: skip
        rc, out, err = run("fleet", "add", early, "--escalator", prof, "--date", date, "--db", db)
        assert rc == 0, err
        assert "unit M7" in out and "links: too few loops" in out
    rc, out, err = run("fleet", "add", rec, "--escalator", prof, "--date", "2026-11-30", "--db", db)
    assert rc == 0, err
    # the worn link (100) by number within one, as `links` names it (the scene's phase is the driven chain's)
    named = re.search(r"links (\d+) or (\d+)\)", out)
    assert "unit M7" in out and named, out
    assert any(min(abs(int(k) - worn), n - abs(int(k) - worn)) <= 1 for k in named.groups()), out
    for name in ("level", "inclined"):
        wprof, wrec = units[name]
        rc, out, err = run("fleet", "add", wrec, "--escalator", wprof, "--date", "2026-11-30", "--db", db)
        assert rc == 0, err
        _no_solver_words(out + err)
    rc, out, err = run("fleet", "status", "--db", db, "--json")
    assert rc == 0, err
    units_ = {u["unit"]: u for u in json.loads(out)["units"]}
    assert set(units_) == {"M7", "W20", "W12"}
    m7 = units_["M7"]
    rate, sigma = m7["slope_percent_per_year"], m7["slope_sigma_percent_per_year"]
    assert m7["n_measurements"] == 4 and abs(rate - 0.5) < 2 * sigma
    nxt = m7["next_limit"]
    # 1.5 % from 1.0 % on 2026-11-30 at 0.5 %/year: a year on, within the forecast's 2-sigma interval
    assert nxt["limit_percent"] == 1.5 and nxt["status"] == "forecast" and not nxt["overdue"]
    assert nxt["earliest_utc"] <= "2027-11-30" <= nxt["latest_utc"]
    pdf = tmp_path / "fleet.pdf"
    rc, out, err = run("fleet", "report", "--db", db, "-o", pdf)
    assert rc == 0, err
    _no_solver_words(err)
    assert pdf.read_bytes().startswith(b"%PDF")
