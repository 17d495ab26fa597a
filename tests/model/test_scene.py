"""Scene loading: bad scenes give a clear error naming the file and the key (issue 2)."""

from pathlib import Path

import pytest

from vibkit.model.scene import SceneError, load_scene

SIM = Path(__file__).resolve().parents[2] / "sim"


def _write(tmp_path, text, name="bad.toml"):
    base = (SIM / "thesis-kinematics.toml").read_text()
    p = tmp_path / name
    p.write_text(text(base) if callable(text) else text)
    return p


def test_shipped_scenes_load():
    for path in sorted(SIM.glob("*.toml")):
        scene = load_scene(path)
        assert scene.analysis in ("kinematics", "inverse", "forward")


@pytest.mark.parametrize(
    "edit, pattern",
    [
        (
            lambda b: b.replace("roller_radius = 0.035", "roller_radius = 0.035\nroller_colour = 3"),
            r"unknown key 'chain.roller_colour'",
        ),
        (lambda b: b.replace("[kinematics]", "[kinematic]"), r"unknown section \[kinematic\]"),
        (lambda b: b.replace("step = 0.0001", ""), r"missing value 'kinematics.step'"),
        (lambda b: b.replace('analysis = "kinematics"', ""), r"missing value 'scene.analysis'"),
        (lambda b: b.replace("roller_mass = 8.0", "roller_mass = -8.0"), r"'chain.roller_mass' must be positive"),
        (lambda b: b.replace("lower_landing = 0.8", "lower_landing = 0.0"), r"'guide.lower_landing' must be positive"),
        (lambda b: b.replace("n_rollers = 159", "n_rollers = 175"), r"cannot close"),
        (lambda b: b.replace("roller_mass = 8.0", 'roller_mass = "heavy"'), r"'chain.roller_mass' expected float"),
        (
            lambda b: b.replace('variables = ["delta", "s1", "closure_residual"]', 'variables = ["deltaa"]'),
            r"unknown output 'deltaa'",
        ),
        (lambda b: b + "\n[effects]\ngravity = true\n", r"no meaning in a kinematics scene"),
        (lambda b: b.replace("[scene]", "[scene"), r"not valid TOML"),
    ],
)
def test_bad_scene_messages(tmp_path, edit, pattern):
    p = _write(tmp_path, edit)
    with pytest.raises(SceneError, match=pattern) as info:
        load_scene(p)
    assert str(p) in str(info.value)
    assert "\n" not in str(info.value)


def test_unknown_effect_is_named(tmp_path):
    text = (SIM / "thesis-inverse.toml").read_text().replace("gravity = true", "gravity = true\nmagnetism = true")
    p = tmp_path / "eff.toml"
    p.write_text(text)
    with pytest.raises(SceneError, match="unknown effect 'effects.magnetism'"):
        load_scene(p)


def test_missing_file():
    with pytest.raises(SceneError, match="no such scene file"):
        load_scene("does/not/exist.toml")


def test_closure_choice_is_checked(tmp_path):
    text = (
        (SIM / "thesis-forward.toml").read_text().replace('method = "dopri5"', 'method = "dopri5"\nclosure = "tabel"')
    )
    p = tmp_path / "closure.toml"
    p.write_text(text)
    with pytest.raises(SceneError, match=r"'solver.closure' must be one of table, exact, got 'tabel'"):
        load_scene(p)
    p.write_text(text.replace('"tabel"', '"exact"'))
    assert load_scene(p).section("solver")["closure"] == "exact"
