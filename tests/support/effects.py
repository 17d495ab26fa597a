"""Scene effects shared by the closure tests: every effect with a branch in the compiled right-hand sides."""

# damped contact, the carriage, passengers by place, rolling resistance
ALL_EFFECTS = {
    "gravity": {"g": 9.81},
    "contact": {"stiffness": 1.0e6, "exponent": 1.5, "damping": 0.3},
    "motor": {"kp": 600.0, "speed": 0.5},
    "tensioner": {"stiffness": 2.0e4, "preload": 3000.0, "mass": 40.0},
    "passengers": {
        "mass": [70.0, 90.0],
        "step": [3, 53],
        "board": ["lower_landing"] * 2,
        "alight": ["upper_landing"] * 2,
    },
    "rolling_resistance": {"coefficient": 0.01},
}
