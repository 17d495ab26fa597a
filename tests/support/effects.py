"""What the closure tests share: every effect with a branch in the compiled right-hand sides, random states."""

import numpy as np

from vibkit.model.schema import EFFECT_OPTIONS

# damped contact, the carriage, passengers by place, rolling resistance
EXAMPLES = {
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


def every_effect(examples: dict, where: str) -> dict:
    """One entry of ``examples`` for each effect of the scene schema, in the schema's order; an effect the
    schema declares without one stops the tests that use them, naming it (add it to ``where``)."""
    missing = [name for name in EFFECT_OPTIONS if name not in examples]
    if missing:
        raise LookupError(f"{where}: no options for the schema's effects {', '.join(missing)}; add them")
    return {name: examples[name] for name in EFFECT_OPTIONS}


#: every effect of the schema (vibkit.model.schema.EFFECT_OPTIONS) with options
ALL_EFFECTS = every_effect(EXAMPLES, "tests/support/effects.py EXAMPLES")


def random_state(rng, p0):
    """A forward state [s0_1, s0_1-dot, theta, theta-dot, speed-error integral] anywhere on two loops of a
    guide of period ``p0``, moving either way, the sprocket at any angle."""
    return np.array(
        [
            rng.uniform(0.0, 2.0 * p0),
            rng.uniform(-0.6, 0.6),
            rng.uniform(0.0, 2 * np.pi),
            rng.uniform(-1.0, 0.0),
            rng.uniform(-0.01, 0.01),
        ]
    )
