"""One printed form per quantity across commands: `ride` prints the run's speed as `pitch` and `report` do; a
down escalator's simulated speed is not printed against a negative set speed (`compare --help`'s channel rule:
tests/cli/test_cli_help.py)."""

from __future__ import annotations

from pathlib import Path

from vibkit.cli import main
from vibkit.diagnose.comparison import counted_speed_note
from vibkit.diagnose.rounding import fmt_pm

ROOT = Path(__file__).resolve().parents[2]
PHYPHOX = str(ROOT / "data" / "field" / "layouts" / "phyphox.csv")


def test_ride_prints_the_speed_as_the_other_commands_do(capsys, tmp_path):
    profile = tmp_path / "w1.toml"
    profile.write_text(
        '[escalator]\nunit = "W1"\n[drive]\nspeed = 0.7485\nspeed_uncertainty = 0.00075\n'
        "[chain]\nnominal_pitch = 0.13333\nn_links = 160\n"
    )
    assert main(["ride", PHYPHOX, "--segment", "0.5:3", "--escalator", str(profile)]) == 0
    out = capsys.readouterr().out
    expected = fmt_pm(0.7485, 0.00075, "m/s")  # the form of pitch, report and fleet
    assert expected == "0.74850 +- 0.00075 m/s"
    assert f"speed {expected}" in out and "0.749 m/s" not in out


def test_a_down_escalators_speed_is_not_set_against_its_negative_set_point():
    assert counted_speed_note(0.6505, -0.6505) == ""  # the same speed, the steps travelling down
    note = counted_speed_note(0.6510714, -0.65)
    assert note == "simulated chain speed 0.65107 m/s (its links counted; set 0.65 m/s, the steps travelling down)"
    assert "-0.65" not in note
    assert counted_speed_note(0.49, 0.5).endswith("set 0.5 m/s)")
