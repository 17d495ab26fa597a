"""How the scene's links are numbered as a recording numbers them, and which way a scene's chain runs."""

import pytest

from vibkit.diagnose.link_signature import DIRECTIONS, _scene_with, _signed, link_number_of, scene_direction
from vibkit.model.profile import parse_profile
from vibkit.model.scene import load_scene

from support.profiles import PROFILE_90


@pytest.mark.parametrize("passed", [0.0, 0.4, 1.0, 17.5, 89.99, 90.2, 205.7])
def test_links_pass_in_decreasing_number_up_and_increasing_down(passed):
    """After ``passed`` links the link at the sensor is number 1; running up the next to arrive is the one below in
    model number, running down the one above."""
    n = 90
    for direction, step in (("up", -1), ("down", 1)):
        at_sensor = next(k for k in range(1, n + 1) if link_number_of(k, passed, n, direction) == 1)
        for i in range(1, 5):
            assert link_number_of((at_sensor - 1 + step * i) % n + 1, passed, n, direction) == i + 1
    # at the start roller 1 is at the top: running up link n (roller n to 1) is at the sensor, running down link 1
    assert link_number_of(n, 0.3, n, "up") == 1 and link_number_of(1, 0.3, n, "down") == 1


def test_the_direction_is_the_scene_s_motor_speed_sign(tmp_path):
    down = PROFILE_90.replace("teeth = 28", 'teeth = 28\ndirection = "down"')
    for text, want in ((PROFILE_90, "up"), (down, "down")):
        path = tmp_path / f"{want}.toml"
        path.write_text(parse_profile(text, "E90.toml").scene_text("forward"))
        scene = load_scene(path)
        assert scene_direction(scene) == want
        # the signature's runs run the scene's way unless told, at the speed's magnitude
        assert _signed(path, 0.5, None) == (0.5 if want == "up" else -0.5)
        assert _signed(path, -0.5, "up") == 0.5 and _signed(path, 0.5, "down") == -0.5
        assert _scene_with(scene, speed=-0.5).effects["motor"].speed == -0.5
    with pytest.raises(ValueError, match="direction 'sideways'"):
        _signed(path, 0.5, "sideways")
    assert scene_direction(load_scene("sim/thesis-forward.toml")) == "up" and DIRECTIONS == ("up", "down")
