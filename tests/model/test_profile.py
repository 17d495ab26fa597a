"""Escalator profiles: the user's machine in a small TOML; bad keys are one-line errors naming file and key."""

import math
from pathlib import Path

import numpy as np
import pytest

import vibkit
from vibkit.model.profile import STANDARD_SPEED_TOLERANCE, load_profile, parse_profile, profile_table
from vibkit.model.scene import SceneError

MINIMAL = """
[escalator]
unit = "E07"
site = "Leon, Plaza Mayor"
[drive]
speed = 0.5
[chain]
nominal_pitch = 0.13333
n_links = 160
"""


def test_minimal_profile_loads_with_defaults(tmp_path):
    p = tmp_path / "e07.toml"
    p.write_text(MINIMAL)
    prof = load_profile(p)
    assert (prof.unit, prof.site, prof.speed, prof.nominal_pitch, prof.n_links) == (
        "E07",
        "Leon, Plaza Mayor",
        0.5,
        0.13333,
        160,
    )
    assert (prof.links_per_step, prof.teeth, prof.rise, prof.sensor) == (3, 28, None, None)
    assert prof.source == str(p)


def test_speed_sigma_stated_or_from_the_standard():
    prof = parse_profile(MINIMAL)
    sigma, why = prof.speed_sigma
    # +-5 % taken as a uniform band: sigma = 5 % / sqrt(3) of the speed
    assert sigma == pytest.approx(0.5 * STANDARD_SPEED_TOLERANCE / math.sqrt(3), rel=1e-12)
    assert prof.speed_sigma_from_standard and "EN 115-1" in why
    stated = parse_profile(MINIMAL.replace("speed = 0.5", "speed = 0.5\nspeed_uncertainty = 0.001"))
    assert stated.speed_sigma[0] == 0.001 and not stated.speed_sigma_from_standard


def test_geometry_instead_of_links_and_sensor():
    text = MINIMAL.replace("n_links = 160", "links_per_step = 4") + (
        '[geometry]\nrise = 4.5\nincline_deg = 30\n[sensor]\nkind = "step"\nstep = 12\n'
    )
    prof = parse_profile(text)
    assert (prof.n_links, prof.rise, prof.incline_deg, prof.links_per_step) == (None, 4.5, 30.0, 4)
    assert (prof.sensor.kind, prof.sensor.step) == ("step", 12)
    assert prof.sensors == {} and prof.on_step


def test_sensors_per_channel():
    """[sensors.NAME] gives one channel its sensor; [sensor] stays the default of the others."""
    text = (
        MINIMAL
        + '[sensor]\nkind = "phone"\n[sensors.lvdt]\nkind = "tensioner"\n[sensors.acc]\nkind = "step"\nstep = 4\n'
    )
    prof = parse_profile(text)
    assert prof.sensor.kind == "phone" and prof.on_step
    assert {k: (v.kind, v.step) for k, v in prof.sensors.items()} == {"lvdt": ("tensioner", None), "acc": ("step", 4)}


@pytest.mark.parametrize(
    "edit, pattern",
    [
        (lambda t: t.replace('unit = "E07"', ""), r"missing value 'escalator.unit'"),
        (lambda t: t.replace("speed = 0.5", ""), r"missing value 'drive.speed'"),
        (lambda t: t.replace("nominal_pitch = 0.13333", ""), r"missing value 'chain.nominal_pitch'"),
        (lambda t: t.replace("n_links = 160", ""), r"missing value 'chain.n_links' or the geometry"),
        (lambda t: t.replace("speed = 0.5", "speed = 50"), r"'drive.speed' = 50.0 is outside"),
        (lambda t: t.replace("speed = 0.5", "speed = 2.34"), r"'drive.speed' = 2.34 is outside .* km/h\?"),
        (lambda t: t.replace("speed = 0.5", 'speed = "fast"'), r"'drive.speed' expected float"),
        (lambda t: t.replace("n_links = 160", "n_links = 160\nlinks_per_step = 5"), r"'chain.links_per_step' = 5"),
        (lambda t: t.replace("n_links = 160", "n_links = 160\ncolour = 1"), r"unknown key 'chain.colour'"),
        (lambda t: t + "[motor]\nkp = 1\n", r"unknown section \[motor\]"),
        (lambda t: t + '[sensor]\nkind = "wall"\n', r"'sensor.kind' must be one of tensioner, step, phone"),
        (lambda t: t + '[sensors.az]\nkind = "wall"\n', r"'sensors.az.kind' must be one of tensioner, step, phone"),
        (lambda t: t + '[sensors.az]\nkind = "step"\n', r"missing value 'sensors.az.step'"),
        (lambda t: t + '[sensors.az]\nkind = "phone"\nangle = 1\n', r"unknown key 'sensors.az.angle'"),
        (lambda t: t + '[sensors]\naz = "phone"\n', r"'sensors.az' must be a table"),
        (lambda t: t + '[sensor]\nkind = "step"\n', r"missing value 'sensor.step'"),
        (lambda t: t + "[drive\n", r"not valid TOML"),
        (lambda t: t.replace("speed = 0.5", 'speed = 0.5\ndirection = "downwards"'), r"'drive.direction' must be"),
    ],
)
def test_bad_profile_is_a_one_line_error_naming_file_and_key(tmp_path, edit, pattern):
    p = tmp_path / "bad.toml"
    p.write_text(edit(MINIMAL))
    with pytest.raises(SceneError, match=pattern) as exc:
        load_profile(p)
    assert str(exc.value).startswith(str(p)) and "\n" not in str(exc.value)


def test_missing_profile_file(tmp_path):
    with pytest.raises(SceneError, match="no such profile file"):
        load_profile(tmp_path / "none.toml")


def test_profile_table_lists_every_key():
    table = profile_table()
    for k in ("| [escalator] | unit |", "| [drive] | speed | m/s | required", "| [chain] | links_per_step |"):
        assert k in table


# --- the scene of a profile ---------------------------------------------------------------------

FLEET = Path(__file__).resolve().parents[2] / "data" / "fleet-example" / "escalators"
CHAIN_101 = """
[escalator]
unit = "W4"
[drive]
speed = 0.5
[chain]
nominal_pitch = 0.1016
links_per_step = 4
n_links = 200
"""


def mean_frequency(x, fs, f0):
    """Average frequency of the component of x near f0: the unwrapped phase of its analytic signal
    (band-passed +-30 %), end minus start, over 2 pi T. [Hz]"""
    from scipy.signal import butter, hilbert, sosfiltfilt

    sos = butter(4, [0.7 * f0, 1.3 * f0], btype="band", fs=fs, output="sos")
    phase = np.unwrap(np.angle(hilbert(sosfiltfilt(sos, x - x.mean()))))
    trim = int(2 * fs)  # filter end effects
    return (phase[-trim] - phase[trim]) / (2 * np.pi * (x.size - 2 * trim) / fs)


def test_the_example_fleet_has_a_profile_per_unit():
    units = {line.split(",")[1] for line in (FLEET.parent / "units.csv").read_text().splitlines()[1:]}
    assert {p.stem for p in FLEET.glob("*.toml")} == units
    for path in FLEET.glob("*.toml"):
        prof = load_profile(path)
        assert (prof.unit, prof.speed, prof.nominal_pitch) == (path.stem, 0.5, 0.13333)  # make_fleet_example.py


@pytest.mark.parametrize("unit", ["E07", "E12", "E21"])
def test_every_fleet_profile_simulates_converged_at_its_speed(unit):
    """The scene built from each example profile runs, converged (the check), with every link in tension
    and delta's link pass at the profile's speed / pitch within 0.05 % (measured: +0.006 %, -0.040 %,
    -0.042 % over 20 s: the chain coasts in the tooth backlash at its start speed), and the link pass the
    result states (the links that passed over the run) is delta's within 0.01 %."""
    prof = load_profile(FLEET / f"{unit}.toml")
    ds = vibkit.simulate(prof.scene("forward"), progress=False, check=True)
    assert ds.attrs["converged"] == 1
    assert "warnings" not in ds.attrs
    assert float(ds.link_tension.min()) > 0.0
    f = mean_frequency(ds.delta.values, 1 / float(ds.time[1] - ds.time[0]), prof.speed / prof.nominal_pitch)
    assert f == pytest.approx(prof.speed / prof.nominal_pitch, rel=5e-4)
    assert ds.attrs["link_pass_frequency_hz"] == pytest.approx(f, rel=1e-4)
    inverse = vibkit.simulate(prof.scene("inverse", duration=1.0), progress=False)
    assert float(inverse.link_tension.min()) > 0.0 and "warnings" not in inverse.attrs


def test_profile_scene_fills_from_standard_proportions_and_says_so():
    prof = parse_profile(CHAIN_101, "w4.toml")
    text = prof.scene_text("forward")
    scene = prof.scene("forward")
    # a 101.6 mm chain: rollers and teeth scaled with the pitch, 4 rollers per step, the loop from n_links
    assert scene.chain.roller_radius == pytest.approx(0.035 * 0.1016 / (0.4 / 3), rel=1e-5)
    assert scene.sprocket.base_width == pytest.approx(0.060 * 0.1016 / (0.4 / 3), rel=1e-5)
    assert (scene.chain.n_rollers, scene.chain.links_per_step) == (200, 4)
    assert scene.guide.head_radius == pytest.approx(scene.sprocket.pitch_radius(0.1016), rel=1e-12)
    assert scene.effects["motor"].speed == 0.5 and scene.effects["tensioner"].preload > 0
    assert "filled: reference 35 mm x pitch / 133.33 mm" in text and "chain.n_links" in text
    assert scene.analysis == "forward" and prof.scene("inverse").motion.speed == 0.5


def test_loop_from_rise_and_incline():
    """The guide's incline from the rise: L = (rise - 2 r_t (1 - cos a)) / sin a, the links whole steps
    that close the loop within the tensioner's travel."""
    text = MINIMAL.replace("n_links = 160", "") + "[geometry]\nrise = 4.5\nincline_deg = 30\n"
    scene = parse_profile(text, "e.toml").scene("inverse")
    a = np.radians(30.0)
    assert scene.guide.incline_length == pytest.approx((4.5 - 2 * 1.5 * (1 - np.cos(a))) / np.sin(a), rel=1e-6)
    assert scene.chain.n_rollers % 3 == 0
    assert abs(scene.guide.perimeter - scene.chain.n_rollers * 0.13333) / 2 < 0.36


@pytest.mark.parametrize(
    "edit, pattern",
    [
        # 35 mm rollers (the 133.33 mm chain's) on teeth cut for 101.6 mm
        (lambda t: t.replace("n_links = 200", "n_links = 200\nroller_radius = 0.035"), r"inside the sprocket's teeth"),
        (lambda t: t.replace("n_links = 200", "n_links = 300") + "[geometry]\nrise = 3.0\n", r"cannot close"),
        (lambda t: t.replace("n_links = 200", "n_links = 40"), r"too few"),
    ],
)
def test_geometry_that_cannot_run_is_refused_naming_the_key(edit, pattern):
    with pytest.raises(SceneError, match=pattern) as exc:
        parse_profile(edit(CHAIN_101), "w4.toml").scene("forward")
    text = str(exc.value)
    assert text.startswith("w4.toml: ") and "\n" not in text
    assert any(k in text for k in ("chain.roller_radius", "chain.n_links", "geometry.rise"))


def test_a_step_of_four_links_carries_its_passenger_on_four_rollers():
    """links_per_step = 4: step s is rollers 4 (s - 1) + 1 .. 4 s, and a passenger's weight is shared by
    the four (the compiled kernel and the Python model agree)."""
    from vibkit.model.effects import PASSENGERS_BY_TIME, passenger_loads
    from vibkit.model.escalator import EscalatorModel

    scene = parse_profile(CHAIN_101, "w4.toml").scene("forward")
    model = EscalatorModel(scene)
    assert list(model.step_rollers(3)) == [8, 9, 10, 11]
    fz = np.zeros(model.n)
    pm, ps = np.array([80.0]), np.array([3], dtype=np.int64)
    passenger_loads(1.0, PASSENGERS_BY_TIME, np.zeros(model.n), pm, ps, np.array([0.0]), np.array([5.0]), 9.81,
                    model.n, 4, fz)  # fmt: skip
    assert np.flatnonzero(fz).tolist() == [8, 9, 10, 11]
    np.testing.assert_allclose(fz[8:12], -80.0 * 9.81 / 4, rtol=1e-15)
    assert fz.sum() == pytest.approx(-80.0 * 9.81, rel=1e-15)


def test_scene_key_links_per_step(tmp_path):
    from vibkit.model.scene import load_scene

    base = (Path(__file__).resolve().parents[2] / "sim" / "thesis-forward.toml").read_text()
    assert load_scene(Path(__file__).resolve().parents[2] / "sim" / "thesis-forward.toml").chain.links_per_step == 3
    p = tmp_path / "five.toml"
    p.write_text(base.replace("n_rollers = 159", "n_rollers = 159\nlinks_per_step = 5"))
    with pytest.raises(SceneError, match=r"five.toml: 'chain.links_per_step' must be 3 or 4, got 5"):
        load_scene(p)
    p.write_text(base.replace("n_rollers = 159", "n_rollers = 159\nlinks_per_step = 4").replace("= 20", "= 40"))
    with pytest.raises(SceneError, match=r"'outputs.step_accelerometer' must be a step 1..39"):
        load_scene(p)


def test_profile_scene_description_is_the_users_line_said_once():
    """The scene's description is the unit, its site and the profile's own line; without one, the facts."""
    described = parse_profile(
        MINIMAL.replace('site = "Leon, Plaza Mayor"', 'site = "Leon"\ndescription = "up, 3-link steps"'), "d.toml"
    )
    assert described.scene("forward").description == "E07 (Leon): up, 3-link steps"
    plain = parse_profile(MINIMAL, "p.toml")
    assert plain.scene("forward").description == "E07 (Leon, Plaza Mayor): 0.5 m/s, 133.33 mm pitch, 3 links per step"


def test_a_down_escalator_runs_its_scene_at_a_negative_speed():
    """drive.direction = "down": the profile's scenes set the chain's speed negative (the steps go down the incline);
    the rated speed and the link pass stay the magnitudes a tachometer and a spectrum read."""
    up = parse_profile(MINIMAL)
    down = parse_profile(MINIMAL.replace("speed = 0.5", 'speed = 0.5\ndirection = "down"'))
    assert (up.direction, up.set_speed) == ("up", 0.5)
    assert (down.direction, down.speed, down.set_speed) == ("down", 0.5, -0.5)
    assert down.link_pass_frequency_hz == up.link_pass_frequency_hz
    fwd, inv = down.scene("forward"), down.scene("inverse")
    assert fwd.effects["motor"].speed == -0.5
    assert "initial_speed = -0.5" in fwd.text
    assert "speed = -0.5" in inv.text and "drive.direction = down" in inv.text
