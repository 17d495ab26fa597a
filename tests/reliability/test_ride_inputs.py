"""Ride weightings map one to one onto axes or are refused; ride errors name the file."""

import pytest

from vibkit.diagnose.ride import DEFAULT_WEIGHTINGS, parse_weightings, ride_quality_from_recording


def test_weighting_lists_map_one_to_one():
    assert parse_weightings(None) is None and parse_weightings(" ") is None
    assert parse_weightings("Wk") == {k: "Wk" for k in DEFAULT_WEIGHTINGS}
    assert parse_weightings("Wd,Wd,Wk") == {"x": "Wd", "y": "Wd", "z": "Wk"}
    assert parse_weightings("Wb, Wc, Wd") == {"x": "Wb", "y": "Wc", "z": "Wd"}
    assert parse_weightings("z=Wk,x=Wd") == {"z": "Wk", "x": "Wd"}
    assert parse_weightings("X=wd") == {"x": "Wd"}  # names as ISO writes them, whatever the case given
    for bad, match in (
        ("Wb,Wc", "2 weightings"),
        ("Wd,Wd,Wk,Wk", "4 weightings"),
        ("x=Wd,x=Wk", "given twice"),
        ("x=Wd,Wk", "mix"),
        ("w=Wd", "axis 'w'"),
        ("Wq", "unknown weighting 'Wq'"),
        ("Wd,,Wk", "empty entry"),
    ):
        with pytest.raises(ValueError, match=match):
            parse_weightings(bad)


def test_each_axis_gets_its_weighting_and_errors_name_the_file(tmp_path):
    import numpy as np

    t = np.arange(0.0, 12.0, 1 / 200.0)
    x = 0.3 * np.sin(2 * np.pi * 5.0 * t)
    p = tmp_path / "step.csv"
    p.write_text(
        "time [s],ax [m/s^2],ay [m/s^2],az [m/s^2]\n"
        + "\n".join(f"{a:.6f},{b:.6g},{b:.6g},{b + 9.81:.6g}" for a, b in zip(t, x))
        + "\n"
    )
    rq = ride_quality_from_recording(p, segment=(2.0, 10.0), weightings=parse_weightings("Wd,Wd,Wk"))
    assert {a.axis: a.weighting for a in rq.axes} == {"x": "Wd", "y": "Wd", "z": "Wk"}
    # the same 5 Hz sine on every axis: the weighted r.m.s. scale as the ISO 2631-1 magnitudes |Wk| / |Wd| at 5 Hz
    from vibkit.signal.weighting import frequency_weighting_response

    by = {a.axis: a.weighted.rms for a in rq.axes}
    ratio = abs(frequency_weighting_response([5.0], "Wk")[0]) / abs(frequency_weighting_response([5.0], "Wd")[0])
    assert by["x"] == pytest.approx(by["y"], rel=1e-12)
    assert by["z"] / by["x"] == pytest.approx(ratio, rel=0.02) and ratio > 2
    with pytest.raises(ValueError, match=rf"^{p}: segment 20:30 s is not inside step.csv, which spans 0-12 s"):
        ride_quality_from_recording(p, segment=(20.0, 30.0))
