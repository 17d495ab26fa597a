"""Diagnostics of recordings and simulations: link pitch, comparison, ride quality, reports.

* :mod:`~vibkit.diagnose.pitch`: link-pass detection, pitch and elongation verdicts;
* :mod:`~vibkit.diagnose.decision`: the one decision on an estimate (ok, no link-pass found, implausible,
  inconclusive) that every command and the fleet share;
* :mod:`~vibkit.diagnose.channels`: every vibration channel of a recording, one decision; the speed a file states;
* :mod:`~vibkit.diagnose.comparison`: a simulation against a field recording, scored;
* :mod:`~vibkit.diagnose.ride`: ride quality (weighted accelerations, peak to peak);
* :mod:`~vibkit.diagnose.report`: multi-page PDF diagnostic reports.
"""
