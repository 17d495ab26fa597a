"""One speed per run, numbers as precise as what was measured, a report about the measured unit.

The recording: a chain 0.95 % longer than its nominal 133.33 mm, running at 0.5 m/s (link pass
0.5 / 0.1346 m = 3.715 Hz); the scene it is compared with runs at 0.52 m/s.  Before the one-speed rule the
comparison took the scene's 0.52 m/s for the recording too and gave a pitch ratio of 1.0095 x 0.52 / 0.5
= 1.050.
"""

import json
import re

import numpy as np
import pytest
import xarray as xr

from vibkit.cli.app import main
from vibkit.diagnose.comparison import compare
from vibkit.diagnose.pitch import estimate_pitch

from support.chain import family
from support.recording import recording

NOMINAL = 0.4 / 3  # m
LONG = 1.0095  # the chain is 0.95 % long
SPEED = 0.5  # m/s, measured on the steps
SCENE_SPEED = 0.52  # m/s, sim/las-palmas.toml's
FS = 200.0
AMPS = (0.3, 0.15, 0.09)

PROFILE = """
[escalator]
unit = "E07"
site = "Leon, Plaza Mayor"
description = "up escalator, 6 m rise"
[drive]
speed = 0.5
[chain]
nominal_pitch = 0.13333333
n_links = 160
"""


def _phone(seconds=40.0, seed=3):
    t = np.arange(int(seconds * FS)) / FS
    f = SPEED / (NOMINAL * LONG)
    x = family(t, f, AMPS, phases=[0.3 * k for k in range(3)])
    x = x + 0.05 * np.random.default_rng(seed).standard_normal(t.size)
    return recording({"accel": x}, t=t, units="m/s^2")


@pytest.fixture(scope="module")
def phone_file(tmp_path_factory):
    from vibkit.io import write_result

    d = tmp_path_factory.mktemp("speed")
    write_result(_phone(), d / "phone.nc")
    (d / "e07.toml").write_text(PROFILE)
    return d


def _simulated(seconds=20.0):
    """A stand-in simulation result: its chain at 0.52 m/s, link pass 0.52 / 133.33 mm (pitch ratio 1 exactly)."""
    t = np.arange(int(seconds * 400.0)) / 400.0
    x = family(t, SCENE_SPEED / NOMINAL, AMPS)
    return xr.Dataset(
        {
            "accel_step": ("time", x, {"units": "m/s^2"}),
            "chain_speed": ("time", np.full(t.size, SCENE_SPEED), {"units": "m/s"}),
        },
        coords={"time": ("time", t, {"units": "s"})},
        attrs={"chain_speed_m_s": SCENE_SPEED},
    )


def test_comparison_uses_the_measured_speed():
    rec, sim = _phone(), _simulated()
    c = compare(rec, sim, speed=SPEED, speed_sigma=0.0005 * SPEED)
    assert c.speed_meas_m_s == SPEED and c.speed_sim_m_s == pytest.approx(SCENE_SPEED)
    # the pitch ratio is the chain's elongation: 1.0095 within 3 sigma (sigma: 0.05 % of the speed and the
    # frequencies, about 5e-4)
    assert 0 < c.pitch_ratio_sigma < 1e-3
    assert c.pitch_ratio == pytest.approx(LONG, abs=3 * c.pitch_ratio_sigma)
    assert not c.pitch_consistent  # 0.95 % is more than the 0.5 % tolerance + 1.96 sigma
    # the recording states no speed: without speed= the scene's is assumed (and said), giving the old 1.05, and
    # no pitch verdict is given at a speed nobody measured
    c0 = compare(rec, sim)
    assert c0.pitch_ratio == pytest.approx(LONG * SCENE_SPEED / SPEED, rel=1e-3)
    assert any("the simulation's" in n and "assumed" in n and "not judged" in n for n in c0.notes)
    assert c0.pitch_consistent is None


@pytest.mark.parametrize("percent", [0.01, 0.05, 0.1])
def test_no_speed_warning_when_the_speed_is_good_enough(percent):
    est = estimate_pitch(_phone(), speed=SPEED, speed_sigma=percent / 100 * SPEED, nominal_pitch=NOMINAL)
    assert est.verdict == "ok" and not [w for w in est.warnings if "speed" in w]


def test_speed_warning_when_it_can_change_the_verdict():
    # a rated speed (+-5 % uniform: sigma 2.9 %) cannot tell 0.95 % from the 1.5 % limit
    est = estimate_pitch(_phone(), speed=SPEED, speed_sigma=0.05 / 3**0.5 * SPEED, nominal_pitch=NOMINAL)
    assert [w for w in est.warnings if "speed's uncertainty" in w]
    # 0.2 % of the speed against an elongation 0.02 % from the 1.5 % limit: the verdict could flip
    est = estimate_pitch(_phone(), speed=SPEED, speed_sigma=0.002 * SPEED, nominal_pitch=NOMINAL * LONG / 1.0148)
    assert est.elongation_percent == pytest.approx(1.48, abs=0.01)
    assert [w for w in est.warnings if "speed's uncertainty" in w]


_ZERO = re.compile(r"\+- 0(\.0+)?(?![\d.])")


def test_bare_speed_states_no_uncertainty(phone_file, capsys):
    rec = str(phone_file / "phone.nc")
    assert main(["pitch", rec, "--speed", "0.5", "--nominal-pitch", "133.33mm"]) == 0
    out = capsys.readouterr()
    lines = (out.out + out.err).splitlines()
    assert not [ln for ln in lines if _ZERO.search(ln)]
    assert "speed uncertainty not stated" in out.out
    assert main(["pitch", rec, "--speed", "0.5", "--nominal-pitch", "133.33mm", "--json"]) == 0
    d = json.loads(capsys.readouterr().out)
    assert d["speed_sigma_m_s"] is None and d["pitch_sigma_m"] is None and d["elongation_sigma_percent"] is None
    assert "not stated" in d["uncertainty"] and d["pitch_sigma_frequency_only_m"] > 0


def test_fleet_without_speed_uncertainty_shows_no_zero(phone_file, tmp_path, capsys):
    db = str(tmp_path / "f.sqlite")
    rec = str(phone_file / "phone.nc")
    args = ["fleet", "add", rec, "--unit", "E07", "--speed", "0.5", "--nominal-pitch", "133.33mm", "--db", db]
    assert main(args + ["--date", "2025-01-01"]) == 0
    out = capsys.readouterr()
    assert not [ln for ln in (out.out + out.err).splitlines() if _ZERO.search(ln)]
    assert "not stated" in out.out and "without a speed uncertainty" in out.err
    assert main(["fleet", "status", "--db", db]) == 0
    out = capsys.readouterr()
    assert not [ln for ln in (out.out + out.err).splitlines() if _ZERO.search(ln)]
    assert "not stated" in out.out
    assert main(["fleet", "status", "--db", db, "--json"]) == 0
    d = json.loads(capsys.readouterr().out)
    assert any("speed uncertainty not stated" in f for f in d["units"][0]["flags"])


def _measurement(i, years, e, s=0.05):
    import datetime as dt

    from vibkit.fleet import Measurement

    t = dt.datetime(2022, 3, 1, tzinfo=dt.timezone.utc).timestamp() + years * 365.25 * 86400
    return Measurement(
        id=None,
        unit="E12",
        date_utc=dt.datetime.fromtimestamp(t, dt.timezone.utc).strftime("%Y-%m-%dT%H:%M:%SZ"),
        date_unix_s=t,
        date_source="given",
        speed_m_s=0.5,
        speed_sigma_m_s=0.001,
        nominal_pitch_m=NOMINAL,
        channel="a",
        fundamental_hz=3.75,
        fundamental_sigma_hz=1e-3,
        pitch_m=NOMINAL * (1 + e / 100),
        pitch_sigma_m=NOMINAL * s / 100,
        elongation_percent=e,
        elongation_sigma_percent=s,
        snr_db=20.0,
        warnings=(),
        sha256=f"{i:064x}",
        path=f"/r{i}.csv",
        size_bytes=1,
        vibkit_version="t",
        analysed_utc="2026-01-01T00:00:00Z",
        quality="ok",
        quality_reason="",
        replaced=False,
    )


def test_a_passed_forecast_is_overdue(tmp_path, capsys, monkeypatch):
    from vibkit.fleet import FleetDB

    # 1 %/year from 2022-03 at 1.0 %: the 3 % limit is forecast for about 2024-03; today is 2026-11-25
    ms = [_measurement(i + 1, y, 1.0 + 1.0 * y) for i, y in enumerate((0.0, 0.5, 1.0, 1.5))]
    db = str(tmp_path / "f.sqlite")
    with FleetDB(db) as f:
        f.insert_many(ms)
    monkeypatch.setenv("SOURCE_DATE_EPOCH", "1795564800")  # 2026-11-25
    assert main(["fleet", "status", "--db", db]) == 0
    out = capsys.readouterr()
    row = next(ln for ln in out.out.splitlines() if "E12" in ln)
    assert "OVERDUE" in row and "OVERDUE" in out.err
    assert main(["fleet", "status", "--db", db, "--json"]) == 0
    u = json.loads(capsys.readouterr().out)["units"][0]
    assert u["overdue"] and u["next_limit"]["overdue"] and u["next_limit"]["limit_percent"] == 3.0
    # on 2023-01-01 the same forecast lies ahead: not overdue
    monkeypatch.setenv("SOURCE_DATE_EPOCH", "1672531200")
    assert main(["fleet", "status", "--db", db, "--json"]) == 0
    assert not json.loads(capsys.readouterr().out)["units"][0]["overdue"]


def test_write_report_never_replaces_a_file_unless_told(phone_file, tmp_path):
    from vibkit.diagnose.report import write_report

    out = tmp_path / "r.pdf"
    out.write_bytes(b"mine")
    with pytest.raises(ValueError, match="already exists"):
        write_report(phone_file / "phone.nc", out, speed=SPEED)
    assert out.read_bytes() == b"mine"


@pytest.mark.slow
@pytest.mark.parametrize("against", ["sim/las-palmas.toml", "the profile's scene"])
def test_report_states_one_speed_and_pitch_and_names_the_unit(phone_file, tmp_path, against):
    from vibkit.diagnose.report import write_report
    from vibkit.model.profile import load_profile

    profile = load_profile(phone_file / "e07.toml")
    rep = write_report(
        phone_file / "phone.nc",
        tmp_path / "r.pdf",
        scene=against if against.endswith(".toml") else profile.scene("forward", 8.0),
        speed=SPEED,
        speed_sigma="0.05%",
        duration=8.0,
        profile=profile,
    )
    text = {t: "\n".join(x) for t, x in rep.pages}
    speeds, pitches = set(), set()
    for title, page in text.items():
        if title == "parameters":  # the scene's own text is printed there as it is
            page = page.split("Scene ")[0]
        speeds |= set(re.findall(r"(\d\.\d+) \+- [\d.]+ m/s", page))
        pitches |= set(re.findall(r"(1\d\d\.\d+) \+- [\d.]+ mm", page))
        assert "taken as the scene's nominal" not in page and "nan" not in page.split()
    assert speeds == {"0.50000"} and pitches == {"134.601"}
    v1 = text["verdict"]
    assert "E07, Leon, Plaza Mayor" in v1 and "Las Palmas" not in v1
    assert "WARNING" not in v1 and "no warning" in v1
    ratio = float(re.search(r"pitch ratio (1\.\d+) \+-", v1).group(1))
    # tolerance: an 8-s simulation finds its link pass to about 0.3 % (its transient and speed ripple)
    assert ratio == pytest.approx(LONG, abs=0.003)
    if against.endswith(".toml"):
        assert "ride quality (simulation)" not in text  # the shipped scene is not unit E07's


def test_phone_timestamp_jitter_is_a_note_not_a_warning():
    # a phone's sensor events +-3 ms around a 100 Hz grid: resampled, and the estimate does not depend on how
    rng = np.random.default_rng(1)
    t = np.sort(np.arange(6000) / 100.0 + rng.uniform(-0.003, 0.003, 6000))
    x = family(t, SPEED / (NOMINAL * LONG), AMPS) + 0.05 * rng.standard_normal(t.size)
    est = estimate_pitch(recording({"az": x}, t=t), speed=SPEED, speed_sigma=0.00025, nominal_pitch=NOMINAL)
    assert est.warnings == []
    assert [n for n in est.notes if "irregular time stamps" in n]
    assert est.elongation_percent == pytest.approx(0.95, abs=3 * est.elongation_sigma_percent)


def test_fleet_add_takes_unit_speed_and_sigma_from_the_profile(phone_file, tmp_path, capsys):
    db = str(tmp_path / "f.sqlite")
    prof = str(phone_file / "e07.toml")  # rated 0.5 m/s, no stated uncertainty: the standard's 2.9 %
    assert (
        main(
            ["fleet", "add", str(phone_file / "phone.nc"), "--escalator", prof, "--date", "2025-01-01"]
            + ["--db", db, "--json"]
        )
        == 0
    )
    m = json.loads(capsys.readouterr().out)["measurement"]
    assert m["unit"] == "E07" and m["speed_m_s"] == 0.5 and m["nominal_pitch_m"] == pytest.approx(NOMINAL)
    assert m["speed_sigma_m_s"] == pytest.approx(0.05 / 3**0.5 * 0.5)
    assert main(["fleet", "add", str(phone_file / "phone.nc"), "--db", db]) == 1
    assert "--unit" in capsys.readouterr().err
