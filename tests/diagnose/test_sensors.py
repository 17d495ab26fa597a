"""A channel's sensor is data: the profile's per-channel entries, else the reader's quantity, else the profile's one
[sensor]; each channel's warnings are true of that channel (a unit with a tensioner LVDT and a phone on a step)."""

from __future__ import annotations

import numpy as np
import pytest

from vibkit.diagnose.channels import estimate_channels
from vibkit.diagnose.links import find_worn_links, links_channel
from vibkit.diagnose.pitch import STEP_WARNING
from vibkit.diagnose.sensors import channel_quantity, channel_sensor
from vibkit.diagnose.settings import resolve_settings
from vibkit.model.profile import parse_profile

from support.recording import recording

F0 = 3.75  # link pass of a 133.33 mm chain at 0.5 m/s [Hz]
FS = 200.0
BASE = """[escalator]
unit = "E31"
[drive]
speed = 0.5
speed_uncertainty = 0.0005
[chain]
nominal_pitch = 0.13333
n_links = 160
"""
#: the unit of the issue: a tensioner LVDT (a displacement) and a phone lying on a step
BOTH = BASE + '[sensor]\nkind = "phone"\n[sensors.lvdt]\nkind = "tensioner"\n'


def _family(t, f0, amp=1.0):
    """A link-pass family: the fundamental and two harmonics, with a little noise (seeded)."""
    rng = np.random.default_rng(3)
    x = sum(amp / k * np.sin(2 * np.pi * k * f0 * t + k) for k in (1, 2, 3))
    return x + 0.01 * amp * rng.standard_normal(t.size)


def _unit_recording():
    """An LVDT in metres (the reader's quantity: displacement) and a phone's axis in m/s^2, both built here."""
    t = np.arange(int(40 * FS)) / FS
    rec = recording({"lvdt": 1e-4 * _family(t, F0), "az": _family(t, F0)}, FS)
    rec["lvdt"].attrs.update(units="m", quantity="displacement")
    rec["az"].attrs.update(units="m/s^2", quantity="acceleration")
    return rec


def test_the_sensor_of_a_channel_is_taken_in_one_order():
    rec = _unit_recording()
    both = parse_profile(BOTH)
    # the profile's own entry first
    s = channel_sensor(rec, "lvdt", both)
    assert (s.kind, s.is_tensioner, s.rides_step, s.signature) == ("tensioner", True, False, "delta")
    # no entry: the reader's quantity (a displacement is the tensioner's) before the profile's [sensor]
    only_default = parse_profile(BASE + '[sensor]\nkind = "step"\nstep = 3\n')
    s = channel_sensor(rec, "lvdt", only_default)
    assert (s.kind, s.rides_step) == ("tensioner", False)
    # an acceleration: the profile's [sensor], the default of the channels it does not name
    s = channel_sensor(rec, "az", both)
    assert (s.kind, s.rides_step, s.is_tensioner, s.signature) == ("phone", True, False, None)
    # nothing stated: not a step, not the tensioner
    s = channel_sensor(rec, "az")
    assert (s.kind, s.rides_step, s.is_tensioner) == ("unknown", False, False)
    # an entry overrides the quantity: a displacement channel the profile puts on a step rides it
    on_step = parse_profile(BASE + '[sensors.lvdt]\nkind = "step"\nstep = 2\n')
    s = channel_sensor(rec, "lvdt", on_step)
    assert (s.kind, s.step, s.rides_step, s.is_tensioner) == ("step", 2, True, False)


def test_the_quantity_is_the_readers_never_the_spelling_of_a_unit():
    """The reader's ``quantity`` decides; a recording made without a reader (only ``units``) is read through the io
    layer's unit table, which knows every spelling of a length (cm, in) and none that is not one."""
    t = np.arange(10) / FS
    rec = recording({"a": t, "b": t, "c": t, "d": t}, FS)
    rec["a"].attrs.update(units="counts", quantity="displacement")  # the reader said so
    rec["b"].attrs.update(units="cm")
    rec["c"].attrs.update(units="mm/s^2")
    rec["d"].attrs.update(units="counts")
    assert [channel_quantity(rec, c) for c in "abcd"] == ["displacement", "displacement", "acceleration", "other"]


def test_each_channels_warning_is_its_own():
    """A unit with a tensioner LVDT and a phone.  The phone's estimate warns that a step's link pass reads off
    the chain's; the LVDT's does not (before, one [sensor] said "step" of every channel)."""
    rec = _unit_recording()
    settings = resolve_settings(rec, profile=parse_profile(BOTH))
    assert {s.channel: s.kind for s in settings.sensors} == {"lvdt": "tensioner", "az": "phone"}
    kw = dict(
        speed=settings.speed.value,
        speed_sigma=settings.speed.sigma,
        nominal_pitch=settings.nominal_pitch,
        band=settings.band,
        sensors=settings.sensors_by_channel,
    )
    res = estimate_channels(rec, **kw)
    by = {e.channel: e for e in res.estimates}
    assert set(by) == {"lvdt", "az"}
    assert all(e.fundamental_hz == pytest.approx(F0, rel=1e-3) for e in by.values())
    assert STEP_WARNING in by["az"].warnings
    assert STEP_WARNING not in by["lvdt"].warnings
    # one channel asked for: its own sensor too
    one = estimate_channels(rec, channel="lvdt", **kw)
    assert STEP_WARNING not in one.best.warnings


def test_the_worn_link_map_reads_the_channel_the_profile_names_the_tensioner():
    """The link map takes the tensioner's channel from the sensors: a per-channel entry names it even where its
    unit is not a length (a logger writing the LVDT in raw counts), and a channel the profile puts on a step is
    refused as a step accelerometer is."""
    t = np.arange(int(40 * FS)) / FS
    rec = recording({"az": _family(t, F0), "raw": _family(t, F0)}, FS)
    rec["raw"].attrs.update(units="counts", quantity="other")
    assert links_channel(rec) == "az"  # nothing says which is the tensioner: the first vibration channel
    prof = parse_profile(BASE + '[sensors.raw]\nkind = "tensioner"\n')
    assert links_channel(rec, profile=prof) == "raw"
    on_step = parse_profile(BASE + '[sensors.raw]\nkind = "step"\nstep = 1\n')
    with pytest.raises(ValueError, match="step accelerometer gives no link number"):
        find_worn_links(rec, speed=0.5, n_links=160, channel="raw", profile=on_step)


def test_no_diagnosis_guesses_a_sensor_from_the_spelling_of_a_unit():
    """The sensor of a channel is :mod:`vibkit.diagnose.sensors`' to say: no other module of the diagnoses tests a
    unit against a list of length spellings (the guess that made a displacement the tensioner's whatever the profile
    said).  (A ride's check that its axes are in m/s^2 is a unit's check, not a sensor's.)"""
    import re
    from pathlib import Path

    import vibkit.diagnose

    guess = re.compile(r"""in \(\s*["'](?:m|mm|um|cm)["']\s*,\s*["'](?:mm|um|cm)["']""")
    root = Path(vibkit.diagnose.__file__).parent
    found = [
        f"{p.relative_to(root)}:{k}"
        for p in sorted(root.rglob("*.py"))
        for k, line in enumerate(p.read_text().splitlines(), 1)
        if guess.search(line) and p.name != "sensors.py"
    ]
    assert not found, found
    assert guess.search('if units in ("m", "mm", "um"):')  # the check sees the guess it forbids
