"""A worn chain in the scene: links of another pitch, an elongated chain on its original sprocket,
rollers of another radius or mass; every bad value is an error naming the file and the key."""

import math
from pathlib import Path

import numpy as np
import pytest

from vibkit.model.escalator import EscalatorModel
from vibkit.model.scene import SceneError, parse_scene

SIM = Path(__file__).resolve().parents[2] / "sim"
BASE = (SIM / "thesis-forward.toml").read_text()
L = 0.4 / 3.0


def _scene(chain="", sprocket=""):
    text = BASE.replace("n_rollers = 159", "n_rollers = 159\n" + chain)
    text = text.replace("inertia = 43.78", "inertia = 43.78\n" + sprocket)
    return parse_scene(text, "worn.toml")


def test_worn_links_set_the_pitch_of_each_link():
    sc = _scene("worn_links = [[40, 0.1343], [70, 0.1348]]\nworn_link = 100\nworn_link_pitch = 0.134")
    p = sc.chain.pitches()
    assert p[39] == 0.1343 and p[69] == 0.1348 and p[99] == 0.134
    assert np.count_nonzero(p != L) == 3


def test_elongated_chain_keeps_its_sprocket_and_seats_higher():
    """3 % longer links on teeth cut for the nominal pitch: the teeth (and their pitch radius) are
    the original sprocket's; the rollers seat where links of 1.03 L are a tooth pitch apart."""
    new, worn = _scene(), _scene("elongation_percent = 3.0")
    z = new.sprocket.teeth
    assert worn.chain.link_pitch == pytest.approx(1.03 * L, rel=1e-15)
    assert worn.sprocket.pitch == pytest.approx(L, rel=1e-15)
    m_new, m_worn = EscalatorModel(new), EscalatorModel(worn)
    assert m_worn.pitch_radius == m_new.pitch_radius  # the same sprocket
    np.testing.assert_array_equal(m_worn.corners_local, m_new.corners_local)
    assert worn.guide.head_radius == pytest.approx(1.03 * L / (2 * math.sin(math.pi / z)), rel=1e-14)
    assert worn.chain.n_rollers == new.chain.n_rollers == 159  # the chain keeps its links


def test_sprocket_pitch_separates_teeth_from_chain():
    """A chain of 1.03 L given by its pitch on a sprocket cut for L is the 3 % elongated chain."""
    a = _scene("elongation_percent = 3.0")
    b = parse_scene(
        BASE.replace("link_pitch = 0.13333333333333333", f"link_pitch = {1.03 * L!r}").replace(
            "inertia = 43.78", f"inertia = 43.78\npitch = {L!r}"
        )
    )
    assert b.guide.head_radius == pytest.approx(a.guide.head_radius, rel=1e-14)
    assert EscalatorModel(b).pitch_radius == pytest.approx(EscalatorModel(a).pitch_radius, rel=1e-14)


def test_rollers_by_number():
    sc = _scene("roller_radius_by_roller = [[12, 0.033]]\nroller_mass_by_roller = [[3, 9.5], [4, 7.0]]")
    m = EscalatorModel(sc)
    assert m.radii[11] == 0.033 and np.count_nonzero(m.radii != 0.035) == 1
    assert m.mass[2] == 9.5 and m.mass[3] == 7.0 and np.count_nonzero(m.mass != 8.0) == 2


@pytest.mark.parametrize(
    "chain, sprocket, pattern",
    [
        ("worn_links = [[0, 0.134]]", "", r"worn\.toml: 'chain\.worn_links': link number must be an integer 1\.\.159"),
        ("worn_links = [[160, 0.134]]", "", r"'chain\.worn_links': link number must be an integer 1\.\.159"),
        ("worn_links = [[4, -0.134]]", "", r"'chain\.worn_links': pitch of link 4 must be positive"),
        ("worn_links = [[4, 0.2]]", "", r"'chain\.worn_links': pitch 0\.2 m of link 4 is not plausible"),
        ("worn_links = [4, 0.134]", "", r"'chain\.worn_links' entries must be pairs"),
        ("worn_links = [[4, 0.134], [4, 0.135]]", "", r"'chain\.worn_links': link 4 is given twice"),
        ("worn_links = [[4, 0.134]]\nworn_link = 4\nworn_link_pitch = 0.134", "", r"link 4 is in both"),
        ("worn_link = 4", "", r"'chain\.worn_link' and 'chain\.worn_link_pitch' go together"),
        ("elongation_percent = 30.0", "", r"'chain\.elongation_percent' = 30\.0 is outside the plausible range"),
        ("elongation_percent = 8.0", "", r"above its tooth tips .* has jumped the teeth"),
        ("roller_radius_by_roller = [[3, 0.0]]", "", r"'chain\.roller_radius_by_roller': radius of roller 3"),
        ("roller_radius_by_roller = [[3, 0.09]]", "", r"radius 0\.09 m of roller 3 must be less than half"),
        ("roller_mass_by_roller = [[200, 8.0]]", "", r"'chain\.roller_mass_by_roller': roller number must be"),
        ("", "pitch = -0.1", r"'sprocket\.pitch' must be positive"),
    ],
)
def test_bad_worn_chain_keys_name_file_and_key(chain, sprocket, pattern):
    with pytest.raises(SceneError, match=pattern):
        _scene(chain, sprocket)
