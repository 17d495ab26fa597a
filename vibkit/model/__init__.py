"""The escalator: guide geometry, chain closure, sprocket contact, effects, the assembled model, scenes.

* :mod:`~vibkit.model.params`: the study's parameters (guide, chain, sprocket);
* :mod:`~vibkit.model.guide`: the guide path (arcs and lines) and its breakpoints;
* :mod:`~vibkit.model.chain`: rollers on the guide, the closure of the loop, its partial derivatives;
* :mod:`~vibkit.model.sprocket`: tooth geometry and roller-tooth contact;
* :mod:`~vibkit.model.flat_roller`: a roller worn flat, its knock on the track;
* :mod:`~vibkit.model.dynamics`: the reduced equation of motion and link multipliers;
* :mod:`~vibkit.model.effects`: the right-hand side with only the effects a scene switches on;
* :mod:`~vibkit.model.escalator`: :class:`EscalatorModel`, the three bodies assembled;
* :mod:`~vibkit.model.schema`: every scene key with its unit, default, range and meaning;
* :mod:`~vibkit.model.scene`: scene files (TOML), validated against the schema.

Nothing here imports :mod:`vibkit.analyses`, :mod:`vibkit.diagnose` or the command line.
"""
