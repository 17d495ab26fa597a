"""Escalator profiles: the user's machine in a small TOML; bad keys are one-line errors naming file and key."""

import math

import pytest

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


@pytest.mark.parametrize(
    "edit, pattern",
    [
        (lambda t: t.replace('unit = "E07"', ""), r"missing value 'escalator.unit'"),
        (lambda t: t.replace("speed = 0.5", ""), r"missing value 'drive.speed'"),
        (lambda t: t.replace("nominal_pitch = 0.13333", ""), r"missing value 'chain.nominal_pitch'"),
        (lambda t: t.replace("n_links = 160", ""), r"missing value 'chain.n_links' \(or both 'geometry.rise'"),
        (lambda t: t.replace("speed = 0.5", "speed = 50"), r"'drive.speed' = 50.0 is outside"),
        (lambda t: t.replace("speed = 0.5", 'speed = "fast"'), r"'drive.speed' expected float"),
        (lambda t: t.replace("n_links = 160", "n_links = 160\nlinks_per_step = 5"), r"'chain.links_per_step' = 5"),
        (lambda t: t.replace("n_links = 160", "n_links = 160\ncolour = 1"), r"unknown key 'chain.colour'"),
        (lambda t: t + "[motor]\nkp = 1\n", r"unknown section \[motor\]"),
        (lambda t: t + '[sensor]\nkind = "phone"\n', r"'sensor.kind' must be one of tensioner, step"),
        (lambda t: t + '[sensor]\nkind = "step"\n', r"missing value 'sensor.step'"),
        (lambda t: t + "[drive\n", r"not valid TOML"),
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
