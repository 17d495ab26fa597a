"""Scene loading: bad scenes give a clear error naming the file and the key."""

import math
from pathlib import Path

import pytest

from vibkit.model.scene import SceneError, load_scene, parse_scene

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
        (lambda b: b.replace("n_rollers = 159", "n_rollers = 175"), r"'chain.n_rollers' = 175 links .* cannot close"),
        # with the count filled for the new chain, the elongation is what cannot close (a stranger's 6 %, named n_rollers)
        (
            lambda b: b.replace("n_rollers = 159", 'n_rollers = "fill"\nelongation_percent = 5.0'),
            r"'chain.elongation_percent' = 5.0 \(links of 0.14 m; 'chain.n_rollers' = \"fill\": the 159 links",
        ),
        (lambda b: b.replace("roller_mass = 8.0", 'roller_mass = "heavy"'), r"'chain.roller_mass' expected float"),
        (
            lambda b: b.replace('variables = ["delta", "s1", "closure_residual"]', 'variables = ["deltaa"]'),
            r"unknown output 'deltaa'",
        ),
        (lambda b: b + "\n[effects]\ngravity = true\n", r"no meaning in a kinematics scene"),
        # a step longer than the sweep gave one sample (the inverse analysis refused the same mistake)
        (lambda b: b.replace("step = 0.0001", "step = 5.0"), r"'kinematics.step' = 5.0 m is longer than the sweep"),
        # another analysis' run section, or solver keys where nothing is integrated, were read by nothing
        (
            lambda b: b + "\n[run]\nduration = 5.0\n",
            r"\[run\] has no meaning in a kinematics scene, whose run is \[kinematics\] \(got run.duration\)",
        ),
        (
            lambda b: b + '\n[solver]\nclosure = "exact"\nrtol = 1e-9\n',
            r"solver.closure, solver.rtol have no meaning in a kinematics scene, which integrates nothing",
        ),
        (lambda b: b.replace("[scene]", "[scene"), r"not valid TOML"),
        # a pitch in mm is named as such, not as a chain that cannot close (a stranger's 101.6)
        (
            lambda b: b.replace("link_pitch = 0.13333333333333333", "link_pitch = 133.33"),
            r"'chain.link_pitch' = 133.33 is outside the plausible range \[0.02, 0.5\] m \(101.6 mm is 0.1016 m\)",
        ),
        # rollers that overlap are named as such, not as a chain that jumped the teeth
        (
            lambda b: b.replace("roller_radius = 0.035", "roller_radius = 0.07"),
            r"'chain.roller_radius' = 0.07 m: neighbouring rollers overlap",
        ),
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
    with pytest.raises(SceneError, match=r"'solver.closure' must be one of table, exact, runs, got 'tabel'"):
        load_scene(p)
    p.write_text(text.replace('"tabel"', '"exact"'))
    assert load_scene(p).solver.closure == "exact"


# --- the schema ------------------------------------------------------------------------------------


def test_every_schema_key_states_unit_doc_and_default():
    """No silent default: every key has a unit (possibly "" for a pure number), a doc, and a default,
    or is required, or its doc says what happens when it is not set."""
    from vibkit.model.schema import schema_fields

    fields = schema_fields()
    assert len(fields) > 50
    for sec, f in fields:
        m = f.metadata
        where = f"{sec}.{f.name}"
        assert isinstance(m["unit"], str), where
        assert m["doc"].strip(), where
        assert f.default is not None or m["required"] or "not set" in m["doc"], where
        assert not (m["required"] and f.default is not None), where
        if m["range"]:
            lo, hi, _ = m["range"]
            assert lo < hi, where
            if f.default is not None and math.isfinite(f.default):
                assert lo <= f.default <= hi, where


def test_schema_table_has_a_row_per_key():
    from vibkit.model.schema import schema_fields, schema_table

    table = schema_table()
    rows = table.splitlines()
    assert rows[0] == "| section | key | unit | default | range | meaning |"
    assert len(rows) == 2 + len(schema_fields())
    assert (
        "| [effects.contact] | exponent |  | 1.5 | [1, 3] | force-indentation exponent (1 linear, 1.5 Hertz) |" in rows
    )
    assert (
        "| [effects.contact] | stiffness | N/m^exponent | required | (0, 1e+16] | roller-tooth contact stiffness |"
        in rows
    )


def test_sections_and_ranges_are_derived_from_the_schema():
    """The loader's tables come from the schema: the same keys and types as the scene files use."""
    from vibkit.model.schema import EFFECTS, RANGES, SECTIONS

    assert SECTIONS["run"] == {
        "duration": float,
        "output_step": float,
        "start": float,
        "initial_speed": float,
        "seed": int,
    }
    assert SECTIONS["guide"]["head_radius"] == (float, str)
    assert EFFECTS["contact"] == {"stiffness": float, "exponent": float, "damping": float}
    assert EFFECTS["passengers"] == {"mass": list, "step": list, "board": list, "alight": list}
    assert RANGES["effects.contact.exponent"] == (1.0, 3.0, "(1 linear, 1.5 Hertz)")
    assert RANGES["solver.rtol"] == (1e-14, 0.1, "")
    assert RANGES["effects.motor.initial_torque"] == (-1e8, 1e8, "N m")  # negative: a torque that brakes
    assert len(RANGES) == 20
    assert RANGES["chain.link_pitch"] == (0.02, 0.5, "m (101.6 mm is 0.1016 m)")


def test_defaults_are_typed_and_recorded():
    """A key the file leaves out takes the schema's default and is listed in Scene.defaults."""
    from vibkit.model.params import GRAVITY

    text = (SIM / "thesis-forward.toml").read_text()
    text = text.replace("contact = { stiffness = 1.0e6, exponent = 1.5 }", "contact = { stiffness = 1.0e6 }")
    sc = parse_scene(text.replace("\nstart = 0.0", "\n"))
    assert sc.effects["contact"].exponent == 1.5 and sc.effects["contact"].damping == 0.0
    assert sc.effects["gravity"].g == GRAVITY == 9.81
    assert "effects.contact.exponent" in sc.defaults and "effects.gravity.g" in sc.defaults
    assert "effects.contact.stiffness" not in sc.defaults
    assert sc.solver.atol_for(1e-7) == 1e-7 * 1e-2
    assert sc.run.start == 0.0 and "run.start" in sc.defaults and "run.initial_speed" not in sc.defaults


@pytest.mark.parametrize(
    "name, old, new, key",
    [
        ("thesis-forward.toml", "output_step = 0.005", "output_step = 50.0", "run.output_step"),
        ("thesis-inverse.toml", "step = 0.005 ", "step = 100.0 ", "motion.step"),
    ],
)
def test_an_output_step_longer_than_the_run_is_refused(tmp_path, name, old, new, key):
    """A stranger's 50 s output step in a 44 s run gave a one-sample result, exit 0; `spectrum` failed later."""
    text = (SIM / name).read_text()
    assert old in text
    p = tmp_path / name
    p.write_text(text.replace(old, new))
    with pytest.raises(SceneError, match=rf"'{key}' = .* is longer than .*duration"):
        load_scene(p)


def test_output_times_never_pass_the_run():
    from vibkit.analyses.results import output_times

    assert output_times(11.0, 4.0).tolist() == [0.0, 4.0, 8.0]
    assert output_times(44.0, 0.005).size == 8801 and output_times(44.0, 0.005)[-1] == pytest.approx(44.0)
    assert output_times(0.3, 0.1).size == 4  # 0.3 / 0.1 is 2.9999999999999996 in floats
    with pytest.raises(ValueError, match="longer than the run"):
        output_times(2.0, 3.0)


def test_a_worn_link_s_pitch_as_a_string_is_a_type_error(tmp_path):
    """A stranger's worn_links = [[40, "0.1343"]] read "must be positive, got '0.1343'": the problem is the type."""
    text = (
        (SIM / "thesis-forward.toml")
        .read_text()
        .replace("n_rollers = 159", 'n_rollers = 159\nworn_links = [[40, "0.1343"]]')
    )
    p = tmp_path / "s.toml"
    p.write_text(text)
    with pytest.raises(SceneError, match=r"pitch of link 40 must be a number \[m\], got str '0.1343'"):
        load_scene(p)


def test_run_sections_and_solver_keys_belong_to_their_analysis(tmp_path):
    """A stranger's inverse scene with [run] and [solver] (method, rtol, check) and a forward one with [motion]
    ran with those keys read by nothing; they are refused naming the keys, and the solver key that does apply
    everywhere (the result's size limit) is kept."""
    inverse = (SIM / "thesis-inverse.toml").read_text()
    forward = (SIM / "thesis-forward.toml").read_text()
    cases = [
        (inverse + "\n[run]\nduration = 5.0\n", r"\[run\] has no meaning in an inverse scene, whose run is \[motion\]"),
        (inverse + '\n[solver]\nmethod = "radau"\n', r"solver.method has no meaning in an inverse scene"),
        (forward + "\n[motion]\nspeed = 5.0\n", r"\[motion\] has no meaning in a forward scene, whose run is \[run\]"),
    ]
    for text, pattern in cases:
        with pytest.raises(SceneError, match=pattern):
            parse_scene(text, "s.toml")
    kept = parse_scene(inverse + '\n[solver]\nmax_result_bytes = "2 GB"\n', "s.toml")
    assert kept.analysis == "inverse"


def test_a_flat_roller_in_a_kinematics_scene_is_said_to_be_left_out():
    """A kinematics scene places the chain alone: a roller worn flat is not in it, and the result says so (the
    message existed and was never given)."""
    import vibkit

    text = (
        (SIM / "thesis-kinematics.toml")
        .read_text()
        .replace("roller_radius = 0.035", "roller_radius = 0.035\nroller_flat_by_roller = [[5, 0.005]]")
    )
    ds = vibkit.simulate(parse_scene(text, "flat.toml"), progress=False)
    assert "worn flat: a kinematics scene places the chain alone, no flat" in ds.attrs["warnings"]


def test_the_schema_table_says_which_lower_ends_are_refused():
    """A stranger read kp, g and torque_limit as [0, ...] in the table, and 0 was refused: the table shows the
    ends the loader refuses as open, and an integral controller alone (kp = 0, ki > 0) is taken."""
    from vibkit.model.schema import schema_table

    table = schema_table()
    assert "| [effects.gravity] | g | m/s^2 | 9.81 | (0, 1000] |" in table
    assert "| torque_limit | N m | inf | (0, 1e+08] |" in table
    forward = (SIM / "thesis-forward.toml").read_text()
    assert "motor = { kp = 600.0, speed = 0.5 }" in forward
    integral = parse_scene(forward.replace("kp = 600.0,", "kp = 0.0, ki = 500.0,"), "ki.toml")
    assert integral.effects["motor"].kp == 0.0 and integral.effects["motor"].ki == 500.0
    with pytest.raises(SceneError, match=r"'effects.motor.kp' must be positive, or 0 with effects.motor.ki > 0"):
        parse_scene(forward.replace("kp = 600.0,", "kp = 0.0,"), "none.toml")
