"""The roller-tooth contact kernel against the contact law of model.md section 5, written out here
tooth by tooth and flank by flank over every tooth of the sprocket (no culling, no tooth table)."""

import math
from dataclasses import replace

import numpy as np
import pytest

from vibkit.model.params import reference_chain, reference_sprocket
from vibkit.model.sprocket import (
    contact_kernel,
    fast_atan2,
    local_corners,
    tooth_corners,
    tooth_geometry,
    tooth_table,
)


def _segment_distance(p, a, b):
    """Distance from p to the segment ab, and the closest point."""
    ab = b - a
    u = min(1.0, max(0.0, float(np.dot(p - a, ab) / np.dot(ab, ab))))
    q = a + u * ab
    return float(np.linalg.norm(p - q)), q


def _reference(pos, radii, theta, centre, sp, pitch, roller_radius, k, expo):
    """Forces, torque, energy, deepest indentation, contacts and flank sums over every tooth."""
    corners = tooth_corners(sp, pitch, roller_radius, centre, theta)
    f = np.zeros_like(pos)
    torque = energy = worst = drive = back = 0.0
    active = 0
    for i, p in enumerate(pos):
        for tooth in corners:
            for a, b, is_drive in ((tooth[0], tooth[1], False), (tooth[3], tooth[2], True)):
                dist, q = _segment_distance(p, a, b)
                pen = radii[i] - dist
                if pen <= 0.0:
                    continue
                n = (p - q) / dist
                force = k * pen**expo
                f[i] += force * n
                torque += (q[0] - centre[0]) * (-force * n[1]) - (q[1] - centre[1]) * (-force * n[0])
                energy += k * pen ** (expo + 1) / (expo + 1)
                worst = max(worst, pen)
                active += 1
                if is_drive:
                    drive += force
                else:
                    back += force
    return f, (torque, energy, worst, active, drive, back)


def _rollers(rng, sp, pitch, roller_radius, m):
    """Roller centres round the sprocket: seated and pushed onto the flanks, riding on the tips,
    deep in a tooth, and farther out (none of them touching)."""
    geo = tooth_geometry(sp, pitch, roller_radius)
    phi = rng.uniform(-math.pi, math.pi, m)
    rho = np.concatenate(
        [
            geo["pitch_radius"] + rng.normal(0.0, 0.2 * roller_radius, m // 2),
            rng.uniform(geo["root_radius"] - 0.5 * roller_radius, geo["tip_radius"] + roller_radius, m - m // 2),
        ]
    )
    return np.column_stack([-rho * np.sin(phi), rho * np.cos(phi)])


# wide teeth and rollers wider than the gap between two teeth: a roller can reach a third tooth
WIDE = {"teeth": 60, "base_width": 0.09}


@pytest.mark.parametrize(
    "sprocket, roller_scale",
    [({"teeth": 28}, 1.0), ({"teeth": 11}, 1.0), ({"teeth": 60}, 1.0), ({"teeth": 60}, 2.5), (WIDE, 2.5)],
    ids=["study", "few-teeth", "many-teeth", "many-teeth-wide-rollers", "third-tooth"],
)
def test_kernel_matches_every_tooth_and_flank(sprocket, roller_scale):
    teeth = sprocket["teeth"]
    rng = np.random.default_rng(teeth * 10 + int(roller_scale * 10))
    chain = reference_chain()
    sp = replace(reference_sprocket(), **sprocket)
    pitch, r = chain.link_pitch, chain.roller_radius * roller_scale
    geo = tooth_geometry(sp, pitch, r)
    loc = local_corners(sp, pitch, r)
    m = 400
    centre = np.array([8.0, 3.0])
    teeth_table = tooth_table(loc, geo["root_radius"], geo["tooth_pitch"], teeth, r)
    k, expo = 1e6, 1.5
    zeros = np.zeros(m)
    for theta in rng.uniform(-10.0, 10.0, 5):
        pos = centre + _rollers(rng, sp, pitch, r, m)
        radii = np.full(m, r)
        fx, fz = np.zeros(m), np.zeros(m)
        got = contact_kernel(
            pos[:, 0].copy(), pos[:, 1].copy(), zeros, zeros, np.arange(m, dtype=np.int64), m, theta, 0.0,
            centre[0], centre[1], teeth_table, radii, k, expo, 0.0, fx, fz, np.zeros(teeth), np.zeros(teeth), False,
        )  # fmt: skip
        f_ref, ref = _reference(pos, radii, theta, centre, sp, pitch, r, k, expo)
        assert ref[3] > 10  # the draw puts rollers on flanks and tips
        scale = np.abs(f_ref).max()
        np.testing.assert_allclose(np.column_stack([fx, fz]), f_ref, rtol=0, atol=1e-9 * scale)
        np.testing.assert_allclose(got[:3], ref[:3], rtol=1e-9, atol=1e-12)
        assert got[3] == ref[3]
        np.testing.assert_allclose(got[4:], ref[4:], rtol=1e-9, atol=1e-9 * scale)


def test_the_window_is_what_wide_rollers_need():
    """The tooth table looks beyond the two teeth that bracket a roller only where a roller can
    reach a third; forced to two teeth, the wide rollers' case misses contacts (the control)."""
    chain = reference_chain()
    pitch = chain.link_pitch
    windows = {}
    for name, params, scale in (("study", {"teeth": 28}, 1.0), ("wide", WIDE, 2.5)):
        sp = replace(reference_sprocket(), **params)
        r = chain.roller_radius * scale
        geo = tooth_geometry(sp, pitch, r)
        t = tooth_table(local_corners(sp, pitch, r), geo["root_radius"], geo["tooth_pitch"], sp.teeth, r)
        windows[name] = int(t[2, 4])
    assert windows == {"study": 0, "wide": 1}
    r = chain.roller_radius * 2.5
    geo = tooth_geometry(sp, pitch, r)
    narrow = tooth_table(local_corners(sp, pitch, r), geo["root_radius"], geo["tooth_pitch"], 60, r)
    narrow[2, 4] = 0
    rng = np.random.default_rng(7)
    m = 400
    centre = np.array([8.0, 3.0])
    pos = centre + _rollers(rng, sp, pitch, r, m)
    zeros = np.zeros(m)
    out = contact_kernel(
        pos[:, 0].copy(), pos[:, 1].copy(), zeros, zeros, np.arange(m, dtype=np.int64), m, 0.3, 0.0,
        centre[0], centre[1], narrow, np.full(m, r), 1e6, 1.5, 0.0, np.zeros(m), np.zeros(m), np.zeros(60),
        np.zeros(60), False,
    )  # fmt: skip
    _, ref = _reference(pos, np.full(m, r), 0.3, centre, sp, pitch, r, 1e6, 1.5)
    assert out[3] < ref[3]


def test_fast_arctangent_within_the_tooth_tables_allowance():
    """The arctangent that picks a roller's teeth errs by less than the 1e-3 rad the tooth table
    allows it (measured 2e-4 rad), at every angle and radius."""
    rng = np.random.default_rng(3)
    ang = rng.uniform(-math.pi, math.pi, 20000)
    rho = np.exp(rng.uniform(-5.0, 5.0, 20000))
    err = [abs(math.remainder(fast_atan2(r * math.sin(a), r * math.cos(a)) - a, 2 * math.pi)) for a, r in zip(ang, rho)]
    assert max(err) < 3e-4
