"""The evidence of a clean chain record for :func:`vibkit.diagnose.decision.decide`, as the decision tests build it."""


def chain_evidence(f=3.76, **overrides):
    """Keyword arguments of a :class:`vibkit.diagnose.decision.LinkPassEvidence`: a family detected and estimated at
    ``f`` [Hz] (sigma 1 mHz, bins of 0.125 Hz) in the band 2.5-6.25 Hz, a chain at 0.5 m/s of nominal pitch
    0.5 / ``f`` (elongation 0); ``overrides`` replace or add fields."""
    return {
        "detected": True,
        "detection_hz": f,
        "resolution_hz": 0.125,
        "fundamental_hz": f,
        "fundamental_sigma_hz": 1e-3,
        "band_hz": (2.5, 6.25),
        "speed_m_s": 0.5,
        "nominal_pitch_m": 0.5 / f,
        **overrides,
    }
