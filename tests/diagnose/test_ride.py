"""Ride quality of recordings and simulations through one path; the ``vibkit ride`` command."""

import json
import math
from pathlib import Path

import numpy as np
import pytest
import xarray as xr

from vibkit.cli import main
from vibkit.diagnose.ride import (
    parse_channels,
    parse_segment,
    ride_quality_from_recording,
    ride_quality_from_simulation,
)
from vibkit.signal import frequency_weighting_response

from ..signal.test_signal_ride import synthetic_ride
from support.recording import recording

SIM = Path(__file__).resolve().parents[2] / "sim"
FS = 500.0
AMP_Z, F_Z = 0.08, 6.3
AMP_X, F_X = 0.05, 2.0


def _ride_arrays(fs=FS):
    ax, az, start, end = synthetic_ride(fs, noise=0.0)
    t = np.arange(az.size) / fs
    ax = ax + AMP_X * np.sin(2 * np.pi * F_X * t)
    az = az + AMP_Z * np.sin(2 * np.pi * F_Z * t)
    ay = 0.01 * np.sin(2 * np.pi * 3.1 * t)
    return t, ax, ay, az, start, end


@pytest.fixture(scope="module")
def ride_csv(tmp_path_factory):
    t, ax, ay, az, start, end = _ride_arrays()
    p = tmp_path_factory.mktemp("ride") / "step-ride.csv"
    with open(p, "w") as fh:
        fh.write("# synthetic step ride for tests\ntime (s),ax (m/s^2),ay (m/s^2),az (m/s^2),speed (m/s)\n")
        for row in zip(t, ax, ay, az, np.full(t.size, 0.5)):
            fh.write(",".join(f"{v:.7f}" for v in row) + "\n")
    return p, start, end


def test_recording_ride_quality_has_the_known_values(ride_csv):
    path, start, end = ride_csv
    rq = ride_quality_from_recording(path)
    assert [a.axis for a in rq.axes] == ["x", "y", "z"] and rq.axis("z").channel == "az"
    assert rq.segment.start_s == pytest.approx(start, abs=0.2) and rq.segment.end_s == pytest.approx(end, abs=0.2)
    # the known values on the straight incline (the detected segment reaches into the transition arcs,
    # whose abrupt curvature steps ring through the weightings and add 2-3 % to A95 here)
    rq = ride_quality_from_recording(path, segment=(9.0, 17.0))
    z, x = rq.axis("z"), rq.axis("x")
    assert z.weighted.a95 == pytest.approx(2 * AMP_Z * abs(frequency_weighting_response(F_Z, "Wk")), rel=0.02)
    assert x.weighted.a95 == pytest.approx(2 * AMP_X * abs(frequency_weighting_response(F_X, "Wd")), rel=0.03)
    assert z.weighted.rms == pytest.approx(
        AMP_Z * abs(frequency_weighting_response(F_Z, "Wk")) / math.sqrt(2), rel=0.03
    )
    assert rq.speed_m_s == pytest.approx(0.5)


def test_simulation_dataset_goes_through_the_same_path():
    # a Dataset shaped like vibkit.simulate's output with the step roller's motion (x, z world axes)
    t, ax, ay, az, start, end = _ride_arrays()
    vz = np.cumsum(az - 9.80665 - 0.003) / FS  # synthetic_ride adds a 0.003 m/s^2 sensor offset
    acc = np.stack([ax, az - 9.80665], axis=-1)[:, None, :]  # kinematic acceleration (no gravity)
    vel = np.stack([np.full(t.size, 0.5), vz], axis=-1)[:, None, :]
    ds = xr.Dataset(
        {
            "roller_acceleration": (("time", "roller", "axis"), acc),
            "roller_velocity": (("time", "roller", "axis"), vel),
        },
        coords={"time": t, "roller": [8], "axis": ["x", "z"]},
        attrs={"step_accelerometer": 3, "scene_name": "synthetic"},
    )
    sim = ride_quality_from_simulation(ds)
    rec = ride_quality_from_recording(_dataset_recording(t, ax, ay, az))
    assert sim.kind == "simulation" and sim.segment.method == "speed channel"
    assert sim.segment.start_s == pytest.approx(start, abs=0.05) and sim.segment.end_s == pytest.approx(end, abs=0.05)
    for axis in ("x", "z"):
        assert sim.axis(axis).weighted.a95 == pytest.approx(rec.axis(axis).weighted.a95, rel=0.01)
    # accel_step alone: one tangential axis over the whole record
    ds2 = xr.Dataset({"accel_step": ("time", ax)}, coords={"time": t})
    one = ride_quality_from_simulation(ds2)
    assert [a.axis for a in one.axes] == [
        "tangential"
    ] and one.segment.method == "whole simulated time"  # nobody gave it
    with pytest.raises(ValueError, match="neither"):
        ride_quality_from_simulation(xr.Dataset({"delta": ("time", ax)}, coords={"time": t}))


def test_simulated_step_rides_the_incline_not_a_head():
    # the step goes round the sprocket, down the return run and round the lower head before it rides up the
    # incline (from about 31 s): round a head it rises at up to the chain's speed, up the incline at v sin(30 deg)
    import vibkit
    from vibkit.diagnose.ride_simulation import with_ride_outputs
    from vibkit.model.scene import load_scene

    scene = with_ride_outputs(load_scene(SIM / "thesis-forward.toml"))
    ds = vibkit.simulate(scene, duration=44.0, progress=False)
    rq = ride_quality_from_simulation(ds)
    assert rq.segment.plateau == pytest.approx(0.5 * math.sin(math.radians(30.0)), rel=0.01)
    assert 30.0 < rq.segment.start_s < rq.segment.end_s < 44.0 and rq.segment.duration_s > 10.0
    # 30 s reach only the lower head: no ride, said so (it used to measure the turn round the head)
    with pytest.raises(ValueError, match="does not ride up the incline"):
        ride_quality_from_simulation(ds.sel(time=slice(0.0, 30.0)))


def test_simulate_ride_runs_on_to_the_incline_when_the_scene_ends_before_it():
    # 30 s of the no-load scene end before step 20 reaches the incline (about 31-43 s): without a duration
    # the scene is simulated again one loop longer (159 x 0.1333 m / 0.5 m/s = 42.4 s), and the notes say so
    from vibkit.diagnose.ride_simulation import simulate_ride
    from vibkit.model.scene import load_scene, parse_scene

    shipped = load_scene(SIM / "thesis-forward.toml")
    scene = parse_scene(shipped.text.replace("duration = 44.0", "duration = 30.0"), shipped.source)
    rq = simulate_ride(scene)
    assert rq.segment.plateau == pytest.approx(0.5 * math.sin(math.radians(30.0)), rel=0.01)
    assert 30.0 < rq.segment.start_s and rq.segment.duration_s > 10.0
    assert rq.time[-1] == pytest.approx(73.0, abs=0.01)  # ceil(30 + 42.4)
    assert any("simulated 73 s: in the scene's 30 s step 20 does not ride up the incline" in n for n in rq.notes)
    # a duration given is kept: no incline in it is an error that says what to do
    with pytest.raises(ValueError, match="does not ride up the incline.*--duration"):
        simulate_ride(scene, duration=30.0)


def test_a_down_escalator_rides_down_the_incline():
    """A scene run at a negative speed (a profile's drive.direction = "down"): its step's ride is the descent of the
    incline at v sin(alpha), not the return strand's rise under the steps, and the note says down."""
    from vibkit.diagnose.ride_simulation import simulate_ride
    from vibkit.model.scene import load_scene, parse_scene

    shipped = load_scene(SIM / "thesis-forward.toml")
    text = shipped.text.replace("speed = 0.5 }", "speed = -0.5 }").replace("duration = 44.0", "duration = 60.0")
    assert text != shipped.text
    rq = simulate_ride(parse_scene(text, shipped.source))
    assert rq.segment.plateau == pytest.approx(-0.5 * math.sin(math.radians(30.0)), rel=0.01)
    assert rq.segment.duration_s > 10.0
    assert "(down the incline)" in rq.segment.note, rq.segment.note


def _dataset_recording(t, ax, ay, az):
    channels = {"ax": ax, "ay": ay, "az": az}
    attrs = {"source_file": "synthetic"}
    return recording(channels, t=t, var_attrs={"quantity": "acceleration"}, time_units=None, attrs=attrs)


def test_parsers():
    assert parse_channels("ax,-,az") == {"x": "ax", "z": "az"}
    assert parse_channels("z=acc") == {"z": "acc"}
    assert parse_segment("2.5:14") == (2.5, 14.0)
    for bad in ("a,b,c,d", "q=acc", "x=a,b"):
        with pytest.raises(ValueError, match="channels"):
            parse_channels(bad)
    for bad in ("3", "5:2", "a:b"):
        with pytest.raises(ValueError, match="segment"):
            parse_segment(bad)


def test_cli_ride_json(ride_csv, capsys):
    path, start, end = ride_csv
    assert main(["ride", str(path), "--json"]) == 0
    d = json.loads(capsys.readouterr().out)
    assert d["schema"] == "vibkit.ride/1" and d["kind"] == "recording"
    z = [a for a in d["axes"] if a["axis"] == "z"][0]
    assert z["weighting"] == "Wk" and z["units"] == "m/s^2"
    assert z["weighted"]["a95"] == pytest.approx(2 * AMP_Z * abs(frequency_weighting_response(F_Z, "Wk")), rel=0.04)
    assert d["segment"]["start_s"] == pytest.approx(start, abs=0.2)


def test_cli_ride_options_and_table(ride_csv, capsys):
    path, _, _ = ride_csv
    assert main(["ride", str(path), "--segment", "12:20", "--channels=-,-,az", "--weighting", "z=Wb"]) == 0
    out = capsys.readouterr().out
    assert "12.00-20.00 s" in out and "Wb" in out and "\nz     az" in out and "\nx " not in out


@pytest.mark.parametrize(
    "args,msg,code",
    [
        (["--weighting", "Wq"], "unknown weighting 'Wq'", 2),  # usage errors: what the options say alone
        (["--weighting", "Wb,Wc"], "2 weightings for the three axes", 2),
        (["--channels", "nope,-,-"], "channel 'nope'", 1),  # the file's: bad data
        (["--segment", "9:3"], "segment", 2),
        (["--segment", "900:1000"], "spans 0-", 1),  # outside the recording: its span named, never cut
        (["--channels", "speed,-,-"], "not an acceleration", 1),
    ],
)
def test_cli_ride_bad_input_is_one_line(ride_csv, capsys, args, msg, code):
    path, _, _ = ride_csv
    if code == 2:  # argparse's usage error
        with pytest.raises(SystemExit) as exc:
            main(["ride", str(path)] + args)
        assert exc.value.code == 2
    else:
        assert main(["ride", str(path)] + args) == code
    err = capsys.readouterr().err
    assert msg in err and "Traceback" not in err and err.count("\n") == 1


def test_cli_ride_needs_axes_or_a_file(capsys, tmp_path):
    assert main(["ride", "data/field/las-palmas-accelerometer.csv"]) == 1
    assert "--channels" in capsys.readouterr().err
    assert main(["ride", str(tmp_path / "missing.csv")]) == 1
    assert main(["ride", "sim/leon.toml"]) == 1
    assert "step_accelerometer" in capsys.readouterr().err


def test_cli_ride_of_a_scene_simulates_it(capsys):
    assert main(["ride", "sim/las-palmas.toml", "--duration", "3", "--json"]) == 0
    d = json.loads(capsys.readouterr().out)
    assert d["kind"] == "simulation" and [a["axis"] for a in d["axes"]] == ["x", "z"]
    assert d["segment"]["method"] == "speed channel"
    assert all(math.isfinite(a["weighted"]["a95"]) and a["weighted"]["a95"] > 0 for a in d["axes"])


@pytest.mark.slow
def test_report_has_a_ride_quality_page(ride_csv, tmp_path):
    from vibkit.diagnose.report import write_report

    path, _, _ = ride_csv
    # a short spike window keeps the report's Hampel calibration quick (it is not what is tested here)
    rep = write_report(path, tmp_path / "ride.pdf", channel="az", hampel_half_window_s=0.01)
    titles = [t for t, _ in rep.pages]
    assert "ride quality (recording)" in titles and "ride quality (simulation)" not in titles
    text = "\n".join(dict(rep.pages)["ride quality (recording)"])
    rq = ride_quality_from_recording(path)
    assert "A95" in text and "10 Hz A95" in text and "time [s] (shaded: ride segment)" in text
    assert f"{rq.axis('z').weighted.a95:.3g}" in text and "Wk" in text  # to three digits


def test_cli_ride_recording_with_a_scene_beside_it(ride_csv, capsys):
    path, _, _ = ride_csv
    assert main(["ride", str(path), "--scene", "sim/las-palmas.toml", "--duration", "3", "--json"]) == 0
    d = json.loads(capsys.readouterr().out)
    assert d["kind"] == "recording" and d["simulation"]["kind"] == "simulation"
    assert d["simulation"]["source"] == "sim/las-palmas.toml"
    assert main(["ride", "sim/las-palmas.toml", "--scene", "sim/las-palmas.toml"]) == 1
    assert "already a scene" in capsys.readouterr().err


def test_a_constant_axis_gives_nan_and_a_note_not_an_error():
    from vibkit.diagnose.ride import ride_quality

    t = np.arange(0, 20, 1 / FS)
    rq = ride_quality({"y": np.zeros(t.size), "z": 9.8 + 0.1 * np.sin(2 * np.pi * 5 * t)}, FS, segment=(4, 18))
    assert math.isnan(rq.axis("y").weighted.a95) and rq.axis("y").weighted.n_values == 0
    assert rq.axis("z").weighted.a95 > 0 and any("axis y" in n for n in rq.notes)


def test_a_vibkit_result_file_takes_the_simulation_path(tmp_path, capsys):
    t = np.arange(0, 10, 1 / 400.0)
    ds = xr.Dataset(
        {"accel_step": ("time", 0.05 * np.sin(2 * np.pi * 3.9 * t), {"units": "m/s^2"})},
        coords={"time": ("time", t, {"units": "s"})},
        attrs={"analysis": "forward", "scene_name": "x"},
    )
    rq = ride_quality_from_recording(ds)
    assert rq.kind == "simulation" and rq.axes[0].axis == "tangential"
    assert rq.axes[0].lowpass.a95 == pytest.approx(
        0.1 * abs(1 / math.sqrt(1 + (3.9 / 10) ** 8)) / math.sqrt(1 + (0.4 / 3.9) ** 4), rel=0.01
    )


def test_a_segment_in_the_filters_settling_gets_advice_for_its_kind():
    """A ride segment that starts within the weighting's settling time: a recording is told to start earlier, a
    simulation (which cannot be recorded earlier) to move its segment or its step."""
    from vibkit.diagnose.ride import ride_quality

    t = np.arange(0, 20, 1 / FS)
    signals = {"z": 9.8 + 0.1 * np.sin(2 * np.pi * 5 * t)}
    rec = ride_quality(signals, FS, segment=(0.5, 18))
    sim = ride_quality(signals, FS, segment=(0.5, 18), kind="simulation")
    assert any("record at least 2 s before the ride" in n for n in rec.notes), rec.notes
    assert any("--segment" in n and "[run] start" in n for n in sim.notes), sim.notes
    assert not any("record at least" in n for n in sim.notes)


def test_the_ride_of_a_four_link_step_is_its_middle_roller():
    """A step of 4 links carries rollers 4 (s - 1) + 1 ... 4 s: its middle roller (the second) is 4 (s - 1) + 2,
    not the 3-link step's 3 s - 1 (a stranger's 4-link escalator rode "roller 8 of step 3", a roller of step 2)."""
    import dataclasses

    from vibkit.diagnose.ride_simulation import with_ride_outputs
    from vibkit.model.scene import load_scene

    scene = load_scene(SIM / "thesis-forward.toml")
    four = dataclasses.replace(scene, chain=dataclasses.replace(scene.chain, links_per_step=4, n_rollers=160))
    assert (
        10
        in with_ride_outputs(dataclasses.replace(four, outputs={**four.outputs, "step_accelerometer": 3})).outputs[
            "rollers"
        ]
    )
    assert (
        8
        in with_ride_outputs(dataclasses.replace(scene, outputs={**scene.outputs, "step_accelerometer": 3})).outputs[
            "rollers"
        ]
    )


def test_a_segment_of_a_few_half_cycles_is_said_to_give_no_ride_statistics():
    """Five peak-to-peak values are no ride's A95 (a stranger's 2 s phone 'ride' read max pk-pk under its r.m.s.):
    a note says so; a ride of hundreds gets none."""
    from vibkit.diagnose.ride import MIN_PK_PK_VALUES, ride_quality

    t = np.arange(0, 20, 1 / FS)
    z = 9.8 + 0.1 * np.sin(2 * np.pi * 1.5 * t)
    short = ride_quality({"z": z}, FS, segment=(4.0, 6.0))
    assert any("in the segment: its maximum and A95 are not a ride's" in n for n in short.notes)
    assert short.axis("z").weighted.n_values < MIN_PK_PK_VALUES
    long = ride_quality({"z": 9.8 + 0.1 * np.sin(2 * np.pi * 5 * t)}, FS, segment=(4.0, 18.0))
    assert not any("not a ride's" in n for n in long.notes)


def test_a_run_from_rest_is_a_ride_only_once_its_step_runs_at_speed():
    """A stranger's scene started from rest with its step on the incline: the drive's start-up (0 to 0.45 m/s)
    was read as ride vibration. The ride of a run from rest starts once the step runs at 98 % of the chain's
    counted speed; a run at speed from its start is not cut."""
    from vibkit.diagnose.ride import START_UP_SHARE, _start_up

    t = np.arange(0, 5, 0.005)
    ramp = 0.45 * np.minimum(1.0, t / 2.0)  # 0 to 0.45 m/s in 2 s
    cut = _start_up(ramp, 0.45)
    assert t[cut] == pytest.approx(2.0 * START_UP_SHARE, abs=0.006)
    assert _start_up(np.full(t.size, 0.45), 0.45) == 0  # at speed from the start
    assert _start_up(ramp, 0.0) == 0  # no speed known: nothing cut
