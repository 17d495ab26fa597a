"""A firm's own link count: a count that closes on the unit's rise is built, one that cannot is refused at
`scene` time naming the keys and the link counts that close (and those counts do close); a count vibkit
derives says so; no solver message reaches a user."""

import dataclasses
import re

import pytest

from vibkit.model.chain import Chain, ClosureError
from vibkit.model.guide import Guide
from vibkit.model.profile import parse_profile
from vibkit.model.profile_scene import link_count
from vibkit.model.scene import SceneError

#: a metro escalator as its drawings describe it: 101.6 mm chain, 4 links a step, 25 teeth
METRO = """
[escalator]
unit = "M14"
[drive]
speed = 0.65
speed_uncertainty = 0.0013
teeth = 25
direction = "down"
[chain]
nominal_pitch = 0.1016
links_per_step = 4
n_links = {n}
[geometry]
rise = 9.0
incline_deg = 30.0
"""


def _metro(n):
    return parse_profile(METRO.format(n=n), "m14.toml")


def test_a_count_that_cannot_close_names_the_keys_and_the_counts_that_do():
    with pytest.raises(SceneError) as exc:
        _metro(408).scene("forward")
    text = str(exc.value)
    assert text.startswith("m14.toml: ") and "\n" not in text
    assert "chain.n_links" in text and "geometry.rise" in text
    assert "converge" not in text and "s0_1" not in text
    lo, hi = (int(v) for v in re.search(r"the link counts that close on this rise are (\d+) to (\d+)", text).groups())
    # the loop of 9 m at 30 deg is 44.08 m: 434 links of 101.6 mm with the tensioner at rest, +-7 over its travel
    assert lo < 434 < hi and hi - lo == pytest.approx(2 * 0.351 * 2 / 0.1016, abs=1.5)
    r_lo, r_hi = (float(v) for v in re.search(r"408 links close on a rise of ([\d.]+) to ([\d.]+) m", text).groups())
    assert r_lo < r_hi < 9.0
    # the range said closes: its ends are built (the chain solved at eight places round the loop) ...
    for n in (lo, hi):
        assert _metro(n).scene("forward").chain.n_rollers == n
    # ... and one past either end is refused
    for n in (lo - 1, hi + 1):
        with pytest.raises(SceneError, match="cannot close"):
            _metro(n).scene("forward")
    # the rise said closes for the drawn count
    mid = parse_profile(METRO.format(n=408).replace("rise = 9.0", f"rise = {(r_lo + r_hi) / 2:.3f}"), "m14.toml")
    assert mid.scene("forward").chain.n_rollers == 408


def test_a_derived_count_says_it_is_derived():
    text = METRO.format(n=0).replace("n_links = 0\n", "")
    n, src = link_count(parse_profile(text, "m14.toml"))
    assert n % 4 == 0 and src.startswith("filled: whole steps of 4 links")
    n, src = link_count(_metro(432))
    assert (n, src) == (432, "chain.n_links")


def test_a_chain_that_cannot_close_says_what_to_change_not_the_solvers_state():
    scene = _metro(432).scene("forward")
    guide = Guide(scene.guide)
    short = dataclasses.replace(scene.chain, n_rollers=380)
    with pytest.raises(ClosureError) as exc:
        Chain(guide, short).configure(0.2)
    text = str(exc.value)
    assert "converge" not in text and "s0_1" not in text
    assert "chain.n_links" in text and "\n" not in text


def test_a_closure_the_solver_loses_says_what_to_change(monkeypatch):
    """Where the bracket is found but the solve fails (the chain near the end of the tensioner's travel), the
    error names the chain's length against the loop and the keys, never the solver's state."""
    import vibkit.model.chain as chain_module

    scene = _metro(432).scene("forward")
    chain = Chain(Guide(scene.guide), scene.chain)
    monkeypatch.setattr(chain_module, "solve_closure", lambda *args: (0.0, 0.0, 3))
    with pytest.raises(ClosureError) as exc:
        chain.configure(0.234040595)
    text = str(exc.value)
    assert "converge" not in text and "s0_1" not in text and "status" not in text and "\n" not in text
    assert "432 links" in text and "chain.n_links" in text and "geometry.rise" in text


def test_commands_refuse_a_count_that_cannot_close_in_one_line(tmp_path, capsys):
    import numpy as np

    from vibkit.cli import main

    profile = tmp_path / "m14.toml"
    profile.write_text(METRO.format(n=408))
    t = np.arange(1000) / 100.0
    rec = tmp_path / "m14.csv"
    rec.write_text(
        "time (s),tensioner_displacement (mm)\n" + "".join(f"{a:.2f},{0.02 * np.cos(40.2 * a):.6f}\n" for a in t)
    )
    for argv in (["links", str(rec)], ["report", str(rec), "-o", str(tmp_path / "r.pdf")]):
        assert main([*argv, "--escalator", str(profile)]) == 1
        err = capsys.readouterr().err.strip()
        assert "\n" not in err and "Traceback" not in err and "converge" not in err
        assert "chain.n_links" in err and "the link counts that close on this rise are" in err
    assert not (tmp_path / "r.pdf").exists()
