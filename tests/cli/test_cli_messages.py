"""The command line's messages on a user's mistake or an unusable file: one line, naming the file, the flag
or what was expected; no Python parameter names, no repeated file names, no numpy warnings."""

from __future__ import annotations

import io
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
