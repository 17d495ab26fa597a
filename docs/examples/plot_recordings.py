"""
Recordings from different devices, read alike
=============================================

:func:`vibkit.read_recording` reads each file into one :class:`xarray.Dataset` whatever wrote it: time
in seconds, each channel with its ``units`` attribute in SI, the reader and the file's checksum in the
attributes. Here a tensioner displacement from a field logger's CSV, and a step's acceleration from
a phone app (phyphox), an enDAQ and a GCDC X16 logger, each in its own layout.
"""

import matplotlib.pyplot as plt

import vibkit
import vibkit.datasets

LAYOUTS = vibkit.datasets.path("field")
files = [
    LAYOUTS / "leon-tensioner.csv",
    LAYOUTS / "layouts" / "phyphox.csv",
    LAYOUTS / "layouts" / "endaq.csv",
    LAYOUTS / "layouts" / "gcdc-x16.csv",
]

fig, axes = plt.subplots(len(files), 1, figsize=(8, 7), layout="constrained")
for ax, path in zip(axes, files):
    rec = vibkit.read_recording(path)
    name = list(rec.data_vars)[-1]  # the vertical axis of the three-axis loggers
    da = rec[name]
    print(f"{path.name}: {list(rec.data_vars)}, {rec.sizes['time']} samples, reader {rec.attrs.get('reader', '?')}")
    ax.plot(rec["time"].values, da.values, lw=0.6)
    ax.set_ylabel(f"[{da.attrs.get('units', '')}]")
    ax.set_title(f"{path.name}: {name}", fontsize=9, loc="left")
axes[-1].set_xlabel("time [s]")
plt.show()
