"""The report and `fleet add` take the per-channel decision of `spectrum` and `pitch`; the report never analyses a
status column and does not call a quantised signal's extreme levels clipping."""

from __future__ import annotations

import json

import numpy as np
import pytest

from vibkit.cli import main
from vibkit.diagnose.report.context import _quantisation_explains_extremes, analyse, held_extremes


def three_axes(path, freqs, fs=50.0, seconds=120.0, seed=2, status=False):
    rng = np.random.default_rng(seed)
    t = np.arange(int(fs * seconds)) / fs
    cols = [
        np.sin(2 * np.pi * f * t) + 0.3 * np.sin(4 * np.pi * f * t) + 0.2 * rng.standard_normal(t.size) for f in freqs
    ]
    head = "time (s),ax (m/s^2),ay (m/s^2),az (m/s^2)" + (",accuracy" if status else "")
    with open(path, "w") as fh:
        fh.write(head + "\n")
        for k in range(t.size):
            fh.write(f"{t[k]:.4f}," + ",".join(f"{c[k]:.5f}" for c in cols) + (",3" if status else "") + "\n")
    return path


def test_report_refuses_channels_that_disagree_as_spectrum_does(tmp_path, capsys):
    """A two while running: three axes at 3.0, 3.1 and 3.2 Hz are not one chain, in `spectrum` and `report`."""
    p = three_axes(tmp_path / "two.csv", (3.0, 3.1, 3.2))
    rc = main(["spectrum", str(p), "--json"])
    spec = json.loads(capsys.readouterr().out)
    assert rc == 1 and spec["status"] == "implausible" and "the channels disagree" in spec["reason"]
    ctx = analyse(str(p))
    assert ctx.summary["status"] == "implausible" and "the channels disagree" in ctx.summary["reason"]
    assert not ctx.found and ctx.notes[0].startswith("IMPLAUSIBLE: the channels disagree")


def test_report_numbers_come_from_the_channel_spectrum_chooses(tmp_path, capsys):
    p = three_axes(tmp_path / "chain.csv", (3.75, 3.75, 3.75), status=True)
    rc = main(["spectrum", str(p), "--json"])
    spec = json.loads(capsys.readouterr().out)
    ctx = analyse(str(p))
    assert rc == 0 and ctx.found and ctx.summary["status"] == spec["status"] == "ok"
    assert ctx.channel == spec["channel"] != "accuracy"
    assert ctx.summary["link_pass_hz"] == pytest.approx(spec["fundamental_hz"], rel=1e-12)


def test_quantisation_is_not_clipping_but_a_clipped_quantised_signal_is():
    t = np.arange(10000) / 500
    x = np.round((0.6 * np.sin(2 * np.pi * 4 * t)) * 10) / 10
    assert _quantisation_explains_extremes(x, 0.1)
    clipped = np.minimum(x, 0.4)  # the top two levels cut: the 0.4 level piles up
    assert not _quantisation_explains_extremes(clipped, 0.1)
    assert not _quantisation_explains_extremes(x, None)  # not quantised: the generic test decides


def test_clipping_counts_held_extremes_not_a_value_that_recurs():
    """A clipped sine holds its extremes for runs of samples; a simulation whose tensioner reaches the same table
    value at five separate instants (the shipped no-load scene's delta over 6 s: four at its maximum, one at its
    minimum) holds nothing."""
    t = np.arange(2000) / 200.0
    x = np.sin(2 * np.pi * 3.75 * t)
    clipped = np.clip(x, -0.9, 0.9)
    # 3.75 Hz at 200 Hz: about 2.4 % of each cycle above 0.9 at each crest, 5 samples a crest, 75 crests each way
    assert held_extremes(clipped) > 500
    recurring = x.copy()
    recurring[[42, 425, 482, 529]] = 1.5  # the same extreme at four separate instants, and one minimum
    recurring[106] = -1.5
    assert held_extremes(recurring) == 0
    recurring[43] = 1.5  # two in a row: a flat top of two samples
    assert held_extremes(recurring) == 2


def test_report_on_an_android_log_never_analyses_its_status_column(tmp_path, capfd):
    """The constant 'accuracy' column once went to the report: numpy RuntimeWarnings and LAPACK DLASCL lines."""
    import warnings

    rng = np.random.default_rng(4)
    t = np.arange(2000) / 100.0
    stamps = 81_234_567_890_123 + np.round(t * 1e9).astype(np.int64)  # ns since boot
    x = 0.2 * np.sin(2 * np.pi * 3.75 * t) + 0.05 * np.sin(4 * np.pi * 3.75 * t) + 0.05 * rng.standard_normal(t.size)
    p = tmp_path / "android_accelerometer.csv"
    p.write_text(
        "timestamp,accuracy,x,y,z\n"  # the status first: once the default channel
        + "".join(
            f"{s},3,{a:.5f},{0.05 * b:.5f},{9.81 + 0.05 * c:.5f}\n"
            for s, a, b, c in zip(stamps, x, *rng.standard_normal((2, t.size)))
        )
    )
    with warnings.catch_warnings():
        warnings.simplefilter("error", RuntimeWarning)
        ctx = analyse(str(p), speed=0.5)
    captured = capfd.readouterr()
    assert ctx.channel == "x" and ctx.summary["status"] == "ok"
    assert "DLASCL" not in captured.out + captured.err


def test_a_profile_gives_the_report_its_sprocket_and_band_whatever_scene_is_beside_it():
    # the unit's profile: 24 teeth; the scene given beside it (Leon's) has 28: the report's pitch is the unit's,
    # searched in the profile's band as `vibkit pitch --escalator` searches it
    from vibkit.diagnose.report.context import analyse
    from vibkit.model.profile import parse_profile

    prof = parse_profile(
        '[escalator]\nunit = "X24"\n[drive]\nspeed = 0.49\nspeed_uncertainty = 0.0005\nteeth = 24\n'
        "[chain]\nnominal_pitch = 0.13333\nlinks_per_step = 3\nn_links = 120\n",
        "X24.toml",
    )
    ctx = analyse("data/field/leon-tensioner.csv", scene="sim/leon.toml", duration=2.0, profile=prof)
    assert ctx.pitch.band_hz == pytest.approx(prof.search_band(0.49))
    shaft = [h.name for h in ctx.pitch.hypotheses if "sprocket shaft" in h.name]
    assert "f is the sprocket shaft (Z = 24)" in shaft and not any("28" in name for name in shaft), shaft


def test_fleet_add_takes_the_channel_decision_of_pitch(tmp_path, capsys):
    """`fleet add` analyses every vibration channel as `pitch` does: a first channel without the link pass is
    passed over for the one `pitch` chooses, and channels that disagree are refused with nothing stored."""
    from vibkit.fleet import FleetDB

    db = str(tmp_path / "f.sqlite")
    speed = ["--speed", "0.5", "--speed-uncertainty", "0.1%"]

    def add(path, unit):
        return main(
            ["fleet", "add", str(path), "--unit", unit, *speed, "--nominal-pitch", "0.13333", "--date", "2026-01-01"]
            + ["--db", db, "--json"]
        )

    chain = three_axes(tmp_path / "chain.csv", (0.0, 3.75, 3.75))  # ax: noise alone
    assert main(["pitch", str(chain), *speed, "--json"]) == 0
    pitch = json.loads(capsys.readouterr().out)
    assert pitch["channel"] != "ax" and pitch["channels"][0]["status"] == "no link-pass found"
    assert add(chain, "U1") == 0
    capsys.readouterr()
    with FleetDB(db) as fdb:
        (m,) = fdb.measurements("U1")
    assert m.channel == pitch["channel"] and m.pitch_m == pytest.approx(pitch["pitch_m"], rel=1e-12)

    two = three_axes(tmp_path / "two.csv", (3.70, 3.72, 3.74))  # each a chain 0.3-1.4 % long
    assert main(["pitch", str(two), *speed, "--json"]) == 1
    assert json.loads(capsys.readouterr().out)["status"] == "implausible"
    assert add(two, "U2") == 1
    err = capsys.readouterr().err
    assert "implausible: the channels disagree" in err and "nothing stored" in err and err.count("\n") == 1
    with FleetDB(db) as fdb:
        assert fdb.measurements("U2") == []
