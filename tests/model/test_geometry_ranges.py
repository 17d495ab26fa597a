"""Plausible ranges of the escalator's geometry keys: every shipped scene is inside them, and a length typed in
millimetres where metres are expected is refused naming the key and the metres it meant."""

import re
from pathlib import Path

import pytest

from vibkit.model.scene import SceneError, load_scene, parse_scene
from vibkit.model.schema import GEOMETRY_RANGES, schema_table

SIM = Path(__file__).resolve().parents[2] / "sim"
BASE = (SIM / "thesis-forward.toml").read_text(encoding="utf-8")


def _line_of(key):
    section, name = key.split(".")
    body = BASE.split(f"[{section}]\n", 1)[1].split("\n[", 1)[0]
    m = re.search(rf"^{name}\s*=\s*([0-9.eE+-]+)", body, re.M)
    return (m.group(0), float(m.group(1))) if m else None


PRESENT = {k: _line_of(k) for k in GEOMETRY_RANGES if _line_of(k)}


@pytest.mark.parametrize("path", sorted(SIM.glob("*.toml")), ids=lambda p: p.name)
def test_every_shipped_scene_is_inside_the_ranges(path):
    load_scene(path)


def test_most_geometry_keys_are_exercised():
    assert len(PRESENT) >= 10, sorted(PRESENT)


@pytest.mark.parametrize("key", sorted(PRESENT))
def test_a_value_a_thousand_times_too_large_is_refused(key):
    line, value = PRESENT[key]
    lo, hi, unit = GEOMETRY_RANGES[key]
    assert lo <= value <= hi  # the shipped value is plausible
    text = BASE.replace(line, f"{key.split('.')[1]} = {value * 1000!r}", 1)
    with pytest.raises(SceneError) as err:
        parse_scene(text, "s.toml")
    message = str(err.value)
    assert message.startswith(f"s.toml: '{key}' = ") and f"expected {lo:g}-{hi:g} {unit}" in message
    if unit == "m":
        assert f"did you mean {value:.5g} m?" in message


def test_the_ranges_are_in_the_schema_table():
    table = schema_table()
    for key, (lo, hi, _) in GEOMETRY_RANGES.items():
        section, name = key.split(".")
        assert re.search(rf"\| \[{section}\] \| {name} \|[^\n]*\| \[{lo:g}, {hi:g}\] \|", table), key
