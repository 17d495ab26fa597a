"""The command line through main([...]): every command, its --json, its errors and exit codes."""

import json
import os
import re
import sys
from pathlib import Path

import pytest

from vibkit.cli import main

LEON = "data/field/leon-tensioner.csv"
LP = "data/field/las-palmas-accelerometer.csv"


@pytest.fixture(scope="module")
def leon_nc(tmp_path_factory):
    out = tmp_path_factory.mktemp("cli") / "leon.nc"
    assert main(["simulate", "sim/leon.toml", "-o", str(out), "--duration", "4"]) == 0
    return out


def _json(capsys):
    out = capsys.readouterr().out
    return json.loads(out)


def test_simulate_json(tmp_path, capsys):
    out = tmp_path / "k.nc"
    assert main(["simulate", "sim/thesis-kinematics.toml", "-o", str(out), "--duration", "0.05", "--json"]) == 0
    d = _json(capsys)
    assert d["schema"] == "vibkit.simulate/1"
    assert d["variables"]["delta"]["units"] == "m"
    assert d["closure_residual_max_m"] < 1e-9
    assert out.exists()


def test_simulate_refuses_to_overwrite_input(tmp_path, capsys):
    scene = tmp_path / "s.toml"
    scene.write_text(Path("sim/thesis-kinematics.toml").read_text())
    assert main(["simulate", str(scene), "-o", str(scene)]) == 1
    err = capsys.readouterr().err
    assert "refusing to overwrite" in err and "Traceback" not in err
    assert "[kinematics]" in scene.read_text()


def test_spectrum_table_and_json(capsys):
    assert main(["spectrum", LEON]) == 0
    out = capsys.readouterr().out
    assert "link-pass fundamental 3.539" in out and "amplitude [m]" in out
    assert main(["spectrum", LEON, "--json", "--band", "2.5:6"]) == 0
    d = _json(capsys)
    assert d["schema"] == "vibkit.spectrum/1"
    assert d["fundamental_hz"] == pytest.approx(3.54, abs=0.005)
    assert d["peaks"][1]["frequency_hz"] == pytest.approx(2 * d["fundamental_hz"])


def test_pitch_json_keys(capsys):
    assert (
        main(["pitch", LEON, "--speed", "0.49", "--speed-uncertainty", "0.1%", "--nominal-pitch", "0.133333", "--json"])
        == 0
    )
    d = _json(capsys)
    assert d["schema"] == "vibkit.pitch/1"
    for key in (
        "fundamental_hz",
        "fundamental_sigma_hz",
        "pitch_m",
        "pitch_sigma_m",
        "elongation_percent",
        "harmonics",
        "warnings",
        "hypotheses",
    ):
        assert key in d
    assert d["pitch_m"] == pytest.approx(0.1384, abs=2e-4)
    assert d["speed_sigma_m_s"] == pytest.approx(0.00049)
    assert d["pitch_sigma_m"] >= d["pitch_m"] * 1e-3  # the speed's 0.1 % dominates
    assert d["verdict"] == "replace"
    assert {"frequency_hz", "amplitude", "order"} <= set(d["harmonics"][0])


def test_pitch_table_bursts(capsys):
    assert main(["pitch", LP, "--speed", "0.52", "--limits", "1,2,4", "--nominal-pitch", "0.13333"]) == 0
    cap = capsys.readouterr()
    assert "(6 burst(s))" in cap.out and "f is the link pass" in cap.out and "step pass" in cap.out
    assert "by construction" in " ".join(cap.err.split())  # messages are wrapped at 100 columns


def test_pitch_no_time_column_needs_sample_rate(capsys):
    f = "data/field/layouts/no-time-column.txt"  # 1 s at 2050 Hz: three periods need a band above 3 Hz
    # its one second holds no detectable link-pass family (harmonic least squares finds every harmonic
    # below its own detection limit, SNR -5 dB): the honest answer is "no link-pass found", exit 1
    assert (
        main(
            ["pitch", f, "--speed", "0.52", "--sample-rate", "2050", "--band", "3.5:6", "--channel", "acc_x", "--json"]
        )
        == 1
    )
    d = _json(capsys)
    assert d["status"] == "no link-pass found" and "fundamental_hz" not in d
    assert d["detection"]["segment_s"] == pytest.approx(2050 / 2050, rel=1e-2)  # the given sample rate was used


def test_compare_result_file(leon_nc, capsys):
    assert main(["compare", str(leon_nc), str(leon_nc), "--json"]) == 0
    d = _json(capsys)
    assert d["schema"] == "vibkit.compare/1"
    assert d["score"] == pytest.approx(1.0) and d["pitch_consistent"] is True
    assert main(["compare", LEON, str(leon_nc)]) == 0
    out = capsys.readouterr().out
    assert "NOT consistent" in out


def test_compare_chooses_the_channel_as_pitch_does_and_takes_a_scene_by_name(leon_nc, monkeypatch, tmp_path, capsys):
    """A stranger's three-axis logger file: `pitch` and `report` analysed az (the link pass at 3.896 Hz), `compare`
    took the first channel, ax, found no link pass and blamed the scene file; and `compare` alone did not take a
    shipped scene's name. Now: the same channel, a recording's refusal named after the recording, and scenes by
    name."""
    gcdc = "data/field/layouts/gcdc-x16.csv"
    assert main(["pitch", gcdc, "--speed", "0.52", "--json"]) in (0, 3)
    chosen = _json(capsys)["channel"]
    assert main(["compare", gcdc, "sim/las-palmas.toml", "--duration", "6", "--json"]) == 0
    d = _json(capsys)
    assert d["channel"] == chosen == "az"
    assert d["link_pass_meas_hz"] == pytest.approx(3.896, abs=0.002)
    # a recording without a link pass: the message names the recording, not the scene
    assert main(["compare", "data/thirdparty/obspy_gaps.mseed", "sim/las-palmas.toml", "--duration", "2"]) == 1
    err = capsys.readouterr().err
    assert "obspy_gaps.mseed: no link-pass found" in err and "las-palmas.toml:" not in err
    # a shipped scene by name, from a folder that has no sim/
    rec = os.path.abspath(str(leon_nc))
    monkeypatch.chdir(tmp_path)
    assert main(["compare", rec, "leon", "--duration", "4", "--json"]) == 0
    assert _json(capsys)["score"] == pytest.approx(1.0)


@pytest.mark.slow
def test_report_json(leon_nc, tmp_path, capsys):
    out = tmp_path / "r.pdf"
    assert main(["report", LEON, "-o", str(out), "--json"]) == 0
    d = _json(capsys)
    assert d["schema"] == "vibkit.report/1" and "verdict" in d["pages"] and out.exists()
    # without --json: the summary table on stdout, what was written a message on stderr
    assert main(["report", LEON, "-o", str(out), "--force"]) == 0
    cap = capsys.readouterr()
    assert cap.err.rstrip().endswith(f"vibkit report: wrote {out} ({len(d['pages'])} pages)")
    assert "wrote" not in cap.out and "verdict" in cap.out
    # values in their units, sigmas to two significant digits with their zeros
    assert re.search(r"^rms +[0-9.e+-]+ m$", cap.out, re.M) and re.search(
        r"^fundamental_sigma_hz +0\.000[0-9]{2}$", cap.out, re.M
    )


def test_report_table_gives_a_flagged_link_as_text():
    """A stranger's report table printed the flagged links as a Python list of dicts with 16 digits."""
    from vibkit.cli.report import _shown

    flag = {"link": 210, "alternatives": [28], "excess_pitch_mm": 0.7906982260359852, "sigma_mm": 0.008363426626000377}
    assert (
        _shown("flagged_links_detail", [{**flag, "loops": [1, 2, 3]}], {})
        == "210 (or 28): +0.7907 +- 0.0084 mm, loops 1,2,3"
    )
    assert _shown("flagged_links", [210, 14], {}) == "210, 14" and _shown("flagged_links", [], {}) == "none"


@pytest.mark.parametrize(
    "argv",
    [
        ["pitch", LEON, "--speed", "49"],
        ["nonsense"],
        ["pitch", LEON, "--speed", "-1"],
        ["pitch", LEON, "--speed", "0.5", "--band", "6:2"],
        [],
        ["pitch", LEON, "--speed", "0.5", "--speed-uncertainty", "abc"],
    ],
)
def test_usage_errors_exit_2(argv, capsys):
    with pytest.raises(SystemExit) as exc:
        main(argv)
    assert exc.value.code == 2


@pytest.mark.parametrize(
    "argv, text",
    [
        (["pitch", "missing.csv", "--speed", "0.5"], "file not found"),
        (["pitch", LEON, "--speed", "0.5", "--channel", "nope"], "channel 'nope'"),
        (["simulate", "missing.toml", "-o", "x.nc"], "missing.toml"),
        (["compare", LEON, "missing.toml"], "file not found"),
        (["report", LEON, "-o", "out.txt"], ".pdf"),
    ],
)
def test_data_errors_exit_1_one_line(argv, text, capsys, tmp_path, monkeypatch):
    assert main(argv) == 1
    err = capsys.readouterr().err
    assert text in err and "Traceback" not in err
    assert err.count("\n") == 1


@pytest.mark.parametrize(
    "argv",
    [
        ["pitch", "missing.csv", "--speed", "0.5"],
        ["spectrum", "missing.csv"],
        ["links", "missing.csv", "--speed", "0.5", "--links", "40"],
        ["report", "missing.csv", "-o", "r.pdf"],
        ["report", LEON, "--scene", "missing.toml", "-o", "r.pdf"],
    ],
)
def test_json_error_is_one_line_on_stderr_and_nothing_on_stdout(argv, capsys, tmp_path, monkeypatch):
    """A bad input with --json: exit 1, the one-line message on stderr, stdout empty (no half document);
    ``report`` as ``pitch``, ``spectrum`` and ``links`` (a refused analysis is data: its JSON has a status)."""
    monkeypatch.chdir(tmp_path)
    argv = [str(Path(__file__).parents[2] / a) if a == LEON else a for a in argv]  # read from tmp_path
    assert main([*argv, "--json"]) == 1
    out, err = capsys.readouterr()
    assert out == "" and err.count("\n") == 1 and "missing." in err and "Traceback" not in err
    assert not (tmp_path / "r.pdf").exists()


def test_bench(tmp_path, capsys):
    b = tmp_path / "benchmarks"
    b.mkdir()
    (b / "bench_ok.py").write_text("import sys\nprint('quick' if '--quick' in sys.argv else 'full')\n")
    (b / "bench_bad.py").write_text("raise SystemExit(3)\n")
    assert main(["bench", "--root", str(tmp_path), "--quick", "--only", "ok", "--json"]) == 0
    d = _json(capsys)
    assert d["schema"] == "vibkit.bench/1" and d["results"][0]["last_line"] == "quick"
    assert main(["bench", "--root", str(tmp_path)]) == 1
    assert "1 of 2" in capsys.readouterr().err
    assert main(["bench", "--root", str(tmp_path / "nowhere")]) == 1


def test_help_shows_example(capsys):
    for cmd in ("simulate", "spectrum", "pitch", "compare", "report", "bench"):
        with pytest.raises(SystemExit) as exc:
            main([cmd, "--help"])
        assert exc.value.code == 0
        assert f"vibkit {cmd}" in capsys.readouterr().out


def test_python_m_vibkit():
    import subprocess

    r = subprocess.run(
        [sys.executable, "-m", "vibkit", "--version"],
        capture_output=True,
        text=True,
        env={**os.environ, "NO_COLOR": "1"},
    )
    assert r.returncode == 0 and r.stdout.startswith("vibkit ")


def test_simulate_check_json_carries_the_convergence_verdict(tmp_path, capsys):
    out = tmp_path / "fwd.nc"
    assert main(["simulate", "sim/thesis-forward.toml", "-o", str(out), "--duration", "2", "--check", "--json"]) == 0
    d = json.loads(capsys.readouterr().out)
    conv = d["convergence"]
    assert conv["converged"] is True and conv["rtol"] == 1e-7
    assert [r["rtol"] for r in conv["runs"]] == pytest.approx([1e-7, 1e-9])
    assert "converged" in conv["message"]
    import xarray as xr

    with xr.open_dataset(out) as ds:
        assert ds.attrs["converged"] == 1 and json.loads(ds.attrs["convergence"]) == conv
