"""``vibkit spectrum`` with a speed (--speed or --escalator) makes the decision ``vibkit pitch`` makes on the
same file: the same numbers, verdict and exit code, the pitch and elongation under pitch's JSON names, and the
same pitch and elongation lines; without a stated speed uncertainty neither gives a sigma."""

import json

import pytest

# synthetic: link pitch 0.133730 m at 0.5 m/s, 10 s at 100 Hz (data/make_fleet_example.py); no speed in the file
E12_REC = "data/fleet-example/E12/2026-11-23.csv"
E12 = "data/fleet-example/escalators/E12.toml"
TRUE_PITCH_M = 0.133730
#: pitch's JSON keys that spectrum does not repeat: its evidence in detail (spectrum has its peak table)
PITCH_ONLY = {"schema", "bursts", "burst_chi2_per_dof", "detected", "harmonics", "hypotheses", "notes", "parts"}
#: the lines of the text output that carry the pitch, the elongation and the verdict
PITCH_LINES = ("link pitch", "elongation", "(limits")

CASES = {
    # no speed uncertainty given: the frequency's part resolves the elongation, verdict ok
    "speed": (["--speed", "0.5", "--nominal-pitch", "0.13333"], 0),
    # 0.1 % of the speed: elongation sigma 0.1 %, under a third of the 1.5 % limit
    "speed and sigma": (["--speed", "0.5", "--speed-uncertainty", "0.1%", "--nominal-pitch", "133.33mm"], 0),
    # the profile's rated speed, sigma 5 %/sqrt(3) = 2.9 % (EN 115-1): over a third of the first limit
    "escalator": (["--escalator", E12], 3),
}


def _both(run, args, *extra):
    s = run("spectrum", E12_REC, *args, *extra)
    p = run("pitch", E12_REC, *args, *extra)
    return s, p


@pytest.mark.parametrize("case", CASES)
def test_spectrum_json_is_pitch_json(run, case):
    args, exit_code = CASES[case]
    (rc_s, out_s, _), (rc_p, out_p, _) = _both(run, args, "--json")
    assert rc_s == rc_p == exit_code
    s, p = json.loads(out_s), json.loads(out_p)
    assert s["schema"] == "vibkit.spectrum/1" and p["schema"] == "vibkit.pitch/1"
    for key in ("pitch_m", "nominal_pitch_m", "elongation_percent", "verdict", "speed_sigma_m_s", "limits_percent"):
        assert key in s, key
    assert {k: s.get(k, "missing") for k in set(p) - PITCH_ONLY} == {k: p[k] for k in set(p) - PITCH_ONLY}
    assert s["exit_code"] == exit_code
    # the pitch is the file's: within 4 of the frequency's sigmas of the pitch it was made with
    sigma_f = s["pitch_sigma_m"] if s["pitch_sigma_m"] is not None else s["pitch_sigma_frequency_only_m"]
    assert abs(s["pitch_m"] - TRUE_PITCH_M) < 4 * sigma_f
    assert s["elongation_percent"] == pytest.approx(100 * (s["pitch_m"] / 0.13333 - 1), rel=1e-12)


def test_escalator_speed_sigma_makes_both_inconclusive(run):
    (rc_s, out_s, err_s), (rc_p, _, err_p) = _both(run, ["--escalator", E12], "--json")
    s = json.loads(out_s)
    assert rc_s == rc_p == 3
    assert s["status"] == "inconclusive" and s["verdict"] == "inconclusive"
    assert s["speed_sigma_m_s"] == pytest.approx(0.5 * 0.05 / 3**0.5)  # EN 115-1's +-5 % uniform
    # the speed's part alone: 100 * 0.05 / sqrt(3) = 2.89 %, more than 0.5 % (a third of 1.5 %)
    assert s["elongation_sigma_percent"] == pytest.approx(100 * 0.05 / 3**0.5 * s["pitch_m"] / 0.13333, rel=1e-3)
    assert "from the profile" in err_s and "from the profile" in err_p


def test_without_a_stated_speed_sigma_no_sigma_anywhere(run):
    (rc, out, _), _ = _both(run, CASES["speed"][0], "--json")
    s = json.loads(out)
    assert rc == 0 and s["verdict"] == "ok"
    assert s["pitch_sigma_m"] is None and s["elongation_sigma_percent"] is None
    assert s["speed_sigma_m_s"] is None and "speed uncertainty not stated" in s["uncertainty"]
    assert 0 < s["elongation_sigma_frequency_only_percent"] < 0.05  # the frequency's part, named as such
    assert "+-" not in s["reason"] and "speed uncertainty not stated" in s["reason"]
    row = s["channels"][0]
    assert row["pitch_sigma_m"] is None and row["elongation_sigma_percent"] is None and "+-" not in row["reason"]


@pytest.mark.parametrize("case", CASES)
def test_spectrum_text_has_pitch_lines(run, case):
    args, exit_code = CASES[case]
    (rc_s, out_s, err_s), (rc_p, out_p, _) = _both(run, args)
    assert rc_s == rc_p == exit_code
    lines_s = [ln.strip() for ln in out_s.splitlines() if ln.strip().startswith(PITCH_LINES)]
    lines_p = [ln.strip() for ln in out_p.splitlines() if ln.strip().startswith(PITCH_LINES)]
    assert len(lines_s) == 3 and lines_s == lines_p
    if case == "speed":
        assert "+-" not in lines_s[0] + lines_s[1] and "speed uncertainty not stated" in lines_s[1]
        assert lines_s[1].endswith("-> ok")
    if exit_code == 3:
        assert lines_s[1].endswith("-> inconclusive") and "vibkit spectrum: inconclusive" in err_s


def test_without_a_speed_the_frequency_only(run):
    rc, out, err = run("spectrum", E12_REC, "--nominal-pitch", "0.13333", "--json")
    d = json.loads(out)
    assert rc == 0 and d["speed_m_s"] is None and d["band_hz"] == [2.5, 6.0]
    assert not {"pitch_m", "elongation_percent", "verdict"} & set(d)
    assert not {"pitch_m", "verdict"} & set(d["channels"][0])
    rc, out, err = run("spectrum", E12_REC)
    assert rc == 0 and "link pitch" not in out and "note:" not in err
