"""
The link pass in a tensioner recording
======================================

A chain of links of pitch :math:`p` running at speed :math:`v` moves the tensioner once per link:
the recording's spectrum has a line at the link-pass frequency :math:`f = v / p` and its harmonics.
:func:`vibkit.diagnose.pitch.estimate_pitch` finds that family and turns it into a pitch with its
uncertainty; ``vibkit pitch`` is this call from the command line.
"""

import matplotlib.pyplot as plt

import vibkit
import vibkit.datasets
from vibkit.diagnose.pitch import estimate_pitch
from vibkit.signal import amplitude_spectrum, sample_rate

rec = vibkit.read_recording(vibkit.datasets.path("field/leon-tensioner.csv"))
est = estimate_pitch(rec, speed=0.49, speed_sigma=0.49e-3, nominal_pitch=0.13333)
print(f"link pass {est.fundamental_hz:.4f} +- {est.fundamental_sigma_hz:.4f} Hz")
print(f"pitch {est.pitch_m * 1e3:.3f} +- {est.pitch_sigma_m * 1e3:.3f} mm, {est.verdict}")

# %%
# The spectrum with the fitted harmonics marked: the fundamental and its multiples stand out of the
# noise floor, each harmonic's amplitude is the one the estimate fitted.

x = rec[est.channel]
f, a = amplitude_spectrum(x.values, sample_rate(rec))
units = x.attrs.get("units", "")
fig, ax = plt.subplots(figsize=(8, 3.5), layout="constrained")
ax.semilogy(f, a, lw=0.7, color="0.3")
for k in range(1, 6):
    ax.axvline(k * est.fundamental_hz, color="C1", lw=0.8, ls="--", alpha=0.7)
ax.set_xlim(0, 6.5 * est.fundamental_hz)
ax.set_xlabel("frequency [Hz]")
ax.set_ylabel(f"amplitude [{units}]")
ax.set_title(f"{est.channel}: link pass {est.fundamental_hz:.3f} Hz and its harmonics (dashed)")
plt.show()
