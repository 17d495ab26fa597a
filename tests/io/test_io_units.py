"""Units read from headers and overrides, against their definitions (SI brochure, CGPM 1901)."""

import math

import pytest

from vibkit.io.text.units import STANDARD_GRAVITY, is_time_name, parse_time_unit, parse_unit, split_name_unit


@pytest.mark.parametrize(
    "text, factor, si, quantity",
    [
        ("m/s^2", 1.0, "m/s^2", "acceleration"),
        ("m/s2", 1.0, "m/s^2", "acceleration"),
        ("m/s²", 1.0, "m/s^2", "acceleration"),
        ("m s-2", 1.0, "m/s^2", "acceleration"),
        ("m·s⁻²", 1.0, "m/s^2", "acceleration"),
        ("m/s/s", 1.0, "m/s^2", "acceleration"),
        ("mm/s^2", 1e-3, "m/s^2", "acceleration"),
        ("g", 9.80665, "m/s^2", "acceleration"),
        ("G", 9.80665, "m/s^2", "acceleration"),
        ("mg", 9.80665e-3, "m/s^2", "acceleration"),
        ("Gal", 1e-2, "m/s^2", "acceleration"),
        ("m/s", 1.0, "m/s", "velocity"),
        ("mm/s", 1e-3, "m/s", "velocity"),
        ("in/s", 0.0254, "m/s", "velocity"),
        ("m", 1.0, "m", "displacement"),
        ("mm", 1e-3, "m", "displacement"),
        ("µm", 1e-6, "m", "displacement"),
        ("um", 1e-6, "m", "displacement"),
        ("g/2048", 9.80665 / 2048, "m/s^2", "acceleration"),
        ("0.001 m", 1e-3, "m", "displacement"),
        ("2.5e-4*g", 2.5e-4 * 9.80665, "m/s^2", "acceleration"),
        ("deg/s", math.pi / 180, "rad/s", "other"),
    ],
)
def test_parse_unit_factor_to_si(text, factor, si, quantity):
    u = parse_unit(text)
    assert u is not None
    assert u.factor == pytest.approx(factor, rel=1e-12)
    assert (u.si, u.quantity) == (si, quantity)


def test_standard_gravity_is_the_cgpm_value():
    assert STANDARD_GRAVITY == 9.80665


@pytest.mark.parametrize("text", ["counts", "Counts", "raw", "LSB"])
def test_counts_have_no_factor(text):
    u = parse_unit(text)
    assert u.factor is None and u.si == "counts" and u.quantity == "other"


@pytest.mark.parametrize("text", ["", "xyz", "UTC", "left", "100g", "g/0", "m/s^3", None, 5])
def test_unknown_units_are_none(text):
    assert parse_unit(text) is None


@pytest.mark.parametrize(
    "text, factor",
    [("s", 1.0), ("sec", 1.0), ("ms", 1e-3), ("µs", 1e-6), ("us", 1e-6), ("ns", 1e-9), ("min", 60.0), ("seg", 1.0)],
)
def test_time_units(text, factor):
    assert parse_time_unit(text) == factor


@pytest.mark.parametrize(
    "header, name, unit",
    [
        ("Acceleration x (m/s^2)", "Acceleration x", "m/s^2"),
        ('"Time (s)"', "Time", "s"),
        ("acc [g]", "acc", "g"),
        ("Aceleración (g)", "Aceleración", "g"),
        ("time_ms", "time", "ms"),
        ("acc_z_g", "acc_z", "g"),
        ("accel_m_s2", "accel", "m/s^2"),
        ("acc_z_m_s_2", "acc_z", "m/s^2"),
        ("vel_mm_s", "vel", "mm/s"),
        ("pos_m", "pos", "m"),
        ("pos in mm", "pos", "mm"),
        ("X (100g)", "X", "g"),
        ("gFz", "gFz", "g"),
        ("TgF", "TgF", "g"),
        ("acc_z", "acc_z", None),
        ("Ax", "Ax", None),
        ("sensor_in", "sensor_in", None),
    ],
)
def test_split_name_unit(header, name, unit):
    got_name, got_unit, _ = split_name_unit(header)
    assert (got_name, got_unit) == (name, unit)


@pytest.mark.parametrize("name", ["time", "Time", "t", "Tiempo", "timestamp", "Date/Time", "datetime", "hora"])
def test_time_names(name):
    assert is_time_name(name)


@pytest.mark.parametrize("name", ["acc", "temperature", "Ax", "gFz", "tensioner_displacement"])
def test_not_time_names(name):
    assert not is_time_name(name)
