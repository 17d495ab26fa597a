"""One run's chain settings, resolved once: the same recording and profile give every command the same numbers."""

from __future__ import annotations

import types
from pathlib import Path

import numpy as np
import pytest

import vibkit.diagnose.channels
import vibkit.diagnose.report.context
import vibkit.fleet.measurement
from vibkit.cli import main
from vibkit.diagnose.settings import DEFAULT_LINKS_PER_STEP, DEFAULT_TEETH, chain_numbers, recording_chain

from support.recording import recording

RECORDING = Path(__file__).resolve().parents[2] / "data" / "fleet-example" / "E07" / "2026-11-23.csv"
#: E07's profile with a sprocket and steps of its own (not the defaults 28 and 3, so that a default shows)
PROFILE = """[escalator]
unit = "E07"
[drive]
speed = 0.5
speed_uncertainty = 0.0005
teeth = 23
[chain]
nominal_pitch = 0.13333
links_per_step = 4
n_links = 159
[sensor]
kind = "step"
step = 3
"""


def test_the_chain_numbers_are_taken_in_one_order():
    """Given, else the profile's, else the scene's, else the recording's, else the defaults."""
    profile = types.SimpleNamespace(teeth=23, links_per_step=4)
    scene = types.SimpleNamespace(
        sprocket=types.SimpleNamespace(teeth=25), chain=types.SimpleNamespace(links_per_step=3)
    )
    rec = recording({"az": np.zeros(4)}, 10.0, attrs={"sprocket_teeth": 31, "links_per_step": 4})
    assert chain_numbers() == (DEFAULT_TEETH, DEFAULT_LINKS_PER_STEP) == (28, 3)
    assert chain_numbers(recording=rec) == (31, 4) == recording_chain(rec)
    assert chain_numbers(scene=scene, recording=rec) == (25, 3)
    assert chain_numbers(profile=profile, scene=scene, recording=rec) == (23, 4)
    assert chain_numbers(teeth=19, links_per_step=3, profile=profile, scene=scene, recording=rec) == (19, 3)
    bad = recording({"az": np.zeros(4)}, 10.0, attrs={"sprocket_teeth": "many", "links_per_step": 0})
    assert recording_chain(bad) == (None, None) and chain_numbers(recording=bad) == (28, 3)


class _Resolved(Exception):
    """Raised by the spy once it has what the analysis was given: the command goes no further."""


@pytest.fixture
def spy(monkeypatch):
    """The keywords each entry point gives the per-channel estimate (where its settings end up)."""
    seen = {}

    def install(module, name):
        def fake(rec, **kw):
            seen[name] = kw
            raise _Resolved

        monkeypatch.setattr(module, "estimate_channels", fake)

    install(vibkit.diagnose.channels, "pitch")  # `pitch` and `spectrum` import it when they run
    install(vibkit.fleet.measurement, "fleet add")
    install(vibkit.diagnose.report.context, "report")
    return seen


def test_pitch_spectrum_report_and_fleet_add_resolve_the_same_settings(spy, tmp_path):
    profile = tmp_path / "e07.toml"
    profile.write_text(PROFILE)
    runs = {
        "pitch": ["pitch", RECORDING, "--escalator", profile],
        "spectrum": ["spectrum", RECORDING, "--escalator", profile],
        "report": ["report", RECORDING, "--escalator", profile, "-o", tmp_path / "r.pdf"],
        "fleet add": ["fleet", "add", RECORDING, "--escalator", profile, "--db", tmp_path / "f.db"],
    }
    got = {}
    for name, argv in runs.items():
        with pytest.raises(_Resolved):
            main([str(a) for a in argv])
        got[name] = dict(spy.pop("pitch" if name == "spectrum" else name))
    keys = ("speed", "speed_sigma", "nominal_pitch", "teeth", "links_per_step", "n_links")
    want = {"speed": 0.5, "speed_sigma": 0.0005, "nominal_pitch": 0.13333, "teeth": 23, "links_per_step": 4}
    want["n_links"] = 159
    for name, kw in got.items():
        assert {k: kw.get(k) for k in keys} == pytest.approx(want), name


@pytest.fixture
def settings_spy(monkeypatch):
    """The :class:`RunSettings` each command resolves for its recording (the command goes no further once it has
    them)."""
    import vibkit.diagnose.comparison
    import vibkit.diagnose.settings

    real = vibkit.diagnose.settings.resolve_settings
    seen = []

    def spy(recording=None, **kwargs):
        settings = real(recording, **kwargs)
        if recording is None:  # `fleet add` resolves its speed before it reads the file: not yet the run's
            return settings
        seen.append(settings)
        raise _Resolved

    # the CLI's run_settings imports it where it runs; the library's entry points at their top
    for module in (vibkit.diagnose.settings, vibkit.fleet.measurement, vibkit.diagnose.report.context):
        monkeypatch.setattr(module, "resolve_settings", spy)
    monkeypatch.setattr(vibkit.diagnose.comparison, "resolve_settings", spy)
    return seen


def test_every_command_resolves_the_same_settings_from_one_recording_and_profile(settings_spy, tmp_path):
    """``pitch``, ``spectrum``, ``links``, ``compare``, ``report`` and ``fleet add`` given the same recording,
    profile and segment: the same speed and sigma, nominal pitch, teeth, links per step, links, band, limits, sensor
    of each channel and segment (where each came from may differ in words: ``fleet add`` hands its speed on)."""
    profile = tmp_path / "e07.toml"
    profile.write_text(PROFILE.replace('kind = "step"\nstep = 3\n', 'kind = "phone"\n'))
    common = [RECORDING, "--escalator", profile, "--segment", "1:9"]
    runs = {
        "pitch": ["pitch", *common],
        "spectrum": ["spectrum", *common],
        "links": ["links", *common],
        "compare": ["compare", *common],
        "report": ["report", *common, "-o", tmp_path / "r.pdf"],
        "fleet add": ["fleet", "add", *common, "--db", tmp_path / "f.db"],
    }
    got = {}
    for name, argv in runs.items():
        with pytest.raises(_Resolved):
            main([str(a) for a in argv])
        got[name] = settings_spy.pop(0).as_dict()
        assert not settings_spy
    values = ("speed_m_s", "speed_sigma_m_s", "nominal_pitch_m", "teeth", "links_per_step", "n_links")
    want = {"speed_m_s": 0.5, "speed_sigma_m_s": 0.0005, "nominal_pitch_m": 0.13333, "teeth": 23}
    want.update(links_per_step=4, n_links=159)
    for name, d in got.items():
        assert {k: d[k] for k in values} == pytest.approx(want), name
        # the profile's band: 0.8 to 1.25 times its link pass, speed / nominal pitch
        assert d["band_hz"] == pytest.approx([0.8 * 0.5 / 0.13333, 1.25 * 0.5 / 0.13333], rel=1e-12), name
        assert d["limits_percent"] == [1.5, 2.0, 3.0], name
        assert d["sensors"] == {"accel": "phone"}, name
        assert d["segment_s"] == [1.0, 9.0], name
