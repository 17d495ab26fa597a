"""The parts check: a drifting source's sigma covers its truth, a gait gets no verdict at any forced speed, a steady
chain's result is what it was without the check."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest

from vibkit.diagnose import pitch as pitch_mod
from vibkit.diagnose.decision import MAX_PART_WANDER, STATUS_INCONCLUSIVE, STATUS_OK
from vibkit.diagnose.pitch import estimate_pitch
from vibkit.diagnose.pitch_parts import PartsCheck

from support import chain, drift
from support.evidence import chain_evidence
from support.recording import recording

NOMINAL = 0.4 / 3.0
ROOT = Path(__file__).resolve().parents[2]
FS = 25.0


def _rec(x, fs=FS):
    return recording({"x": x}, fs)


def _coverage(make, n, seed):
    """2-sigma coverage of the truth after and before the parts check, and the statuses, over ``n`` records."""
    rng = np.random.default_rng(seed)
    after = before = 0
    statuses = []
    for _ in range(n):
        x, truth = make(rng)
        est = estimate_pitch(_rec(x), speed=truth * NOMINAL, nominal_pitch=NOMINAL)
        assert est.has_link_pass
        err = abs(est.fundamental_hz - truth)
        after += err <= 2 * est.fundamental_sigma_hz
        before += err <= 2 * est.parts["sigma_before_hz"]
        statuses.append(est.status)
    return after / n, before / n, statuses


# The widened sigma is the parts' scatter of the mean with K - 1 = 3 to 7 degrees of freedom: its 2-sigma interval
# covers 86-91 % (Student's t), not 95 %. 0.8 lies 2.1 binomial standard deviations (of 40 records at 0.9) below
# that; the stated sigmas before the check cover a few per cent to three quarters.


def test_wandering_source_sigma_covers_its_centre():
    """A random wander about f_c (0.5 %, correlation 3 s, 60 s records): another record of the same source
    lands within the widened 2 sigma of this one's estimate; the Cramer-Rao / end-phase sigma alone misses."""

    def make(rng):
        x, centre, _ = drift.ou_wander(60.0, FS, rng.uniform(3.0, 4.5), 0.005, 3.0, rng.uniform(0, 10), rng)
        return x, centre

    after, before, statuses = _coverage(make, 40, 301)
    assert after >= 0.8
    assert before <= 0.3
    # wanders more than a chain can: mostly no verdict (35 of 40 here; a record whose parts happen to agree
    # within 0.1 % gets one)
    assert statuses.count(STATUS_INCONCLUSIVE) >= 0.8 * len(statuses)


def test_linear_drift_sigma_covers_the_mid_record_frequency():
    """A 2 % linear drift over 60 s: the mid-record frequency (the record's mean) within the widened 2 sigma."""

    def make(rng):
        x, mid, _ = drift.linear_drift(60.0, FS, rng.uniform(3.0, 4.5), 0.02, rng.uniform(0, 10), rng)
        return x, mid

    after, before, statuses = _coverage(make, 30, 302)
    assert after >= 0.8
    assert before < after
    assert set(statuses) == {STATUS_INCONCLUSIVE}


def test_gait_gets_no_verdict_at_any_forced_speed(run, tmp_path):
    """A cadence of 2.72 Hz wandering +-1 % over minutes, with harmonics and noise, on one channel of three:
    ``vibkit pitch --channel wrist --speed v`` from 0.3 to 0.75 m/s, with and without a nominal pitch that
    makes it a plausible link pass, gives no verdict (refused, exit 1, or inconclusive, exit 3)."""
    rng = np.random.default_rng(303)
    x, cadence, _ = drift.gait(300.0, FS, rng, snr_db=6.0)
    t = np.arange(x.size) / FS
    path = tmp_path / "run.csv"
    cols = np.column_stack([t, x, 0.5 * x + 0.3 * rng.standard_normal(x.size), rng.standard_normal(x.size)])
    np.savetxt(path, cols, delimiter=",", header="time (s),wrist (m/s^2),other (m/s^2),z (m/s^2)", comments="")
    wander_seen = 0
    for v in np.round(np.arange(0.30, 0.751, 0.05), 2):
        for extra in ([], ["--nominal-pitch", f"{v / cadence * 1.005:.6f}"]):
            rc, out, err = run("pitch", path, "--channel", "wrist", "--speed", v, *extra)
            assert rc in (1, 3), (v, extra, out, err)
            wander_seen += "wanders" in out + err
    assert wander_seen >= 5  # where the cadence lies in the band, the reason names the measured wander


def test_gait_reason_names_the_measured_wander():
    rng = np.random.default_rng(304)
    x, cadence, _ = drift.gait(300.0, FS, rng, snr_db=6.0)
    est = estimate_pitch(_rec(x), speed=0.365, nominal_pitch=0.365 / cadence, channel="x")
    assert est.status == STATUS_INCONCLUSIVE and est.verdict == "inconclusive"
    assert est.parts["wander_percent"] > 100 * MAX_PART_WANDER
    assert f"wanders {est.parts['wander_percent']:.2g} %" in est.reason
    assert any("sigma widened" in w for w in est.notes)
    assert est.parts["widened"] and est.fundamental_sigma_hz > 5 * est.parts["sigma_before_hz"]


def _without_check(ests, comb, n_links=None):
    return PartsCheck(False, "check off", sigma_before_hz=comb.sigma, sigma_hz=comb.sigma), comb.sigma


@pytest.mark.parametrize("snr_db, seconds, f", [(-3.0, 60.0, 3.75), (10.0, 120.0, 3.3), (20.0, 40.0, 4.2)])
def test_steady_chain_result_unchanged_by_the_check(monkeypatch, snr_db, seconds, f):
    rng = np.random.default_rng(int(snr_db + seconds))
    x = chain.noisy_family(int(seconds * 100), 100.0, f, rng, snr_db)
    rec = recording({"x": x}, 100.0)
    with_check = estimate_pitch(rec, speed=f * NOMINAL, nominal_pitch=NOMINAL)
    monkeypatch.setattr(pitch_mod, "check_parts", _without_check)
    without = estimate_pitch(rec, speed=f * NOMINAL, nominal_pitch=NOMINAL)
    assert with_check.parts["checked"] and not with_check.parts["widened"]
    assert with_check.fundamental_hz == without.fundamental_hz
    assert with_check.fundamental_sigma_hz == without.fundamental_sigma_hz
    assert with_check.status == without.status == STATUS_OK
    assert with_check.verdict == without.verdict == "ok"


def test_short_record_is_not_checked_and_says_so():
    x = chain.chain(3.75, seconds=20.0)
    est = estimate_pitch(recording({"x": x}, 200.0), speed=0.5)
    assert not est.parts["checked"] and "too short for the parts check" in est.parts["reason"]
    assert any("too short for the parts check" in n for n in est.notes)
    assert est.status == STATUS_OK


@pytest.mark.parametrize(
    "path, speed, f, verdict",
    [
        ("data/field/leon-tensioner.csv", 0.49, 3.54, "replace"),
        ("data/field/las-palmas-accelerometer.csv", 0.52, 3.9, "ok"),
    ],
)
def test_field_files_keep_their_verdicts(path, speed, f, verdict):
    from vibkit import read_recording

    est = estimate_pitch(read_recording(path), speed=speed, speed_sigma=0.001 * speed, nominal_pitch=NOMINAL)
    assert est.status == STATUS_OK and est.verdict == verdict
    assert abs(est.fundamental_hz - f) < 0.01
    assert est.parts["checked"] and est.parts["wander_percent"] < 100 * MAX_PART_WANDER


def test_decide_on_the_parts_wander():
    """At the thresholds: up to MAX_PART_WANDER a verdict, over it inconclusive naming the wander, over
    MAX_WANDER no link-pass; not checked (None) changes nothing."""
    from vibkit.diagnose.decision import MAX_WANDER, STATUS_NOT_FOUND, LinkPassEvidence, decide

    base = chain_evidence(
        3.76, resolution_hz=0.05, fundamental_sigma_hz=1e-4, part_summary="8 parts of 75 s give 3.75-3.77 Hz"
    )
    assert decide(LinkPassEvidence(**base)).verdict == "ok"
    assert decide(LinkPassEvidence(**base, part_wander=MAX_PART_WANDER)).verdict == "ok"
    over = decide(LinkPassEvidence(**base, part_wander=1.5 * MAX_PART_WANDER))
    assert over.status == STATUS_INCONCLUSIVE and over.verdict == "inconclusive"
    assert "wanders 0.15 % between parts" in over.reason and "3.75-3.77 Hz" in over.reason
    assert not over.checks["steady between parts"]
    far = decide(LinkPassEvidence(**base, part_wander=1.2 * MAX_WANDER))
    assert far.status == STATUS_NOT_FOUND and "wanders 3 %" in far.reason
    no_nominal = decide(LinkPassEvidence(**{**base, "nominal_pitch_m": None}, part_wander=0.004))
    assert no_nominal.status == STATUS_INCONCLUSIVE and no_nominal.verdict is None


def test_decide_on_the_methods_disagreement():
    """Spectral and mean-phase estimates apart by more than DISAGREE_SIGMAS *and* MAX_PART_WANDER: inconclusive,
    naming both; either under its threshold: the verdict stands."""
    from vibkit.diagnose.decision import DISAGREE_SIGMAS, LinkPassEvidence, decide

    f = 3.76
    base = dict(detected=True, detection_hz=f, resolution_hz=0.05, fundamental_hz=f, fundamental_sigma_hz=1e-4,
                band_hz=(2.5, 6.25), speed_m_s=0.5, nominal_pitch_m=0.5 / f, spectral_hz=f)  # fmt: skip
    apart = f * (1 + 2 * MAX_PART_WANDER)
    over = decide(LinkPassEvidence(**base, mean_phase_hz=apart, methods_sigmas=2 * DISAGREE_SIGMAS))
    assert over.status == STATUS_INCONCLUSIVE and over.verdict == "inconclusive"
    assert "differ by 0.2 %" in over.reason and "riding a step" in over.reason
    assert not over.checks["estimates agree"]
    # significant but within a chain's own wander, or large but not significant (a noisy record): a verdict
    near = f * (1 + 0.5 * MAX_PART_WANDER)
    assert decide(LinkPassEvidence(**base, mean_phase_hz=near, methods_sigmas=10 * DISAGREE_SIGMAS)).verdict == "ok"
    assert decide(LinkPassEvidence(**base, mean_phase_hz=apart, methods_sigmas=0.5 * DISAGREE_SIGMAS)).verdict == "ok"


def _coasting_e07(tmp_path):
    """E07's profile with no running resistance (``drive.no_load_power = 0``): the chain coasts in the teeth's
    backlash, and a step's accelerometer reads the step's own path alone."""
    text = (ROOT / "data/fleet-example/escalators/E07.toml").read_text()
    path = tmp_path / "E07-coasting.toml"
    path.write_text(text.replace("teeth = 28", "teeth = 28\nno_load_power = 0", 1))
    return path


def test_a_step_sensor_going_round_a_curve_gets_no_verdict(run, tmp_path):
    # a new chain coasting (E07's profile without running resistance, steady at 0.5 m/s from the start): step 3's
    # accelerometer reads its own path, and goes round the sprocket at about 15-20 s, where its own link-pass phase
    # shifts by half a cycle; the total tracked phase then counts 74.5 link passes in 20 s (3.72 Hz, +0.7 %
    # "elongation" at 0.0004 Hz) where the spectrum and the tensioner give 3.750 Hz: the two estimates disagree,
    # and no verdict is given
    scene, nc = tmp_path / "E07.toml", tmp_path / "E07.nc"
    assert run("scene", _coasting_e07(tmp_path), "--analysis", "forward", "-o", scene)[0] == 0
    assert run("simulate", scene, "--duration", "20", "-o", nc)[0] == 0
    rc, out, _ = run("pitch", nc, "--escalator", "data/fleet-example/escalators/E07.toml", "--channel", "accel_step",
                     "--json")  # fmt: skip
    d = json.loads(out)
    assert rc == 3 and d["status"] == STATUS_INCONCLUSIVE and d["verdict"] == "inconclusive"
    assert "estimates differ by" in d["reason"] and "riding a step goes round a curve" in d["reason"]
    rc, out, _ = run("pitch", nc, "--escalator", "data/fleet-example/escalators/E07.toml", "--channel", "delta",
                     "--json")  # fmt: skip
    tensioner = json.loads(out)
    assert abs(tensioner["fundamental_hz"] / 3.7503 - 1) < 2e-4 and tensioner["verdict"] == "ok"
    # every channel at once: the step's channel, its estimates apart, is not "a second periodicity"; the numbers
    # come from the tensioner
    rc, out, _ = run("pitch", nc, "--escalator", "data/fleet-example/escalators/E07.toml", "--json")
    both = json.loads(out)
    assert rc == 0 and both["status"] == "ok" and both["channel"] in ("delta", "tensioner_displacement")
    assert both["fundamental_hz"] == tensioner["fundamental_hz"]


def test_a_step_sensor_on_a_driven_chain_reads_the_chain(run, tmp_path):
    """E07's scene as built (a driven chain: the running resistance carried by the teeth): the drive's speed
    pulsation at the link pass (the sprocket's polygon under load) moves the whole chain at once, so step 3's
    accelerometer reads it in the chain's phase, which does not turn where the step goes round the sprocket, and
    its estimates agree; its verdict is the truth, the scene's new chain (elongation 0 within two sigmas)."""
    scene, nc = tmp_path / "E07.toml", tmp_path / "E07.nc"
    assert run("scene", "data/fleet-example/escalators/E07.toml", "--analysis", "forward", "-o", scene)[0] == 0
    assert run("simulate", scene, "--duration", "20", "-o", nc)[0] == 0
    rc, out, _ = run("pitch", nc, "--escalator", "data/fleet-example/escalators/E07.toml", "--channel", "accel_step",
                     "--json")  # fmt: skip
    d = json.loads(out)
    assert rc == 0 and d["status"] == STATUS_OK and d["verdict"] == "ok"
    assert abs(d["elongation_percent"]) < 2 * d["elongation_sigma_percent"]
