"""--escalator FILE (a profile of the user's escalator) and ``vibkit scene``: the profile's numbers where no
flag gives them, the scene written atomically and never over a file unless told, bad profiles one line."""

import json

import pytest

from vibkit.model.scene import parse_scene

from support.cli import one_line_error

LEON = "data/field/leon-tensioner.csv"
E07 = "data/fleet-example/escalators/E07.toml"
E12 = "data/fleet-example/escalators/E12.toml"
MISFIT = """
[escalator]
unit = "W4"
[drive]
speed = 0.5
[chain]
nominal_pitch = 0.1016
links_per_step = 4
n_links = 200
roller_radius = 0.035
"""


def test_scene_to_stdout_is_a_valid_scene(run):
    rc, out, err = run("scene", E07, "--analysis", "inverse", "-o", "-")
    # stdout is the scene alone; stderr one note: E07 states no geometry (a 30 deg escalator from its 159 links)
    assert rc == 0 and err.startswith("note: ") and len(err.splitlines()) == 1 and "states no geometry" in err
    scene = parse_scene(out)
    assert (scene.name, scene.analysis, scene.motion.speed, scene.chain.n_rollers) == ("E07", "inverse", 0.5, 159)


def test_scene_file_is_written_once_unless_forced(run, tmp_path):
    out = tmp_path / "e07.toml"
    rc, _, err = run("scene", E07, "-o", out, "--duration", "5")
    assert rc == 0 and "wrote" in err
    assert parse_scene(out.read_text()).run.duration == 5.0
    one_line_error(run("scene", E07, "-o", out), out, "--force")
    assert run("scene", E07, "-o", out, "--force")[0] == 0


def test_scene_of_a_geometry_that_cannot_run_names_the_key(run, tmp_path):
    bad = tmp_path / "w4.toml"
    bad.write_text(MISFIT)
    one_line_error(run("scene", bad, "-o", "-"), bad, "inside the sprocket's teeth", "chain.roller_radius")


def test_pitch_takes_speed_sigma_and_pitch_from_the_profile(run):
    rc, out, err = run("pitch", LEON, "--escalator", E12, "--json")
    d = json.loads(out)
    assert d["speed_m_s"] == 0.5 and "E12, rated" in d["speed_source"]
    # not stated in the profile: the rated speed's tolerance, 5 % / sqrt(3)
    assert d["speed_sigma_m_s"] == pytest.approx(0.5 * 0.05 / 3**0.5)
    assert d["nominal_pitch_m"] == 0.13333
    assert "from the profile" in err and "EN 115-1" in err
    rc, out, err = run("pitch", LEON, "--escalator", E07, "--json")
    assert json.loads(out)["speed_sigma_m_s"] == 0.0005  # stated: drive.speed_uncertainty


def test_explicit_flags_win_over_the_profile(run):
    rc, out, err = run("pitch", LEON, "--escalator", E07, "--speed", "0.49", "--nominal-pitch", "133mm", "--json")
    d = json.loads(out)
    assert (d["speed_m_s"], d["speed_source"], d["nominal_pitch_m"]) == (0.49, "--speed", 0.133)


@pytest.mark.parametrize("command", ["pitch", "spectrum"])
def test_bad_profile_is_one_line_naming_file_and_key(run, tmp_path, command):
    bad = tmp_path / "bad.toml"
    bad.write_text('[escalator]\nunit = "X"\n[drive]\nspeed = 0.5\n')
    one_line_error(run(command, LEON, "--escalator", bad), bad, "--escalator", "chain.nominal_pitch")
