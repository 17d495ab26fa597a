"""Escalator profiles the tests share."""

#: a 90-link escalator (28-tooth sprocket, 0.5 m/s, tensioner): its worn link's signature changes with the excess,
#: and where the chain coasts (no_load_power = 0) repeats half a loop later (the link on the sprocket, then on the
#: lower head, 45 links apart)
PROFILE_90 = """[escalator]
unit = "E90"
[drive]
speed = 0.5
speed_uncertainty = 0.0005
teeth = 28
[chain]
nominal_pitch = 0.13333
n_links = 90
[sensor]
kind = "tensioner"
"""
