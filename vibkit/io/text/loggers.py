"""What each known logger or app writes without saying it in its columns: one :class:`LoggerProfile` each.

Every fact vibkit knows of one device family sits in its entry of :data:`PROFILES`, read from the
maker's own documentation; the generic text reader reads the entries and never names a logger:

* ``column_units``: units of columns the header leaves unnamed, applied when ``recognise`` claims
  the file (the first profile that does decides; the decision goes into the history);
* ``bracket_units`` and ``bare_headers``: header cells whose unit text means something else
  (an enDAQ ``X (100g)`` is a range, the values are in g; a Physics Toolbox ``gFx`` is in g),
  read by :func:`vibkit.io.text.units.split_name_unit`;
* ``rate_keys``: metadata keys that hold the sample rate (PicoQuake's ``data_rate``), read by
  :mod:`vibkit.io.text.metadata` beside the generic ones (``Sampling rate``, ``fs`` ...);
* ``header_keys``: metadata keys whose value names the columns (GCDC's ``;Headers, time,Ax,...``);
* ``clock_columns``: time columns named after a clock function, with their unit (Arduino
  ``millis()``, ``micros()``), read by :mod:`vibkit.io.text.timecolumn`;
* ``facts``: what else the layout does that the generic reader handles without being told (for the
  reader of this module; no code reads it).

Adding a logger
---------------
Add one :class:`LoggerProfile` to :data:`PROFILES` with the facts its documentation states (give
the source in ``source``) and one test file, ``tests/io/test_logger_<name>.py``, that writes (or
ships, where the licence allows) a file in the logger's exact layout and checks that it reads right
with no options: channel names, units in SI, rate, and the history line naming the logger.
A logger that is a different *file format* (binary packets, a container) is an entry of
:data:`vibkit.io.registry.FORMATS` instead.
"""

from __future__ import annotations

import os
import re
from dataclasses import dataclass, field
from typing import Callable

from ...runtime.reader_options import spell

__all__ = ["LoggerProfile", "PROFILES", "app_units", "header_unit", "rate_key_patterns", "header_keys", "clock_units"]


@dataclass(frozen=True)
class LoggerProfile:
    """What vibkit knows of one logger or app.

    Attributes
    ----------
    name : str
        The logger as its maker calls it.
    source : str
        Where the facts come from (the maker's documentation).
    recognise : callable, optional
        ``recognise(path, low_names, free_text) -> bool``: whether a file is this logger's
        (``low_names``: column names without units, lower case; ``free_text``: comment lines).
    column_units : callable, optional
        ``column_units(path, names, low_names, units, history) -> {column index: unit text}``
        for a recognised file; appends its decision to ``history``.
    bracket_units : tuple of (regex, unit, note)
        A header ``name (text)`` whose ``text`` fully matches ``regex`` is in ``unit``; ``note``
        (formatted with ``text`` and the regex's groups as ``{0}``, ``{1}`` ...) goes to the history.
    bare_headers : tuple of (regex, unit, note)
        A whole header cell fully matching ``regex`` (case-insensitive) is in ``unit``
        (``note`` formatted with ``header``).
    rate_keys : tuple of str
        Regular expressions (searched, case-insensitive) for metadata keys holding the sample rate.
    header_keys : tuple of str
        Metadata keys (lower case) whose value lists the column names.
    clock_columns : dict
        Time column name (lower case) -> (unit text, factor to seconds).
    facts : str
        Layout quirks the generic reader handles without this entry.
    """

    name: str
    source: str
    recognise: Callable[..., bool] | None = None
    column_units: Callable[..., dict] | None = None
    bracket_units: tuple = ()
    bare_headers: tuple = ()
    rate_keys: tuple = ()
    header_keys: tuple = ()
    clock_columns: dict = field(default_factory=dict)
    facts: str = ""


_SENSOR_LOGGER_FILES = (  # file name (lower case, no separators) -> (unit of x, y, z, what the app calls it)
    ("totalacceleration", "m/s^2", "TotalAcceleration.csv"),
    ("accelerometer", "m/s^2", "Accelerometer.csv"),
    ("acceleration", "m/s^2", "Accelerometer.csv"),
    ("gravity", "m/s^2", "Gravity.csv"),
    ("gyroscope", "rad/s", "Gyroscope.csv"),
    ("gyro", "rad/s", "Gyroscope.csv"),
)


def _is_sensor_logger(path, low, free_text):
    # its exports lead with 'time,seconds_elapsed'; earlier ones (Metadata.csv version 2, 2021) wrote 'time,z,y,x'
    return (low[:2] == ["time", "seconds_elapsed"] and {"x", "y", "z"} <= set(low)) or low == ["time", "z", "y", "x"]


def _sensor_logger_platform(path):
    """'ios' or 'android' from the Metadata.csv that Sensor Logger writes beside each sensor file, else None."""
    meta = os.path.join(os.path.dirname(str(path)), "Metadata.csv")
    try:
        with open(meta, encoding="utf-8", errors="replace") as f:
            head, row = f.readline().strip().split(","), f.readline().strip().split(",")
    except OSError:
        return None
    if "platform" in head and len(row) == len(head):
        p = row[head.index("platform")].strip().lower()
        return p if p in ("ios", "android") else None
    return None


def _sensor_logger_units(path, names, low, units, history):
    base = re.sub(r"[^a-z]", "", os.path.basename(str(path)).lower())
    if "uncalibrated" in base and "accelerometer" in base:
        platform = _sensor_logger_platform(path)
        unit = {"ios": "g", "android": "m/s^2"}.get(platform)
        if unit is None:
            history.append(
                "Sensor Logger AccelerometerUncalibrated.csv: x, y, z are in g on iOS and m/s^2 on Android, and "
                f"no Metadata.csv beside the file says the platform; x, y, z keep no unit (pass {spell('units')})"
            )
            return {}
        history.append(
            f"Sensor Logger AccelerometerUncalibrated.csv on {platform} (Metadata.csv beside it): x, y, z in "
            f"{unit}; pass {spell('units')} to override"
        )
        return {j: unit for j, n in enumerate(low) if n in ("x", "y", "z") and units[j] is None}
    for key, unit, app_name in _SENSOR_LOGGER_FILES:
        if key in base:
            history.append(
                f"Sensor Logger export ('time,...,z,y,x'): x, y, z in {unit}, as the app "
                f"documents for {app_name} (file name); pass {spell('units')} to override"
            )
            return {j: unit for j, n in enumerate(low) if n in ("x", "y", "z") and units[j] is None}
    history.append(
        "Sensor Logger export ('time,...,z,y,x'): the file name does not say the "
        f"sensor, so x, y, z keep no unit; pass {spell('units')} (e.g. m/s^2 for the accelerometer)"
    )
    return {}


_PTB_UNITS = {"ax": "m/s^2", "ay": "m/s^2", "az": "m/s^2", "wx": "rad/s", "wy": "rad/s", "wz": "rad/s"}


def _is_physics_toolbox(path, low, free_text):
    return {"gfx", "gfy", "gfz"} <= set(low)


def _physics_toolbox_units(path, names, low, units, history):
    out = {j: _PTB_UNITS[n] for j, n in enumerate(low) if n in _PTB_UNITS and units[j] is None}
    if out:
        history.append(
            "Physics Toolbox Sensor Suite export (gFx, gFy, gFz): "
            + ", ".join(f"{names[j]} in {u}" for j, u in out.items())
            + f" as the app documents; pass {spell('units')} to override"
        )
    return out


_PICOQUAKE = re.compile(r"^[ag]_[xyz]$")


def _is_picoquake(path, low, free_text):
    return any("picoquake" in t.lower() for t in free_text)


def _picoquake_units(path, names, low, units, history):
    out = {j: ("g" if n[0] == "a" else "deg/s") for j, n in enumerate(low) if _PICOQUAKE.match(n) and units[j] is None}
    if out:
        history.append(
            "PicoQuake export ('# PLab PicoQuake Data'): a_x, a_y, a_z in g and g_x, g_y, g_z in "
            f"deg/s, as PLab documents; pass {spell('units')} to override"
        )
    return out


_SCIENCE_JOURNAL_UNITS = {  # Science Journal sensor ids -> unit (the app's sensor documentation)
    "accx": "m/s^2",
    "accy": "m/s^2",
    "accz": "m/s^2",
    "linearaccelerometersensor": "m/s^2",
    "magneticrotationsensor": "uT",
    "ambientlightsensor": "lx",
    "barometersensor": "hPa",
    "decibelsource": "dB",
    "pitchsensor": "Hz",
}


def _is_science_journal(path, low, free_text):
    return bool(low) and low[0] == "relative_time"


def _science_journal_units(path, names, low, units, history):
    out = {j: _SCIENCE_JOURNAL_UNITS[n] for j, n in enumerate(low) if n in _SCIENCE_JOURNAL_UNITS and units[j] is None}
    history.append(
        "Google Science Journal export ('relative_time' in ms, one column per sensor id, a row whenever a "
        "sensor updates)" + (": " + ", ".join(f"{names[j]} in {u}" for j, u in out.items()) if out else "")
    )
    return out


_ANDROID_FILES = (("acc", "m/s^2", "accelerometer"), ("grav", "m/s^2", "gravity"), ("gyro", "rad/s", "gyroscope"))


def _is_android_sensor_event(path, low, free_text):
    return bool(low) and low[0] in ("timestamp", "timestamp_ns", "elapsedrealtimenanos") and "accuracy" in low


def _android_units(path, names, low, units, history):
    base = os.path.basename(str(path)).lower()
    for key, unit, what in _ANDROID_FILES:
        if key in base:
            history.append(
                f"Android SensorEvent log ('timestamp' in ns since boot, 'accuracy' a status): x, y, z in {unit} "
                f"as Android documents for the {what} (file name); pass {spell('units')} to override"
            )
            return {j: unit for j, n in enumerate(low) if n in ("x", "y", "z") and units[j] is None}
    history.append(
        f"Android SensorEvent log: the file name does not say the sensor, x, y, z keep no unit ({spell('units')})"
    )
    return {}


#: the logger table; ``recognise`` is tried in this order and the first that claims a file decides its units
PROFILES: tuple[LoggerProfile, ...] = (
    LoggerProfile(
        "Sensor Logger",
        "Kelvin Choi, Sensor Logger for Android/iOS: export documentation, one CSV per sensor",
        recognise=_is_sensor_logger,
        column_units=_sensor_logger_units,
        facts="header 'time,seconds_elapsed,z,y,x' ('time,z,y,x' in its earlier exports): time is Unix epoch in ns (UTC, not "
        "since boot), seconds_elapsed a second clock; the axes carry no unit, which the app documents per sensor file: "
        "Accelerometer.csv (gravity removed), TotalAcceleration.csv, Gravity.csv in m/s^2, Gyroscope.csv in "
        "rad/s; AccelerometerUncalibrated.csv in g on iOS and m/s^2 on Android (Metadata.csv's platform)",
    ),
    LoggerProfile(
        "Physics Toolbox Sensor Suite",
        "Vieyra Software, Physics Toolbox Sensor Suite: CSV export",
        recognise=_is_physics_toolbox,
        column_units=_physics_toolbox_units,
        bare_headers=((r"t?gf[xyz]?", "g", "'{header}' is a g-force column (Physics Toolbox), values in g"),),
        facts="header 'time,gFx,gFy,gFz,ax,...,wx,...': gF* in g, linear acceleration ax ay az in m/s^2, "
        "gyroscope wx wy wz in rad/s; a leading empty line, a trailing comma, and a row whenever any "
        "sensor updates (values held between updates)",
    ),
    LoggerProfile(
        "PicoQuake",
        "PLab PicoQuake: docs/acquisition_data.md",
        recognise=_is_picoquake,
        column_units=_picoquake_units,
        rate_keys=(r"^data[\s_-]*rate$",),
        facts="a '# PLab PicoQuake Data' comment, columns 'count,a_x,...,g_z': a_* in g, g_* in deg/s; the rate "
        "is data_rate inside the '# Config: data_rate = 2000.0 Hz, filter = 488 Hz' comment",
    ),
    LoggerProfile(
        "GCDC",
        "Gulf Coast Data Concepts X16/X2 loggers: user manual, CSV file format",
        header_keys=("headers", "header", "columns"),
        facts="';'-commented metadata lines (Title, Start_time, SampleRate, 'Scale, 2048, counts per g'), the "
        "column names on a ';Headers, time,Ax,Ay,Az' line and no header row; values in counts",
    ),
    LoggerProfile(
        "enDAQ",
        "Midé enDAQ sensors: enDAQ Lab / IDE to CSV export",
        bracket_units=((r"(\d+(?:\.\d+)?)\s*g", "g", "'({text})' read as a {0} g sensor range, values in g"),),
        facts="quoted key/value metadata lines above the header; channel headers 'X (100g)' name the "
        "sensor's range, the values are in g",
    ),
    LoggerProfile(
        "Arduino",
        "Arduino reference: millis(), micros()",
        clock_columns={"micros": ("us", 1e-6), "millis": ("ms", 1e-3)},
        facts="sketches print an integer clock column with no unit; one named micros or millis is in us or ms",
    ),
    LoggerProfile(
        "Google Science Journal",
        "Google Science Journal (Arduino Science Journal): CSV export of a trial",
        recognise=_is_science_journal,
        column_units=_science_journal_units,
        clock_columns={"relative_time": ("ms", 1e-3)},
        facts="header 'relative_time,AccX,AccY,AccZ,...': relative_time in ms from the start, one column per "
        "sensor id; a row whenever any sensor updates, holding only that sensor's value (the other cells "
        "empty): each channel keeps its own samples (NaN elsewhere, attr sparse); the 2016 format "
        "'timestamp,value' has epoch ms",
    ),
    LoggerProfile(
        "Android SensorEvent logger",
        "Android SensorEvent reference: timestamp in ns (SystemClock.elapsedRealtimeNanos base), values in SI, "
        "accuracy a status (0-3)",
        recognise=_is_android_sensor_event,
        column_units=_android_units,
        clock_columns={"elapsedrealtimenanos": ("ns", 1e-9), "timestamp_ns": ("ns", 1e-9)},
        facts="header 'timestamp,x,y,z,accuracy': timestamp counts ns since boot (not an epoch); accuracy is a "
        "status column, never a channel to analyse",
    ),
    LoggerProfile(
        "PASCO SPARKvue / Capstone",
        "PASCO SPARKvue and Capstone: CSV export",
        facts="header 'Time (s) Run #1,Acceleration (m/s²) Run #1': the run goes to the name; values "
        "quantised to the sensor's resolution (0.1 m/s^2 at 500 Hz): repeated values are quantisation, "
        "not holds (vibkit.io.timebase.quantum)",
    ),
    LoggerProfile(
        "MetaWear",
        "MbientLab MetaBase: CSV export",
        facts="header 'epoc (ms),timestamp (-0500),elapsed (s),x-axis (g),...' states every unit; the text stamp "
        "'2022-08-05T15.26.13.153' is not read as time while the epoch column is there",
    ),
    LoggerProfile(
        "phyphox",
        "RWTH Aachen phyphox: CSV export",
        facts='header \'"Time (s)","Acceleration x (m/s^2)"\' states every unit; the first sample may be '
        "written twice at t = 0 (handled by vibkit.io.timebase.check_order)",
    ),
)


def app_units(path, names, units, free_text, history):
    """Units of columns that a recognised logger leaves unnamed: {column index: unit text}.

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
    for p in PROFILES:
        if p.recognise is not None and p.recognise(path, low, free_text):
            return p.column_units(path, names, low, units, history)
    return {}


def header_unit(header: str, text: str | None = None):
    """(unit, note) a logger profile gives a header cell, or None.

    With ``text`` (the unit text inside the header's brackets) the profiles' ``bracket_units`` are
    tried; without it the whole ``header`` is matched against their ``bare_headers``.
    """
    for p in PROFILES:
        if text is not None:
            for pattern, unit, note in p.bracket_units:
                m = re.fullmatch(pattern, text, re.IGNORECASE)
                if m:
                    return unit, note.format(*m.groups(), text=text)
        else:
            for pattern, unit, note in p.bare_headers:
                if re.fullmatch(pattern, header, re.IGNORECASE):
                    return unit, note.format(header=header)
    return None


def rate_key_patterns() -> tuple[str, ...]:
    """The profiles' regular expressions for metadata keys that hold the sample rate."""
    return tuple(k for p in PROFILES for k in p.rate_keys)


def header_keys() -> frozenset:
    """Metadata keys (lower case) whose value lists the column names, from every profile."""
    return frozenset(k for p in PROFILES for k in p.header_keys)


def clock_units() -> dict:
    """Time column names (lower case) of clock functions -> (unit text, factor to seconds), from every profile."""
    return {k: v for p in PROFILES for k, v in p.clock_columns.items()}
