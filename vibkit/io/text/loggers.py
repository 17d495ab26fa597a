"""What known loggers and phone apps write without saying it in their columns.

Each entry is read from the app's or device's own documentation; the file is
recognised by its header (and, for per-sensor exports, its file name) and the
decision is recorded in the history:

* **Sensor Logger** (Kelvin Choi, Android/iOS; ``time,seconds_elapsed,z,y,x``):
  ``time`` is Unix epoch in ns, ``seconds_elapsed`` a second clock; the axes
  carry no unit, which the app documents per sensor file: ``Accelerometer.csv``,
  ``TotalAcceleration.csv``, ``Gravity.csv`` in m/s^2, ``Gyroscope.csv`` in rad/s.
* **Physics Toolbox Sensor Suite** (Vieyra Software; ``time,gFx,gFy,gFz,ax,...,wx,...``):
  ``gF*`` in g, linear acceleration ``ax ay az`` in m/s^2, gyroscope ``wx wy wz``
  in rad/s.
* **PicoQuake** (PLab; ``# PLab PicoQuake Data`` comment, ``count,a_x,...,g_z``):
  ``a_*`` in g, ``g_*`` in deg/s; the rate is ``data_rate`` in the ``# Config:``
  comment (read by :mod:`vibkit.io.text.metadata`).

MetaWear (MbientLab MetaBase) and phyphox exports write their units in the
header (``x-axis (g)``, ``Time (s)``); they need nothing here.
"""

from __future__ import annotations

import os
import re

__all__ = ["app_units"]

_SENSOR_LOGGER_FILES = (  # file name (lower case, no separators) -> (unit of x, y, z, what the app calls it)
    ("totalacceleration", "m/s^2", "TotalAcceleration.csv"),
    ("accelerometer", "m/s^2", "Accelerometer.csv"),
    ("acceleration", "m/s^2", "Accelerometer.csv"),
    ("gravity", "m/s^2", "Gravity.csv"),
    ("gyroscope", "rad/s", "Gyroscope.csv"),
    ("gyro", "rad/s", "Gyroscope.csv"),
)
_PTB_UNITS = {"ax": "m/s^2", "ay": "m/s^2", "az": "m/s^2", "wx": "rad/s", "wy": "rad/s", "wz": "rad/s"}
_PICOQUAKE = re.compile(r"^[ag]_[xyz]$")


def app_units(path, names, units, free_text, history):
    """Units of columns that a recognised app leaves unnamed: {column index: unit text}.

    Parameters
    ----------
    path : str
        The file (its name tells a Sensor Logger sensor).
    names : list of str
        Column names without their unit.
    units : list of str or None
        The unit each column's header states (None: none).
    free_text : list of str
        Comment lines above the data.
    history : list of str
        The decision is appended here.
    """
    low = [str(n).strip().lower() for n in names]
    out = {}
    if low[:2] == ["time", "seconds_elapsed"] and {"x", "y", "z"} <= set(low):
        base = re.sub(r"[^a-z]", "", os.path.basename(str(path)).lower())
        for key, unit, app_name in _SENSOR_LOGGER_FILES:
            if key in base:
                out = {j: unit for j, n in enumerate(low) if n in ("x", "y", "z") and units[j] is None}
                history.append(
                    f"Sensor Logger export ('time,seconds_elapsed,...'): x, y, z in {unit}, as the app "
                    f"documents for {app_name} (file name); pass units= to override"
                )
                break
        else:
            history.append(
                "Sensor Logger export ('time,seconds_elapsed,...'): the file name does not say the "
                "sensor, so x, y, z keep no unit; pass units= (e.g. m/s^2 for the accelerometer)"
            )
    elif {"gfx", "gfy", "gfz"} <= set(low):
        out = {j: _PTB_UNITS[n] for j, n in enumerate(low) if n in _PTB_UNITS and units[j] is None}
        if out:
            history.append(
                "Physics Toolbox Sensor Suite export (gFx, gFy, gFz): "
                + ", ".join(f"{names[j]} in {u}" for j, u in out.items())
                + " as the app documents; pass units= to override"
            )
    elif any("picoquake" in t.lower() for t in free_text):
        out = {
            j: ("g" if n[0] == "a" else "deg/s") for j, n in enumerate(low) if _PICOQUAKE.match(n) and units[j] is None
        }
        if out:
            history.append(
                "PicoQuake export ('# PLab PicoQuake Data'): a_x, a_y, a_z in g and g_x, g_y, g_z in "
                "deg/s, as PLab documents; pass units= to override"
            )
    return out
