"""Recording-vs-simulation comparison: round trip through a file, known pitch mismatch, bursts."""

import numpy as np
import pytest
import xarray as xr

import vibkit
from vibkit.diagnose.comparison import compare

from support.chain import family
from support.recording import recording


@pytest.fixture(scope="module")
def leon_short(tmp_path_factory):
    res = vibkit.simulate("sim/leon.toml", duration=4.0, progress=False)
    path = tmp_path_factory.mktemp("cmp") / "leon.nc"
    from vibkit.io import write_result

    write_result(res, path)
    return res, path


def test_round_trip_perfect_agreement(leon_short):
    res, path = leon_short
    rec = vibkit.read_recording(path)
    c = compare(rec, res)
    assert c.variable == "delta" and c.channel == "delta"
    assert c.score == pytest.approx(1.0, abs=1e-12)
    for h in c.harmonics:
        assert h["frequency_ratio"] == pytest.approx(1.0, abs=1e-12)
        assert h["amplitude_diff_db"] == pytest.approx(0.0, abs=1e-9)
    assert c.log_spectral_distance_db == pytest.approx(0.0, abs=1e-9)
    # the simulation states its chain's pitch; the file's implied pitch is its counted speed over its spectrum's
    # fundamental, which an inverse run's link pass (varying within a loop) moves by 6e-5 from the count
    assert c.pitch_sim_m == pytest.approx(0.4 / 3, rel=1e-12)
    assert c.pitch_consistent and c.pitch_ratio == pytest.approx(1.0, abs=1e-4)


def test_leon_pitch_not_consistent(leon_short):
    res, _ = leon_short
    c = compare(vibkit.read_recording("data/field/leon-tensioner.csv"), res)
    assert c.channel == "tensioner_displacement" and c.variable == "delta"
    # recording: 0.49 / 3.54 = 138.4 mm; scene: 133.3 mm -> ratio 1.038
    assert c.pitch_ratio == pytest.approx(0.1384 / (0.4 / 3), rel=2e-3)
    assert not c.pitch_consistent
    assert c.harmonics[0]["frequency_ratio"] == pytest.approx(3.54 / 3.675, rel=2e-3)
    assert c.harmonics[0]["frequency_mismatch"]
    assert c.score < 0.05
    # no more precise than `vibkit pitch` on the same record: its parts check widens the recorded frequency's sigma
    # (the record's parts scatter beyond their sigmas), and so every ratio's
    from vibkit.diagnose.pitch import estimate_pitch

    est = estimate_pitch(vibkit.read_recording("data/field/leon-tensioner.csv"), speed=0.49, frequency_only=True)
    assert est.parts["widened"]
    assert c.pitch_ratio_sigma / c.pitch_ratio >= est.fundamental_sigma_hz / est.fundamental_hz
    assert any("widened" in n and "parts' scatter" in n for n in c.notes)


def _synthetic(t, f, amps, seg=None, rng=None):
    x = family(t, f, amps, phases=[0.3 * k for k in range(len(amps))])
    if rng is not None:
        x = x + 1e-3 * rng.standard_normal(t.size)
    return recording(
        {"delta": x}, t=t, units="m", var_attrs={"long_name": "d"}, segment=seg, attrs={"chain_speed_m_s": 0.5}
    )


def test_bursts_and_known_amplitude_difference():
    rng = np.random.default_rng(0)
    t_sim = np.arange(4000) / 200.0
    sim = _synthetic(t_sim, 3.75, [1.0, 0.5, 0.25])
    t = np.concatenate([np.arange(2000) / 500.0 + 6.0 * i for i in range(3)])  # three 4 s bursts
    seg = np.repeat(np.arange(3), 2000)
    rec = _synthetic(t, 3.75, [2.0, 0.5, 0.125], seg, rng)  # +6.02 dB, 0 dB, -6.02 dB
    c = compare(rec, sim, n_harmonics=3)
    assert [h["amplitude_diff_db"] for h in c.harmonics] == pytest.approx([6.02, 0.0, -6.02], abs=0.1)
    for h in c.harmonics:
        lo, hi = h["amplitude_diff_db_ci"]
        assert lo <= h["amplitude_diff_db"] <= hi
        assert h["frequency_ratio"] == pytest.approx(1.0, abs=1e-3)
    assert c.pitch_consistent
    # score rule: mean of exp(-(d/3 dB)^2 / 2) over three harmonics
    expect = np.mean([np.exp(-0.5 * (d / 3.0) ** 2) for d in (6.02, 0.0, -6.02)])
    assert c.score == pytest.approx(expect, abs=0.02)


def test_no_matching_variable(leon_short):
    res, _ = leon_short
    t = np.arange(2000) / 200.0
    rec = xr.Dataset({"v": ("time", np.sin(2 * np.pi * 3.7 * t), {"units": "K"})}, coords={"time": t})
    with pytest.raises(ValueError, match="no variable to compare"):
        compare(rec, res)


def test_orders_that_disagree_widen_every_frequency_sigma():
    """One chain gives every harmonic one frequency ratio; a recording whose orders' ratios scatter more
    than their sigmas (here its 2nd and 3rd lines 0.1 % off the multiples) has errors beyond the noise,
    and every ratio's sigma, the pitch ratio's included, grows by the scatter (Birge ratio)."""
    rng = np.random.default_rng(1)
    t = np.arange(8000) / 200.0
    sim = _synthetic(t, 3.75, [1.0, 0.5, 0.25])
    honest = compare(_synthetic(t, 3.75, [1.0, 0.5, 0.25], rng=rng), sim, n_harmonics=3)
    assert not any("scatter" in n for n in honest.notes)
    x = (
        np.cos(2 * np.pi * 3.75 * t)
        + 0.5 * np.cos(2 * np.pi * 7.5 * 1.001 * t)
        + 0.25 * np.cos(2 * np.pi * 11.25 * 0.999 * t)
        + 1e-3 * rng.standard_normal(t.size)
    )
    bent = compare(recording({"delta": x}, t=t, units="m", attrs={"chain_speed_m_s": 0.5}), sim, n_harmonics=3)
    ratios = [h["frequency_ratio"] for h in bent.harmonics]
    assert ratios == pytest.approx([1.0, 1.001, 0.999], abs=2e-4)
    sig = np.array([h["frequency_ratio_sigma"] for h in bent.harmonics])
    mean = np.average(ratios, weights=1 / sig**2)
    # after widening the orders agree with one ratio within their sigmas (chi^2 / dof = 1)
    assert np.sum(((np.array(ratios) - mean) / sig) ** 2) / 2 == pytest.approx(1.0, rel=1e-9)
    assert any("scatter" in n for n in bent.notes)
    assert bent.pitch_ratio_sigma > 20 * honest.pitch_ratio_sigma
    assert abs(bent.pitch_ratio - 1) < 3 * bent.pitch_ratio_sigma


def test_a_kinematics_scene_is_named_not_its_outputs():
    """A stranger compared a recording with a kinematics scene and was told to add delta to its outputs, which
    it had: the scene has no time axis, and the error says so."""
    rec = vibkit.read_recording("data/field/leon-tensioner.csv")
    kin = vibkit.simulate("sim/thesis-kinematics.toml", progress=False)
    with pytest.raises(ValueError, match="no time axis: a kinematics scene"):
        compare(rec, kin)


def test_a_coasting_simulation_compared_with_itself_reads_its_own_pitch():
    """A stranger's escalator (0.65 m/s, 101.6 mm, 23 teeth, 35 deg, 4 m rise) from its profile with no running
    resistance (``no_load_power = 0``; a profile's scene is driven by default): the chain coasts and
    drifts within the teeth's backlash, its link pass wandering by a few hundredths of a per cent. Compared with
    itself it read a pitch ratio 1.0004132 +- 0.0000058 (71 sigma): the recording's link pass was the spectrum's
    fit, which weights the record unevenly, against the counted speed. It is now read as `vibkit pitch` reads it
    (the mean phase where the frequency wanders), and the simulation's pitch is its chain's own."""
    from vibkit.model.profile import parse_profile

    prof = parse_profile(
        '[escalator]\nunit = "B1"\n[drive]\nspeed = 0.65\nteeth = 23\nno_load_power = 0\n[chain]\n'
        "nominal_pitch = 0.1016\nlinks_per_step = 4\n[geometry]\nrise = 4.0\nincline_deg = 35.0\n"
    )
    ds = vibkit.simulate(prof.scene("forward"), progress=False)
    c = compare(ds, ds, channel="tensioner_displacement")
    assert c.pitch_sim_m == pytest.approx(0.1016, rel=1e-12)  # the chain's own pitch
    assert abs(c.pitch_ratio - 1) < 1e-5 and abs(c.pitch_ratio - 1) <= 3 * c.pitch_ratio_sigma
    assert c.link_pass_meas_hz == pytest.approx(ds.attrs["link_pass_frequency_hz"], rel=1e-5)
    assert c.pitch_consistent is True


def test_a_comparison_plots_the_order_spectra_it_holds(leon_short):
    """`Comparison.plot()` draws the two order spectra at the amplitudes the result holds (in the unit the axis names,
    um or mm as the report's tables give a tensioner's lengths), the amplitude spectra and the spectrograms."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    res, path = leon_short
    c = compare(vibkit.read_recording(path), res)
    fig = c.plot()
    try:
        ax = fig.axes[0]
        sim, meas = ax.get_lines()[:2]
        np.testing.assert_allclose(sim.get_xdata(), c.orders)
        scale = {"amplitude [\u00b5m]": 1e6, "amplitude [mm]": 1e3, "amplitude [m]": 1.0}[ax.get_ylabel()]
        np.testing.assert_allclose(meas.get_ydata(), np.maximum(scale * c.order_amplitude_meas, 1e-30), rtol=1e-12)
        np.testing.assert_allclose(sim.get_ydata(), np.maximum(scale * c.order_amplitude_sim, 1e-30), rtol=1e-12)
        assert len([a for a in fig.axes if a.get_label() != "<colorbar>"]) == 5
    finally:
        plt.close(fig)
