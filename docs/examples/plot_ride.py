"""
Ride quality of a step
======================

A phone (here running phyphox) lying on a step records the three accelerations a passenger feels.
:func:`vibkit.diagnose.ride.quality.ride_quality_from_recording` (``vibkit ride``) weights them as
ISO 2631-1 does (Wd across, Wk vertical), and gives each axis's maximum peak to peak, A95 and r.m.s.
over the ride; :func:`vibkit.diagnose.report.plot_ride` draws the table and the weighted signals, the
largest peak-to-peak pair marked. ``--segment 0.5:3`` picks the seconds of the ride.
"""

import matplotlib.pyplot as plt

import vibkit.datasets
from vibkit.diagnose.report import plot_ride
from vibkit.diagnose.ride.quality import ride_quality_from_recording

rq = ride_quality_from_recording(vibkit.datasets.path("field/layouts/phyphox.csv"), segment=(0.5, 3.0))
for axis in rq.axes:
    w = axis.weighted
    print(f"{axis.axis} ({axis.weighting}): max pk-pk {w.max:.3f}, A95 {w.a95:.3f}, r.m.s. {w.rms:.3f} m/s^2")

# %%
fig = plot_ride(rq)
plt.show()
