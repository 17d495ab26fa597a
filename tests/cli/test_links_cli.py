"""``vibkit links`` on constructed recordings: the table, --json with its flagged links, the refusal of
a recording under two loops (exit 1, how long to record), and usage errors."""

import json

import numpy as np
import pytest
import xarray as xr

FS = 200.0
F_LP = 3.75
SPEED = 0.5  # m/s: pitch 133.3 mm


def _recording(path, n_links, loops, *, bump_link=None, bump=0.0, seed=0):
    """A tensioner-like link-pass signal [m] over ``loops`` loops; link ``bump_link`` (from the start)
    raises the level of its own cycle by ``bump``."""
    rng = np.random.default_rng(seed)
    t = np.arange(int((loops * n_links + 2) / F_LP * FS)) / FS
    phase = 2 * np.pi * (0.3 + F_LP * t)
    x = 1e-5 * np.cos(phase) + 3e-6 * np.cos(2 * phase) + 1e-7 * rng.standard_normal(t.size)
    if bump_link is not None:
        cyc = phase / (2 * np.pi)
        x = x + bump * (((np.floor(cyc) - np.floor(cyc[0])) % n_links) == bump_link - 1)
    xr.Dataset({"delta": ("time", x, {"units": "m"})}, coords={"time": ("time", t, {"units": "s"})}).to_netcdf(path)
    return path


def test_links_flags_a_deviating_link_in_json_and_table(tmp_path, run):
    path = _recording(tmp_path / "bump.nc", 40, 2.2, bump_link=12, bump=2e-7)
    rc, out, err = run("links", path, "--speed", SPEED, "--links", 40, "--json")
    assert rc == 0, err
    d = json.loads(out)
    assert d["schema"] == "vibkit.links/1"
    assert [f["link"] for f in d["flagged"]] == [12]
    assert d["loops"] == 2
    assert d["false_alarm"] == 0.01
    rc, out, err = run("links", path, "--speed", SPEED, "--links", 40)
    assert rc == 0
    assert "12" in out.split("----")[-1]
    assert "note: without --scene" in err


def test_links_on_a_clean_chain_flags_none(tmp_path, run):
    path = _recording(tmp_path / "clean.nc", 40, 2.2)
    rc, out, err = run("links", path, "--speed", SPEED, "--links", 40, "--json")
    assert rc == 0
    assert json.loads(out)["flagged"] == []


def test_links_under_two_loops_is_refused_with_the_time_to_record(tmp_path, run):
    path = _recording(tmp_path / "short.nc", 159, 1.2)
    rc, out, err = run("links", path, "--speed", SPEED, "--links", 159)
    assert rc == 1
    assert str(path) in err
    assert "record at least 86 s" in err  # (2 x 159 + 1) / 3.75 Hz = 85.07 s, rounded up: 85 s is not enough


@pytest.mark.parametrize(
    "args, words",
    [
        (["--links", "1"], "at least 2 links"),
        (["--links", "40", "--min-excess", "-1mm"], "excess"),
        (["--links", "40", "--false-alarm", "2"], "probability"),
        (["--links", "40", "--marker", "-3"], "time"),
    ],
)
def test_links_usage_errors(tmp_path, capsys, args, words):
    from vibkit.cli import main

    path = _recording(tmp_path / "u.nc", 40, 2.2)
    with pytest.raises(SystemExit) as e:
        main(["links", str(path), "--speed", "0.5", *args])
    assert e.value.code == 2
    assert words in capsys.readouterr().err


def test_links_takes_the_chain_and_speed_from_an_escalator_profile(tmp_path, run):
    """E07's profile: 159 links at 0.5 m/s; a recording of 1.2 loops of it is refused with the time to record."""
    path = _recording(tmp_path / "e07.nc", 159, 1.2)
    rc, out, err = run("links", path, "--escalator", "data/fleet-example/escalators/E07.toml")
    assert rc == 1
    assert "159 links" in err and "record at least 86 s" in err


def test_links_without_a_number_of_links_says_how_to_give_it(tmp_path, run):
    path = _recording(tmp_path / "n.nc", 40, 2.2)
    rc, out, err = run("links", path, "--speed", SPEED)
    assert rc == 1
    assert "--links N" in err and str(path) in err


def test_links_refuses_a_step_accelerometer_and_says_why(tmp_path, run):
    """An acceleration channel (a step accelerometer) gets no link number, with or without a scene: the
    step's own passes round the heads change as much as a worn link does; the message says to record the
    tensioner."""
    src = _recording(tmp_path / "x.nc", 40, 2.2)
    ds = xr.open_dataset(src).load()
    ds["delta"].attrs["units"] = "m/s^2"
    path = tmp_path / "step.nc"
    ds.rename({"delta": "accel_step"}).to_netcdf(path)
    rc, out, err = run("links", path, "--speed", SPEED, "--links", 40)
    assert rc == 1
    assert out == ""
    assert str(path) in err and "accel_step" in err
    assert "step accelerometer gives no link number" in err
    assert "record the tensioner's displacement" in err


@pytest.mark.parametrize("command", ["links", "pitch", "spectrum"])
def test_a_number_of_links_that_the_profile_contradicts_is_refused(tmp_path, run, command):
    """E07's profile says 159 links: --links 140 beside it is one line naming both, not a scan of a chain that is
    not there (a stranger's wrong count flagged nothing on a worn chain and exited 0)."""
    path = _recording(tmp_path / "e07.nc", 159, 2.2)
    profile = "data/fleet-example/escalators/E07.toml"
    rc, out, err = run(command, path, "--escalator", profile, "--links", "140")
    assert rc == 1 and out == "" and len(err.strip().splitlines()) == 1, err
    assert "--links 140" in err and "chain.n_links = 159" in err and profile in err


def test_a_marker_outside_the_recording_is_named_by_its_flag(tmp_path, run):
    path = _recording(tmp_path / "m.nc", 40, 2.2)
    rc, out, err = run("links", path, "--speed", SPEED, "--links", "40", "--marker", "999")
    assert rc == 1 and "--marker 999.0 s must lie within the recording" in err and "marker_s" not in err


def test_a_profile_with_its_geometry_gives_the_links_its_scene_fills_in(tmp_path, run):
    """A profile with rise and incline instead of chain.n_links: `links` takes the count its scene fills in (as
    the report does), and says so; it asked for --links N before."""
    profile = tmp_path / "geo.toml"
    profile.write_text(
        '[escalator]\nunit = "G1"\n[drive]\nspeed = 0.5\nspeed_uncertainty = 0.0005\n'
        "[chain]\nnominal_pitch = 0.13333\n[geometry]\nrise = 4.5\nincline_deg = 30\n"
    )
    from vibkit.model.profile import load_profile

    n = load_profile(profile).scene("forward").chain.n_rollers
    path = _recording(tmp_path / "g.nc", 40, 2.2)
    rc, out, err = run("links", path, "--escalator", profile)
    assert rc == 1 and f"{n} links, filled in from its geometry" in err and f"{n} links" in err.splitlines()[-1]
    assert "give --links N" not in err


def test_links_says_when_too_few_samples_a_cycle_read_the_excess_low(tmp_path, run):
    """A stranger's 50 Hz recording (5.6 samples a link-pass cycle) read a 1 mm link as 0.75 mm with no word of
    it; below 10 samples a cycle a note says the excess is read low and what rate to record at."""
    global FS
    keep = FS
    FS = 30.0  # 8 samples a cycle at 3.75 Hz
    try:
        path = _recording(tmp_path / "slow.nc", 40, 2.2)
    finally:
        FS = keep
    rc, out, err = run("links", path, "--speed", SPEED, "--links", 40)
    err = " ".join(err.split())
    assert "8.0 samples per link-pass cycle" in err and "record at 50 Hz or more" in err
    rc, out, err = run("links", _recording(tmp_path / "fast.nc", 40, 2.2), "--speed", SPEED, "--links", 40)
    assert "samples per link-pass cycle" not in err


def _cut(src, path, start, end):
    """``src`` without its samples from ``start`` to ``end`` [s] (a gap in the time stamps)."""
    ds = xr.open_dataset(src).load()
    t = ds.time.values
    ds.isel(time=(t < start) | (t >= end)).to_netcdf(path)
    return path


def test_a_gap_in_the_recording_is_refused_naming_it_and_the_part_to_analyse(tmp_path, run):
    """5 loops of 40 links with link 12 raised, then the same with 6 s cut out at 10 s: the links that passed in
    the gap are unknown, so no link is numbered across it (it used to be resampled across the gap, exit 0, no flag);
    the refusal names the gap's span and the longest part, which covers over two loops; cut out, that part flags
    the raised link again (numbered from its own start)."""
    whole = _recording(tmp_path / "whole.nc", 40, 5, bump_link=12, bump=2e-7)
    rc, out, err = run("links", whole, "--speed", SPEED, "--links", 40, "--json")
    assert rc == 0 and [f["link"] for f in json.loads(out)["flagged"]] == [12]
    gapped = _cut(whole, tmp_path / "gapped.nc", 10.0, 16.0)
    rc, out, err = run("links", gapped, "--speed", SPEED, "--links", 40)
    assert rc == 1 and out == "" and len(err.strip().splitlines()) == 1, err
    assert str(gapped) in err and "1 gap(s)" in err and "9.99-16.00 s" in err
    assert "longest part without a gap is 16.00-" in err and "analyse it alone" in err
    t_end = float(xr.open_dataset(whole).time.values[-1])
    # links pass at 3.75 Hz: 16 s is 60 links, so the link raised is 12 - 60 mod 40 = 32 from the part's start
    part = _cut(whole, tmp_path / "part.nc", 0.0, 16.0)
    rc, out, err = run("links", part, "--speed", SPEED, "--links", 40, "--json")
    assert rc == 0, err
    assert [f["link"] for f in json.loads(out)["flagged"]] == [(12 - 1 - 60) % 40 + 1] and t_end > 50


@pytest.mark.parametrize(
    "seconds, words",
    [
        (2.0, ["2.0 s", "covers 0.05 loops of the chain's 159 links", "record at least 86 s"]),
        (5 / FS, ["has 5 samples", "record at least 86 s"]),
    ],
)
def test_a_recording_too_short_says_how_long_to_record(tmp_path, run, seconds, words):
    """A 2 s recording was refused as a wrong speed or nominal pitch; five samples as "Parameter x has 3 samples
    along axis -1": each is one line naming the file, how little it holds and how long to record."""
    src = _recording(tmp_path / "src.nc", 159, 1.2)
    ds = xr.open_dataset(src).load()
    short = tmp_path / "short.nc"
    ds.isel(time=slice(0, int(round(seconds * FS)))).to_netcdf(short)
    rc, out, err = run("links", short, "--escalator", "data/fleet-example/escalators/E07.toml")
    assert rc == 1 and out == "" and len(err.strip().splitlines()) == 1, err
    assert str(short) in err
    for w in words:
        assert w in err, (w, err)
    assert "Parameter" not in err and "nominal" not in err.split("record at least")[0]


@pytest.mark.parametrize("flag", ["--escalator", "--scene"])
def test_an_empty_profile_or_scene_is_refused_by_its_flag(tmp_path, run, flag):
    """`--escalator ''` was ignored silently (the chain then came from --links, no scene)."""
    path = _recording(tmp_path / "e.nc", 40, 2.2)
    rc, out, err = run("links", path, "--speed", SPEED, "--links", 40, flag, "")
    assert rc == 1 and out == "" and len(err.strip().splitlines()) == 1, err
    assert f"{flag} ''" in err and "leave" in err


def test_a_direction_the_profile_contradicts_is_refused(tmp_path, run):
    path = _recording(tmp_path / "e07.nc", 159, 2.2)
    profile = "data/fleet-example/escalators/E07.toml"
    rc, out, err = run("links", path, "--escalator", profile, "--direction", "down")
    assert rc == 1 and out == "" and len(err.strip().splitlines()) == 1, err
    assert "--direction down" in err and "drive.direction = up" in err


def test_a_constant_channel_is_named_with_what_to_check(tmp_path, run):
    """A constant signal was refused as "no vibration channel", without naming it."""
    t = np.arange(0.0, 60.0, 1 / FS)
    path = tmp_path / "flat.nc"
    xr.Dataset({"delta": ("time", np.full(t.size, 0.002), {"units": "m"})}, coords={"time": t}).to_netcdf(path)
    rc, out, err = run("links", path, "--speed", SPEED, "--links", 40)
    assert rc == 1 and out == "" and len(err.strip().splitlines()) == 1, err
    assert str(path) in err and "channel delta is constant (0.002 in every sample)" in err
