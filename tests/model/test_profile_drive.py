"""A profile's scene drives its chain as a real unit's drive does: a running resistance, the
profile's ``drive.no_load_power`` where it states one, else TfL's typical figure (2 kW of friction on a 15 m escalator
at 0.75 m/s: 88.9 N per metre of loop), and a PI drive, so that once at speed the sprocket's teeth always carry the
chain; the drive power the simulation gives (torque x angular speed) is the stated or typical one; the solver's
defaults converge (``--check``) on the shipped profiles as they are, a down-running one and a 3 % worn chain.
``no_load_power = 0`` gives the coasting scene of before (no resistance, the reference's P drive)."""

import dataclasses
import math
from pathlib import Path

import numpy as np
import pytest

import vibkit
from vibkit.model.profile import load_profile, parse_profile
from vibkit.model.profile_scene import profile_scene, scene_text
from vibkit.model.scene import SceneError, parse_scene

from support.profiles import PROFILE_90

ROOT = Path(__file__).resolve().parents[2]
SHIPPED = sorted((ROOT / "data" / "fleet-example" / "escalators").glob("*.toml"))
#: a down escalator of 101.6 mm chain, 4 links a step, 25 teeth, whose firm states its no-load drive power
DOWN_STATED = """[escalator]
unit = "M4"
[drive]
speed = 0.65
speed_uncertainty = 0.0013
teeth = 25
direction = "down"
no_load_power = 1500.0
[chain]
nominal_pitch = 0.1016
links_per_step = 4
n_links = 208
[sensor]
kind = "tensioner"
"""
#: 2000 W / 0.75 m/s over the two 15 m strands of TfL's escalator: the figure's own arithmetic, not vibkit's
TFL_N_PER_M = 2000.0 / 0.75 / 30.0


def _profiles():
    """The shipped profiles and a 90-link one as they are (no power stated: the typical figure), and a down-running
    unit whose firm states its power."""
    out = [(p.stem, load_profile(p)) for p in SHIPPED]
    out.append(("E90", parse_profile(PROFILE_90, "E90.toml")))
    out.append(("M4 down, stated", parse_profile(DOWN_STATED, "M4.toml")))
    return out


def _expected_power(profile, n_links):
    """The no-load drive power [W]: the profile's, else TfL's figure over the loop (n_links x pitch) at the speed,
    computed from TfL's own numbers."""
    if profile.no_load_power is not None:
        return profile.no_load_power
    return TFL_N_PER_M * n_links * profile.nominal_pitch * abs(profile.speed)


def _run(profile, *, elongation=None, check=False, duration=12.0):
    text = scene_text(profile, duration=duration).replace('"accel_step"]', '"accel_step", "contact_force"]')
    if elongation is not None:
        text = text.replace("[sprocket]", f"elongation_percent = {elongation!r}\n\n[sprocket]", 1)
    scene = parse_scene(text, f"{profile.source} (scene)")
    return scene, vibkit.simulate(scene, progress=False, check=check)


@pytest.mark.parametrize("name,profile", _profiles(), ids=[n for n, _ in _profiles()])
def test_the_teeth_carry_the_drive_at_the_stated_power(name, profile):
    scene, ds = _run(profile)
    t = ds.time.values
    steady = t >= 2.0  # the start: the PI controller takes up the resistance within a second
    force = np.abs(ds["contact_force"].values).sum(axis=1)
    # never without tooth load for longer than one link pass once at speed
    passing = scene.chain.link_pitch / abs(profile.speed)
    dt = float(t[1] - t[0])
    free = force[steady] <= 1.0
    longest, run = 0, 0
    for f in free:
        run = run + 1 if f else 0
        longest = max(longest, run)
    assert longest * dt < passing, f"{name}: {longest * dt:.3f} s without tooth load (a link pass {passing:.3f} s)"
    # the drive's power: torque x angular speed, as stated (or the typical figure), within 2 %
    power = ds["motor_torque"].values * ds["sprocket_speed"].values
    want = _expected_power(profile, scene.chain.n_rollers)
    assert float(np.mean(power[steady])) == pytest.approx(want, rel=0.02)
    # the speed held: the mean chain speed (a magnitude) over the steady part is the rated one within 0.2 %
    assert float(np.mean(ds["chain_speed"].values[steady])) == pytest.approx(abs(profile.speed), rel=2e-3)
    assert "coasts" not in ds.attrs.get("notes", "")
    # the link pass the result states is counted after the drive took up the load (its second half): the rated one
    assert ds.attrs["link_pass_frequency_hz"] == pytest.approx(abs(profile.speed) / profile.nominal_pitch, rel=3e-4)


@pytest.mark.parametrize("which", ["E07", "E21", "M4 down, stated", "E07 worn 3 %"])
def test_the_defaults_converge(which):
    profiles = dict(_profiles())
    profile = profiles[which.split(" worn")[0]]
    _, ds = _run(profile, elongation=3.0 if "worn" in which else None, check=True, duration=None)  # the 20 s default
    assert int(ds.attrs["converged"]) == 1, ds.attrs.get("convergence")


def test_a_power_the_chain_cannot_resist_names_the_key(tmp_path):
    p = parse_profile(DOWN_STATED.replace("no_load_power = 1500.0", "no_load_power = 90000.0"), "big.toml")
    with pytest.raises(SceneError, match=r"big.toml: 'drive.no_load_power' = 90000 W at 0.65 m/s is more than"):
        profile_scene(p)


def test_without_a_stated_power_the_scene_says_it_took_the_typical_one():
    text = scene_text(load_profile(SHIPPED[0]))
    line = next(s for s in text.splitlines() if s.startswith("rolling_resistance"))
    assert "filled: typical 88.9 N per metre of loop" in line and "drive.no_load_power states the unit's" in line


def test_a_stated_zero_power_gives_the_coasting_scene():
    profile = dataclasses.replace(load_profile(SHIPPED[0]), no_load_power=0.0)
    text = scene_text(profile)
    assert "motor = { kp = 600.0, speed = 0.5 }" in text and "rolling_resistance" not in text
    assert "# no running resistance (drive.no_load_power = 0): the chain coasts at speed" in text


def test_the_scene_says_where_its_resistance_came_from():
    stated = scene_text(parse_profile(DOWN_STATED, "M4.toml"))
    line = next(s for s in stated.splitlines() if s.startswith("rolling_resistance"))
    assert "drive.no_load_power 1500 W at 0.65 m/s" in line
    mu = float(line.split("=")[2].split("}")[0])
    mass = 208 * 60.0 * 0.1016  # the scene's 60 kg per metre of chain and steps
    assert mu == pytest.approx(1500.0 / (9.81 * mass * 0.65), rel=1e-5)
    assert math.isclose(TFL_N_PER_M, 88.888, rel_tol=1e-4)
