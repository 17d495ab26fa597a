"""Chain closure, its velocity and acceleration recursions."""

import numpy as np
import pytest

from vibkit.model.chain import Chain, ClosureError
from vibkit.model.guide import Guide
from vibkit.model.params import ChainParams, reference_chain, reference_guide

L = 0.4 / 3


@pytest.fixture(scope="module")
def chain():
    return Chain(Guide(reference_guide()), reference_chain())


def test_full_loop_closure_residual(chain):
    """Every configuration around the whole loop closes to 1e-12 m (1 mm steps: 21,275 configurations)."""
    s0 = np.arange(0.0, chain.guide.p0, 1e-3)
    deltas, resid = chain.sweep(s0)
    assert resid.max() <= 1e-12
    assert np.all(np.isfinite(deltas))
    assert 0.0331 < deltas.min() and deltas.max() < 0.0333


def test_configuration_links_all_have_pitch(chain):
    for s0_1 in (0.0, 0.2, 1.9, 7.77, 10.4, 19.9, 21.2):  # tensioner runs, heads, joints, wrap
        conf = chain.configure(s0_1)
        r = conf.position
        links = np.hypot(*(np.roll(r, -1, axis=0) - r).T)
        np.testing.assert_allclose(links, L, atol=1e-12)
        assert conf.closure_residual <= 1e-12
        assert np.all(np.diff(conf.s0) > 0)


def test_delta_periodic_with_link_pitch_and_mean(chain):
    s = np.linspace(3.0, 3.0 + L, 1334)[:-1]
    d1, _ = chain.sweep(s)
    d2, _ = chain.sweep(s + L)
    d3, _ = chain.sweep(s + 3 * L)
    np.testing.assert_allclose(d2, d1, atol=1e-12)
    np.testing.assert_allclose(d3, d1, atol=1e-12)
    assert d1.mean() == pytest.approx(0.03317, abs=0.5e-5)  # the study's 33.17 mm


@pytest.mark.parametrize("s0_1", [0.13, 1.5, 3.3, 8.8, 10.05, 20.5])
def test_velocities_satisfy_differentiated_constraints(chain, s0_1):
    conf = chain.configure(s0_1)
    mo = chain.motion(conf, 0.5, 0.2)
    r, v = conf.position, mo["velocity"]
    u = np.roll(r, -1, axis=0) - r
    dv = np.roll(v, -1, axis=0) - v
    rel = np.abs(np.sum(u * dv, axis=1)) / (L * np.abs(v).max())
    assert rel.max() < 1e-10
    # accelerations: u.(a_j+1 - a_j) + |v_j+1 - v_j|^2 = 0
    a = mo["acceleration"]
    da = np.roll(a, -1, axis=0) - a
    rel_a = np.abs(np.sum(u * da, axis=1) + np.sum(dv * dv, axis=1)) / (L * np.abs(a).max())
    assert rel_a.max() < 1e-10


def _clear_of_joints(chain, start, margin=2e-3):
    """First s0_1 >= start with every roller at least ``margin`` from a segment joint (the curvature
    jumps there, so finite differences across a joint are first order only)."""
    joints = np.append(chain.guide.table[:, 0], chain.guide.p0)
    for s0_1 in start + np.arange(0, L, 1e-3):
        s0 = np.mod(chain.configure(s0_1).s0, chain.guide.p0)
        if np.min(np.abs(s0[:, None] - joints[None, :])) > margin:
            return s0_1
    raise AssertionError("no configuration clear of joints")


@pytest.mark.parametrize("start", [3.3, 8.1, 12.0])
def test_velocity_and_acceleration_against_finite_differences(chain, start):
    """r_i(t) along s0_1(t) = s + v t + a t^2 / 2; central differences in t.

    h = 1 ms: truncation error ~1e-6 m/s^2; position rounding (~1e-13 m) / h^2 stays below 1e-6."""
    v1, a1, h = 0.5, 0.3, 1e-3
    s0_1 = _clear_of_joints(chain, start)

    def positions(t):
        c = chain.configure(s0_1 + v1 * t + 0.5 * a1 * t * t)
        return c.position, c.delta

    (rm, dm), (r0, d0), (rp, dp) = positions(-h), positions(0.0), positions(h)
    mo = chain.motion(chain.configure(s0_1), v1, a1)
    v_fd = (rp - rm) / (2 * h)
    a_fd = (rp - 2 * r0 + rm) / h**2
    np.testing.assert_allclose(mo["velocity"], v_fd, atol=1e-6)
    np.testing.assert_allclose(mo["acceleration"], a_fd, atol=1e-5)
    assert mo["delta_dot"] == pytest.approx((dp - dm) / (2 * h), abs=1e-7)  # truncation ~3e-8
    assert mo["delta_ddot"] == pytest.approx((dp - 2 * d0 + dm) / h**2, abs=1e-5)


def test_chain_that_cannot_close():
    g = Guide(reference_guide())
    with pytest.raises(ClosureError, match="cannot close"):
        Chain(g, ChainParams(link_pitch=L, roller_radius=0.035, roller_mass=8.0, n_rollers=170)).configure(3.0)


@pytest.mark.parametrize("p", [50, 120, 159])
def test_other_chain_lengths_close(p):
    """Scaled guides with p from 50 to 159 rollers close to 1e-12 (linear-cost walk, no dense solve)."""
    import dataclasses

    base = reference_guide()
    scale = p / 159
    guide = dataclasses.replace(base, incline_length=base.incline_length * scale)
    g = Guide(guide)
    n = int(g.p0 // L)
    ch = Chain(g, ChainParams(link_pitch=L, roller_radius=0.035, roller_mass=8.0, n_rollers=n))
    s0 = np.linspace(0, g.p0, 301)
    _, resid = ch.sweep(s0)
    assert resid.max() <= 1e-12


@pytest.mark.parametrize("worn", [False, True])
def test_crossing_table_puts_a_roller_on_a_breakpoint(worn):
    """Every value of the crossing table closes the chain with some roller on a breakpoint of the
    guide (to the closure's rounding), with equal pitches and with one worn link; and between two
    values no roller crosses one."""
    from dataclasses import replace

    from vibkit.model.chain import Chain
    from vibkit.model.guide import Guide
    from vibkit.model.params import reference_chain, reference_guide

    guide = Guide(reference_guide())
    params = reference_chain()
    if worn:
        params = replace(params, worn_links=((40, 1.03 * params.link_pitch),))
    chain = Chain(guide, params)
    cross = chain.crossing_table()
    bps = guide.breakpoints()
    p0 = guide.p0

    def distance(s0_1):
        s0 = chain.configure(float(s0_1)).s0
        return np.abs(np.mod(s0[:, None] - bps[None, :] + 0.5 * p0, p0) - 0.5 * p0).min()

    for v in cross[:: max(1, cross.size // 60)]:
        assert distance(v) < 1e-11
    # between consecutive values the rollers' segments do not change (sampled)
    for a, b in zip(cross[100:110], cross[101:111]):
        segs = [chain.configure(float(x)).segment for x in np.linspace(a, b, 5)[1:-1]]
        assert all(np.array_equal(segs[0], s) for s in segs[1:])


@pytest.mark.parametrize("s0_1", [0.0, 0.05, 0.3, 7.77, 20.9, 21.2, 21.275, 30.0])
def test_the_ghost_walk_is_the_walk(chain, s0_1):
    """The ghost walk (the telescopic runs' s0 left out, as the inverse run's closing walks take it) has the walk's
    ghost residual and points to the bit, and with ``runs`` 1.0 its s0 too; roller 1 on a run, near and across
    the wrap, past a loop. Only s0 on the runs differ (some do, else the test shows nothing)."""
    from vibkit.model.chain import walk, walk_ghost
    from vibkit.model.guide import SIGP

    g, n = chain.guide, chain.n
    delta = chain.configure(s0_1 % g.p0).delta
    runs = {}
    for flag in (None, 1.0, 0.0):
        s0, lam, xs, zs, kk = [np.empty(n + 1) for _ in range(4)] + [np.empty(n + 1, dtype=np.int64)]
        args = (g.table, g.p0, s0_1, delta, chain.pitches, n, s0, kk, lam, xs, zs)
        h = walk(*args) if flag is None else walk_ghost(*args, flag)
        runs[flag] = (h, s0, lam, xs, zs, kk)
    h, s0, lam, xs, zs, kk = runs[None]
    assert abs(h) < 1e-9
    for flag in (1.0, 0.0):
        assert runs[flag][0] == h
        for a, b in zip((lam, xs, zs, kk), runs[flag][2:]):
            assert np.array_equal(a, b)
    assert np.array_equal(runs[1.0][1], s0)
    left = runs[0.0][1] != s0
    assert left.any() and np.all(g.table[kk[left], SIGP] != 0.0)
