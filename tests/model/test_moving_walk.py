"""Moving walks (EN 115-1: pallet walks, level or inclined up to 12 deg) as a firm describes them: by
`[geometry] length` between the heads and `incline_deg`. Geometry truths of the guide that follows: the plan
length between the heads is the one stated, the straight runs have the stated incline, a level walk has no
rise, the derived link count closes on the guide (closure residual nil, the tensioner within its travel), and a
count that cannot close, or a profile that describes neither an escalator nor a walk, is refused in one line
naming the keys."""

import math
import re

import numpy as np
import pytest

from vibkit.model.chain import Chain
from vibkit.model.escalator import EscalatorModel
from vibkit.model.guide import LEN0, PHI0, S0, SEGMENT_NAMES, Guide
from vibkit.model.profile import parse_profile
from vibkit.model.profile_scene import closing_travel, geometry_note, link_count
from vibkit.model.scene import SceneError

#: a 40 m level walk at an airport, as the firm's drawings describe it (0.75 m/s, 133.33 mm pallet chain)
LEVEL = """
[escalator]
unit = "W40"
site = "Airport, pier B"
description = "horizontal pallet walk, 40 m"
[drive]
speed = 0.75
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

#: an inclined walk of a supermarket, 12 deg (the most EN 115-1 allows), rated 0.5 m/s
INCLINED = """
[escalator]
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
"""


def _profile(text, **edits):
    for k, v in edits.items():
        text = re.sub(rf"^{k} = .*$", f"{k} = {v}", text, flags=re.M)
    return parse_profile(text, "walk.toml")


@pytest.mark.parametrize("text, length, incline", [(LEVEL, 40.0, 0.0), (INCLINED, 16.0, 12.0)])
def test_the_guide_follows_the_length_and_incline_and_the_derived_count_closes(text, length, incline):
    prof = _profile(text)
    assert prof.is_walk and prof.kind == "moving walk" and geometry_note(prof) is None
    scene = prof.scene("forward")
    guide = Guide(scene.guide)
    tab = guide.table
    # the heads' axles are the stated length apart in plan (the tensioner at rest); the sprocket's axle is as high
    # as the walk climbs between the landings: L sin(a) + 2 r_t (1 - cos(a)) (a level walk: none)
    xc, zc = scene.guide.sprocket_centre
    assert xc == pytest.approx(length, abs=1e-6)  # (the scene's text gives the incline's length to the micrometre)
    a = math.radians(incline)
    top = SEGMENT_NAMES.index("incline, top run")
    ret = SEGMENT_NAMES.index("incline, return run")
    rise = tab[top, LEN0] * math.sin(a) + 2 * scene.guide.transition_radius * (1 - math.cos(a))
    assert zc == pytest.approx(rise, abs=1e-9)
    # the straight runs have the stated incline, both ways round the loop (points, not only the table's heading)
    for k, sign in ((top, 1.0), (ret, -1.0)):
        s = tab[k, S0] + np.array([0.1, 0.5, 0.9]) * tab[k, LEN0]
        xz = guide.position(guide.s0_to_s(s))
        dx, dz = np.diff(xz[:, 0]), np.diff(xz[:, 1])
        assert np.all(np.sign(dx) == sign) and np.all(dz * sign >= 0)  # top run forward and up, return back and down
        assert np.allclose(np.degrees(np.arctan(np.abs(dz / dx))), incline, atol=1e-9)
        assert math.remainder(tab[k, PHI0] - (a if sign > 0 else math.pi + a), 2 * math.pi) == pytest.approx(
            0, abs=1e-12
        )
    if incline == 0.0:
        assert zc == 0.0
        # landings without transitions: the transition segments are empty, the top run one straight at z = R
        for name in ("lower transition", "upper transition", "upper transition, return", "lower transition, return"):
            assert tab[SEGMENT_NAMES.index(name), LEN0] == 0.0
        s = np.linspace(0.0, guide.perimeter(0.0), 400, endpoint=False)
        assert np.ptp(guide.position(s)[:, 1]) == pytest.approx(2 * scene.guide.head_radius, abs=1e-9)
    # the derived count: whole pallets, and the chain closes on the guide with roller 1 anywhere round the loop
    n, src = link_count(prof)
    assert n == scene.chain.n_rollers and n % 3 == 0 and "pallets" in src
    chain = Chain(guide, scene.chain)
    pitch = scene.chain.link_pitch
    for s0 in np.linspace(0.0, guide.p0, 5, endpoint=False):
        conf = chain.configure(float(s0))
        pos = conf.position
        links = np.hypot(*(np.roll(pos, -1, axis=0) - pos).T)
        assert np.max(np.abs(links - pitch)) < 1e-9  # closure residual: every link, the last one closing the loop
        assert abs(conf.delta) < closing_travel(scene.guide.tensioner_length)
    # the chain's length is the guide's closed length less the tensioner's take-up (chords across the heads'
    # arcs are shorter than the arcs by (pitch^2 / 24 R^2) of them)
    arcs = 2 * math.pi * scene.guide.head_radius + 4 * a * scene.guide.transition_radius
    chord = arcs * pitch**2 / (24 * scene.guide.head_radius**2)
    assert n * pitch == pytest.approx(guide.perimeter(conf.delta) - chord, abs=0.2 * pitch)


def test_a_drawn_count_that_closes_is_built_and_one_that_cannot_names_length_and_the_counts_that_do():
    n, _ = link_count(_profile(LEVEL))
    text = LEVEL.replace("links_per_step = 3", f"links_per_step = 3\nn_links = {n + 2}")
    assert _profile(text).scene("forward").chain.n_rollers == n + 2
    with pytest.raises(SceneError) as exc:
        _profile(LEVEL.replace("links_per_step = 3", f"links_per_step = 3\nn_links = {n + 30}")).scene("forward")
    msg = str(exc.value)
    assert msg.startswith("walk.toml: ") and "\n" not in msg and "converge" not in msg
    assert "chain.n_links" in msg and "geometry.length" in msg and "rise" not in msg
    lo, hi = (int(v) for v in re.search(r"close on this length are (\d+) to (\d+)", msg).groups())
    assert lo <= n <= hi < n + 30
    g_lo, g_hi = (float(v) for v in re.search(r"on a length of ([\d.]+) to ([\d.]+) m", msg).groups())
    # 30 links more need 2 m more loop: the walk 2 m longer (one metre of length is two of loop on a level walk)
    assert g_lo < 40.0 + 15 * 0.13333 < g_hi


@pytest.mark.parametrize(
    "geometry, words",
    [
        ("length = 40.0\nincline_deg = 30", ["geometry.length", "12 deg at most", "geometry.rise"]),
        ("rise = 0\nincline_deg = 0", ["neither an escalator nor a moving walk", "geometry.length"]),
        ("rise = 4.0\nlength = 20.0\nincline_deg = 30", ["not both", "geometry.rise", "geometry.length"]),
        ("length = 40.0", ["missing value 'geometry.incline_deg'", "geometry.length"]),
        ("incline_deg = 0", ["neither an escalator nor a moving walk", "geometry.rise", "geometry.length"]),
        ("length = 1.0\nincline_deg = 0", ["'geometry.length' = 1.0", "plausible range"]),
    ],
)
def test_a_profile_that_describes_neither_an_escalator_nor_a_walk_is_refused_in_one_line(geometry, words):
    text = LEVEL.split("[geometry]")[0] + "[geometry]\n" + geometry + "\n"
    with pytest.raises(SceneError) as exc:
        parse_profile(text, "walk.toml")
    msg = str(exc.value)
    assert msg.startswith("walk.toml: ") and "\n" not in msg
    for w in words:
        assert w in msg


def test_a_walk_too_short_for_its_heads_names_the_length():
    with pytest.raises(SceneError, match=r"'geometry.length' = 2 m is shorter than a moving walk's heads"):
        _profile(LEVEL, length="2.0").scene("forward")


def test_links_alone_build_an_escalator_and_say_so():
    """`chain.n_links` without geometry: an escalator of the common 30 deg incline, said in the scene's text."""
    prof = parse_profile(LEVEL.split("[geometry]")[0].replace("links_per_step = 3", "n_links = 159"), "e.toml")
    assert not prof.is_walk and prof.kind == "escalator"
    note = geometry_note(prof)
    assert "states no geometry" in note and "geometry.length" in note and "30 deg" in note
    assert f"# NOTE: {note}." in prof.scene_text("forward")


def test_the_walk_is_level_in_the_model_and_its_pallets_are_of_its_pitch():
    prof = _profile(LEVEL, length="12.0")
    model = EscalatorModel(prof.scene("forward"))
    conf = model.chain.configure(0.0)
    z = conf.position[:, 1]
    r = model.scene.guide.head_radius
    # every roller on the top or return run (or round a head): no roller above the top run or below the return run
    assert z.max() <= r + 1e-9 and z.min() >= -r - 1e-9
    # a pallet is links_per_step links of the walk's pitch: its first and last rollers two pitches apart on a straight
    top = SEGMENT_NAMES.index("incline, top run")
    on_top = np.flatnonzero(
        np.array([model.guide.segment_at(model.guide.s0_to_s(s)) for s in conf.s0 % model.guide.p0]) == top
    )
    j = int(on_top[len(on_top) // 2])
    rollers = model.step_rollers(j // 3 + 1)
    assert set(rollers) <= set(on_top)
    span = np.hypot(*(conf.position[rollers[-1]] - conf.position[rollers[0]]))
    assert span == pytest.approx(2 * prof.nominal_pitch, abs=1e-9)
