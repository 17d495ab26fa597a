"""The demo (`make demo`): its one-line summaries say what each report judged."""

from pathlib import Path

from vibkit.demo import main

ROOT = Path(__file__).resolve().parents[1]


def test_the_demo_says_a_pitch_it_did_not_judge_is_not_judged(tmp_path, capsys):
    """Las Palmas states no speed: its report does not judge the pitch against the scene, and the demo printed
    "pitch vs scene NOT consistent" for it (a falsy None)."""
    argv = ["--root", str(ROOT), "--out", str(tmp_path), "--inverse-duration", "1", "--field-duration", "4"]
    assert main(argv) == 0
    out = capsys.readouterr().out
    lines = {ln.split(":")[0]: ln for ln in out.splitlines() if ln.startswith(("las-palmas", "leon"))}
    assert "pitch vs scene not judged (the recording states no speed)" in lines["las-palmas"]
    assert "pitch vs scene NOT consistent" in lines["leon"]  # 138.42 mm against the scene's 133.33 mm
