"""Guide and sprocket geometry against the published values of model.md sections 1 and 4."""

import math

import numpy as np
import pytest

from vibkit.model.guide import Guide
from vibkit.model.params import reference_chain, reference_guide, reference_sprocket
from vibkit.model.sprocket import tooth_geometry


def test_reference_numbers():
    sp, ch = reference_sprocket(), reference_chain()
    geo = tooth_geometry(sp, ch.link_pitch, ch.roller_radius)
    assert sp.teeth == 28
    assert geo["pitch_radius"] == pytest.approx(0.59543, abs=5e-6)
    assert math.degrees(geo["beta"]) == pytest.approx(3.064, abs=5e-4)
    assert geo["a"] == pytest.approx(0.801e-3, abs=5e-7)
    g = Guide(reference_guide())
    assert g.perimeter(0.0) == pytest.approx(21.2751, abs=5e-5)
    assert g.params.sprocket_centre == pytest.approx((8.0, 3.0), abs=5e-6)
    # 159 whole pitches fit: P0 / L = 159.56
    assert math.floor(g.p0 / ch.link_pitch) == 159


def test_deformed_perimeter_and_segment_lengths():
    g = Guide(reference_guide())
    for delta in (-0.1, 0.0, 0.033, 0.3):
        assert g.segment_lengths(delta).sum() == pytest.approx(g.p0 - 2 * delta, abs=1e-12)


def test_guide_is_G1_and_tangent_is_derivative():
    """Position is continuous, the tangent is dr/ds and the curvature is the turn rate, everywhere."""
    g = Guide(reference_guide())
    delta = 0.033
    s = np.linspace(0.0, g.perimeter(delta), 20001)[:-1]
    r = g.position(s, delta)
    t = g.tangent(s, delta)
    h = 1e-6
    fd = (g.position(s + h, delta) - g.position(s - h, delta)) / (2 * h)
    np.testing.assert_allclose(fd, t, atol=2e-6)
    np.testing.assert_allclose(np.hypot(*t.T), 1.0, atol=1e-14)
    # consecutive points a small step apart: no jump at segment joints
    assert np.max(np.hypot(*np.diff(r, axis=0).T)) < 1.0001 * (s[1] - s[0])
    # curvature = d(heading)/ds away from joints
    heading = np.unwrap(np.arctan2(t[:, 1], t[:, 0]))
    kap_fd = np.gradient(heading, s)
    kap = g.curvature(s, delta)
    jump = np.zeros(s.size, dtype=bool)
    jump[1:] = np.abs(np.diff(kap)) > 0
    smooth = np.convolve(jump, np.ones(7), mode="same") == 0
    np.testing.assert_allclose(kap_fd[smooth], kap[smooth], atol=1e-6)
    # total turning of a closed loop is -2 pi (clockwise loop)
    total = np.sum(g.table[:, 2] * g.segment_lengths(delta))
    assert total == pytest.approx(-2 * math.pi, abs=1e-12)


def test_lower_head_moves_with_delta():
    g = Guide(reference_guide())
    delta = 0.05
    p = g.perimeter(delta)
    # the top of the lower head is at (delta, R), its bottom at (delta, -R)
    np.testing.assert_allclose(g.position(np.array([0.0]), delta)[0], (delta, g.params.head_radius), atol=1e-12)
    s_bottom = p - math.pi * g.params.head_radius
    np.testing.assert_allclose(g.position(np.array([s_bottom]), delta)[0], (delta, -g.params.head_radius), atol=1e-12)


def test_s0_mapping_roundtrip():
    g = Guide(reference_guide())
    s0 = np.linspace(0, g.p0, 997, endpoint=False)
    for delta in (0.0, 0.04, -0.02):
        np.testing.assert_allclose(g.s_to_s0(g.s0_to_s(s0, delta), delta), s0, atol=1e-12)


def test_bad_delta_is_an_error():
    g = Guide(reference_guide())
    with pytest.raises(ValueError, match="delta"):
        g.perimeter(0.5)
