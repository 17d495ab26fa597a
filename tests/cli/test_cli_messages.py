"""The command line's messages on a user's mistake or an unusable file: one line, naming the file, the flag
or what was expected; no Python parameter names, no repeated file names, no numpy warnings."""

from __future__ import annotations

import io
import json
import sys
from pathlib import Path

import pytest

from vibkit.cli import main

ROOT = Path(__file__).resolve().parents[2]
LEON = ROOT / "data" / "field" / "leon-tensioner.csv"


def _error(capsys) -> str:
    err = capsys.readouterr().err.strip()
    assert "\n" not in err, err
    assert "Parameter" not in err and "Traceback" not in err and "Warning" not in err, err
    return err


@pytest.mark.parametrize("command", ["pitch", "links", "report"])
def test_negative_speed_is_a_positive_chain_speed(command, capsys):
    with pytest.raises(SystemExit) as exc:
        main([command, str(LEON), "--speed", "-1"])
    assert exc.value.code == 2
    err = capsys.readouterr().err
    assert "expected a positive chain speed, got '-1'" in err
    assert "positive a " not in err


def test_unknown_channel_names_the_file_once(capsys):
    assert main(["spectrum", str(LEON), "--channel", "nope"]) == 1
    err = _error(capsys)
    assert err.startswith(f"vibkit spectrum: error: {LEON}: channel 'nope' is not in the recording")
    assert err.count("leon-tensioner.csv") == 1


def test_unknown_channel_on_stdin_names_stdin_once(monkeypatch, capsys):
    monkeypatch.setattr(sys, "stdin", io.TextIOWrapper(io.BytesIO(LEON.read_bytes())))
    assert main(["spectrum", "-", "--channel", "nope"]) == 1
    err = _error(capsys)
    assert err.startswith("vibkit spectrum: error: <stdin>: channel 'nope' is not in the recording"), err
    assert "-: " not in err


class _ClosedPipe(io.TextIOBase):
    """A stdout whose reader has gone (``| head -1``)."""

    def writable(self):
        return True

    def write(self, s):
        raise BrokenPipeError(32, "Broken pipe")


def test_closed_stdout_ends_quietly_with_0(monkeypatch, capsys):
    capsys.readouterr()
    monkeypatch.setattr(sys, "stdout", _ClosedPipe())
    assert main(["spectrum", str(LEON), "--json"]) == 0
    assert capsys.readouterr().err == ""


def _wrong_time_column(tmp_path) -> Path:
    """Leon's recording with its time column 2e7 times too long (a unit mistaken): 1e-5 Hz rows."""
    out = []
    for line in LEON.read_text().splitlines():
        if line[:1].isdigit():
            t, rest = line.split(",", 1)
            line = f"{float(t) * 2e7!r},{rest}"
        out.append(line)
    path = tmp_path / "wrong-time.csv"
    path.write_text("\n".join(out) + "\n")
    return path


def test_links_on_a_wrong_time_column_names_the_rate_and_the_speed(tmp_path, capsys):
    path = _wrong_time_column(tmp_path)
    assert main(["links", str(path), "--links", "159", "--speed", "0.5"]) == 1
    err = _error(capsys)
    assert err.startswith(f"vibkit links: error: {path}: the recording's sample rate 1e-05 Hz"), err
    assert "cannot show a link pass at 0.5 m/s (speed / 200-80 mm: 2.5-6.25 Hz)" in err
    assert "check the time column" in err
    assert err.count(path.name) == 1


def test_links_band_above_nyquist_names_the_flag(capsys):
    assert main(["links", str(LEON), "--links", "159", "--band", "2:150"]) == 1
    err = _error(capsys)
    assert f"{LEON}: --band 2-150 Hz reaches above the Nyquist frequency 100 Hz" in err, err


SCIENCE_JOURNAL = ROOT / "data" / "devices" / "science_journal" / "Untitled Experiment Trial 1.csv"


@pytest.mark.parametrize("argv", [["spectrum"], ["pitch", "--speed", "0.5"]])
def test_bursts_at_different_rates_say_so(argv, capsys):
    # two bursts (100 rows at 12.59 Hz, 38 at 13.55 Hz after a gap): the detection's one rate is neither's
    assert main([argv[0], str(SCIENCE_JOURNAL), *argv[1:]]) == 1
    err = capsys.readouterr().err.strip().splitlines()[-1]  # after the note on the held values
    assert "Parameter" not in err
    assert err.startswith(f"vibkit {argv[0]}: error: {SCIENCE_JOURNAL}: channel 'value': its 2 bursts"), err
    assert "(100 samples at 12.59 Hz, 38 samples at 13.55 Hz)" in err
    assert "needs bursts at one sample rate" in err


@pytest.fixture
def infinite_sigmas(monkeypatch):
    """Every burst's chosen frequency with an infinite sigma (harmonics lost in the noise): zero weights."""
    import dataclasses
    import math

    from vibkit.diagnose import pitch_steps

    chosen = pitch_steps.choose_methods
    monkeypatch.setattr(
        pitch_steps,
        "choose_methods",
        lambda ests: [dataclasses.replace(be, sigma_hz=math.inf) for be in chosen(ests)],
    )


def test_zero_weights_give_a_plain_message_not_a_nan(infinite_sigmas, capsys):
    import warnings

    with warnings.catch_warnings():
        warnings.simplefilter("error")  # the division by zero weights warned (numpy RuntimeWarning)
        assert main(["pitch", str(LEON), "--json"]) == 1
    err = _error(capsys)
    assert "NaN" not in err and "integer" not in err
    assert "channel 'tensioner_displacement': no burst gives a link-pass frequency with a finite uncertainty" in err


def test_zero_weights_in_one_of_several_channels_are_its_error_row(infinite_sigmas, tmp_path, capsys):
    lines = [ln for ln in LEON.read_text().splitlines() if not ln.startswith("#")]
    two = [lines[0] + ",copy (mm)"] + [f"{ln},{ln.split(',')[1]}" for ln in lines[1:]]
    path = tmp_path / "two.csv"
    path.write_text("\n".join(two) + "\n")
    assert main(["spectrum", str(path), "--json"]) == 1
    err = _error(capsys)
    assert "no channel could be analysed" in err and "finite uncertainty" in err and "NaN" not in err


def test_a_sprocket_speed_is_a_speed_channel_not_analysed():
    # the guide: pitch and spectrum analyse every vibration channel, not a speed channel; a sprocket's angular
    # speed (rad/s) is one, as a chain's (m/s) is; a gyroscope's rad/s (not named a speed) stays a vibration
    import numpy as np

    from vibkit.diagnose.channels import vibration_channels

    from support.recording import recording

    t = np.arange(2000) / 200.0
    wiggle = np.sin(2 * np.pi * 3.75 * t)
    rec = recording({"delta": wiggle, "sprocket_speed": 0.84 + 1e-3 * wiggle, "gyro_z": wiggle}, t=t)
    for name, units in (("delta", "m"), ("sprocket_speed", "rad/s"), ("gyro_z", "rad/s")):
        rec[name].attrs["units"] = units
    assert vibration_channels(rec) == ["delta", "gyro_z"]
    rec["sprocket_speed"].attrs["units"] = "rpm"
    assert vibration_channels(rec) == ["delta", "gyro_z"]


def test_an_empty_source_date_epoch_is_unset_and_a_bad_one_is_named(tmp_path, run, monkeypatch):
    """numpy (imported by scipy) reads SOURCE_DATE_EPOCH with int(): an empty one made every command fail with
    "invalid literal for int()"; it now counts as unset, and a value that is no integer is named in one line."""
    import os

    import numpy as np
    import xarray as xr

    t = np.arange(6000) / 200.0
    path = tmp_path / "c.nc"
    xr.Dataset({"delta": ("time", 1e-5 * np.cos(2 * np.pi * 3.75 * t), {"units": "m"})}, coords={"time": t}).to_netcdf(
        path
    )
    monkeypatch.setenv("SOURCE_DATE_EPOCH", "")
    rc, out, err = run("spectrum", path, "--speed", "0.5")
    assert rc != 1 and "error" not in err and "SOURCE_DATE_EPOCH" not in os.environ
    monkeypatch.setenv("SOURCE_DATE_EPOCH", "yesterday")
    rc, out, err = run("spectrum", path, "--speed", "0.5")
    assert rc == 1 and out == "" and "SOURCE_DATE_EPOCH='yesterday' is not a whole number" in err


def test_a_bare_speed_uncertainty_as_large_as_a_speed_is_refused_with_the_percentage_meant(capsys):
    """`--speed-uncertainty 5` is 5 m/s, ten times an escalator's speed: refused, asking whether 5 % was meant
    (it gave 'speed 0.5 +- 5.0 m/s, link pitch 100 +- 1400 mm', status ok)."""
    with pytest.raises(SystemExit) as e:
        main(["pitch", "data/field/leon-tensioner.csv", "--speed", "0.49", "--speed-uncertainty", "5"])
    assert e.value.code == 2 and "did you mean 5%?" in capsys.readouterr().err
    assert main(["pitch", "data/field/leon-tensioner.csv", "--speed", "0.49", "--speed-uncertainty", "0.001"]) == 0


def test_a_usage_error_is_one_line_that_says_where_the_options_are(capsys):
    """argparse printed its whole usage (12 lines) before the one line that says what is wrong."""
    with pytest.raises(SystemExit) as e:
        main(["pitch", "data/field/leon-tensioner.csv", "--speed-uncertainty"])
    err = capsys.readouterr().err
    assert e.value.code == 2 and len(err.strip().splitlines()) == 1, err
    assert err.startswith("vibkit pitch: error:") and "'vibkit pitch --help'" in err


def test_pitch_takes_the_sprocket_and_steps_a_simulation_states(tmp_path, capsys):
    """A stranger's simulated escalator of 17 teeth and 4-link steps got the study's Z = 28 and 3-link steps in
    `pitch`'s hypotheses: a file that states them (a vibkit result) is read with its own."""
    import numpy as np
    import xarray as xr

    from vibkit.cli.app import main

    t = np.arange(0, 20, 0.005)
    ds = xr.Dataset(
        {"delta": ("time", 1e-4 * np.cos(2 * np.pi * 7.38 * t), {"units": "m"})},
        coords={"time": ("time", t, {"units": "s"})},
        attrs={"chain_speed_m_s": 0.75, "sprocket_teeth": 17, "links_per_step": 4},
    )
    path = tmp_path / "sim.nc"
    ds.to_netcdf(path)
    main(["pitch", str(path), "--nominal-pitch", "101.6mm"])
    out = capsys.readouterr().out
    assert "sprocket shaft (Z = 17)" in out and "step pass (4 links)" in out


def test_compare_does_not_judge_a_pitch_without_the_recordings_speed(tmp_path, capsys):
    """A stranger's recording stated no speed: compare took the scene's and printed a pitch ratio +- 0.000015,
    a precision of a speed nobody measured. Without the recording's speed the pitch is not judged."""
    import numpy as np

    from vibkit.cli.app import main

    t = np.arange(0, 20, 0.005)
    x = 1e-4 * np.cos(2 * np.pi * 3.6 * t) + 2e-5 * np.cos(2 * np.pi * 7.2 * t + 1)
    path = tmp_path / "rec.csv"
    path.write_text("time_s,displacement_m\n" + "".join(f"{a:.3f},{b:.8f}\n" for a, b in zip(t, x)))
    assert main(["compare", str(path), "sim/thesis-inverse.toml", "--duration", "20"]) == 0
    out, err = capsys.readouterr()
    assert "pitch     not judged: the recording's speed is not known (give --speed)" in out
    assert "+-" not in out.split("pitch ", 1)[1].split("\n", 1)[0]
    assert "consistent" not in out + err  # nor in a note (a stranger found the verdict there)
    assert main(["compare", str(path), "sim/thesis-inverse.toml", "--duration", "20", "--json"]) == 0
    assert json.loads(capsys.readouterr().out)["pitch_consistent"] is None


def test_a_time_column_in_ms_labelled_s_names_the_option(tmp_path, capsys):
    """A stranger's 'Time [s]' column held milliseconds: the band error named neither the time column nor the
    option that reads it (--time-unit ms)."""
    from vibkit.cli.app import main

    p = tmp_path / "rec.csv"
    p.write_text("Time [s],disp [mm]\n" + "".join(f"{5 * i},{0.01 * (i % 7):.3f}\n" for i in range(4000)))
    assert main(["pitch", str(p), "--speed", "0.65", "--nominal-pitch", "135.47mm"]) == 1
    assert "(--time-unit ms)" in " ".join(capsys.readouterr().err.split())
