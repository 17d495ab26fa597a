"""Phone exports of several sensors, one file each: a folder (ADVIO's ``iphone/``, an unpacked phyphox or
Sensor Logger export) or a zip archive of such files, read as one recording.

Each sensor file is read by the text reader as it comes (headerless with a first column in seconds, as
ADVIO writes; or with a header row, as phyphox and Sensor Logger write).  The sensors keep their own
clocks in the files; the recording is laid on the accelerometer's time stamps, and every other sensor is
joined onto them by linear interpolation where a computation needs them together (held at its first and
last value outside its own span, said in ``history``).  Each channel's native rate is in its attrs
(``native_rate_hz``).

=================  ====================================================  ==============================
sensor             file names (case and separators ignored)               channels, quantity, SI unit
=================  ====================================================  ==============================
accelerometer      accelerometer, accel, acc, acceleration, totalacc...   ``acc_x/y/z``, acceleration,
                                                                          m/s^2 (g when the magnitude
                                                                          reads about 1)
gyroscope          gyro, gyroscope, rotationrate                          ``gyro_x/y/z``, angular
                                                                          velocity, rad/s
barometer          barometer, pressure                                    ``pressure`` [Pa] and
                                                                          ``altitude`` [m] where given
gravity            gravity                                                added to an accelerometer that
                                                                          has gravity removed
=================  ====================================================  ==============================

Gravity is the steady part of an accelerometer's reading (a 2 s running mean near 9.81 m/s^2 or 1 g that
carries most of the magnitude).  Where it is missing (Sensor Logger's ``Accelerometer.csv`` and phyphox's
"Linear Acceleration" have it removed) and the export holds the phone's gravity estimate (``Gravity.csv``),
the two are added: what a phone with gravity would have read, which the walking test of a phone's rides
(``vibkit.signal.stillness``) is made for; said in ``history``.

Other files (magnetometer, location, ground truth) are listed in ``history`` and left out.
"""

from __future__ import annotations

import io
import os
import re
import unicodedata
import zipfile

import numpy as np
from scipy import ndimage

from .errors import RecordingError
from .recording import Channel, build_recording
from .text.csv import read_csv

__all__ = ["PHONE_SENSORS", "phone_sensor_files", "is_phone_export", "read_phone_export"]

#: sensor -> the file-name stems that hold it (lower case, letters and digits only)
PHONE_SENSORS = {
    "accelerometer": (
        "accelerometer",
        "accel",
        "acc",
        "acceleration",
        "totalacceleration",
        "accelerometeruncalibrated",
    ),
    "gyroscope": ("gyro", "gyroscope", "rotationrate", "gyroscopeuncalibrated"),
    "barometer": ("barometer", "pressure"),
    "gravity": ("gravity",),
}
_SUFFIXES = (".csv", ".txt", ".tsv")
_G = 9.80665


def _stem(name: str) -> str:
    base = os.path.basename(name.rstrip("/"))
    for s in _SUFFIXES:
        if base.lower().endswith(s):
            base = base[: -len(s)]
    return re.sub(r"[^a-z0-9]", "", base.lower())


#: phyphox names the one file of a single-sensor experiment after its export set ("Raw Data.csv" in English,
#: "Rohdaten.csv" in German ...); its header says which sensor, in the language of the phone: the word for each
#: sensor's quantity in English, German, French, Spanish, Italian, Portuguese, Dutch and Polish (accents dropped)
_RAW_HEADERS = (
    (
        (
            "acceleration",
            "beschleunigung",
            "accelerazione",
            "aceleracion",
            "aceleracao",
            "versnelling",
            "przyspieszenie",
        ),
        "accelerometer",
    ),
    (("gyroscope", "gyroskop", "giroscopio", "gyroscoop", "zyroskop", "rotation rate", "drehrate"), "gyroscope"),
    (("pressure", "druck", "druk", "pression", "presion", "pressione", "pressao", "cisnienie"), "barometer"),
)


def _header_words(head: bytes) -> str:
    """The first line of a file's head in lower case, accents dropped (``Accélération`` -> ``acceleration``)."""
    line = head[:512].decode("utf-8", "replace").splitlines()[0] if head else ""
    return unicodedata.normalize("NFKD", line.lower()).encode("ascii", "ignore").decode()


def _is_phyphox(names) -> bool:
    """Whether the names hold phyphox's ``meta/`` folder (``meta/device.csv``, ``meta/time.csv``; a folder's
    listing names the folder ``meta`` itself)."""
    return any("meta" in re.split(r"[\\/]", name.rstrip("/").lower()) for name in names)


def phone_sensor_files(names, head=None, phyphox=None):
    """{sensor: name} for the names (paths or zip members) that hold a phone sensor; others left out.

    ``head(name) -> bytes`` (the file's first bytes) sorts phyphox's data file (``Raw Data.csv``, ``Rohdaten.csv``
    ...: any name that is no sensor's) by its header (acceleration, gyroscope, pressure, in the phone's language)
    where the export carries phyphox's ``meta/`` folder (``phyphox``: whether it does; default:
    read from the names)."""
    found = {}
    phyphox = head is not None and (_is_phyphox(names) if phyphox is None else phyphox)
    for name in sorted(names):
        if not name.lower().endswith(_SUFFIXES) or "__macosx" in name.lower():
            continue
        stem = _stem(name)
        known = any(stem in stems for stems in PHONE_SENSORS.values())
        if phyphox and not known and "meta" not in re.split(r"[\\/]", name.lower()):
            first = _header_words(head(name))
            stem = next((PHONE_SENSORS[s][0] for words, s in _RAW_HEADERS if any(w in first for w in words)), stem)
        for sensor, stems in PHONE_SENSORS.items():
            if stem in stems and sensor not in found:
                found[sensor] = name
    return found


def is_phone_export(names, head=None) -> bool:
    """Whether these file names make a phone export: an accelerometer file and at least one other sensor's, or an
    accelerometer file alone beside phyphox's ``meta/`` folder (``head`` as for :func:`phone_sensor_files`)."""
    found = phone_sensor_files(names, head)
    return "accelerometer" in found and (len(found) >= 2 or _is_phyphox(names))


#: the reader options that apply to every sensor file of an export alike (the others name one file's columns)
_PER_FILE_OPTIONS = ("encoding", "delimiter", "decimal", "repair_time", "time_unit", "gap_factor", "date_order")


def _read_one(label, data, options):
    """One sensor file's bytes, read by the text reader (each phone app writes text)."""
    kw = {k: v for k, v in options.items() if k in _PER_FILE_OPTIONS and v is not None}
    return read_csv(label, data, **kw)


#: the running mean that gravity, and nothing a person does with a phone, holds steady [s]
_STEADY_S = 2.0


def _steady(vals, t):
    """(median magnitude of the running mean over :data:`_STEADY_S`, median ``|a|``) of the three axes ``vals``."""
    a = np.vstack(vals)
    ok = np.all(np.isfinite(a), axis=0)
    if ok.sum() < 3:
        return 0.0, 0.0
    a = a[:, ok]
    dt = np.diff(np.asarray(t, dtype=float)[ok])
    step = float(np.median(dt)) if dt.size else 0.0
    w = max(int(round(_STEADY_S / step)), 1) if step > 0 else 1
    steady = float(np.median(np.sqrt(np.sum(ndimage.uniform_filter1d(a, w, axis=1, mode="nearest") ** 2, axis=0))))
    return steady, float(np.median(np.sqrt(np.sum(a**2, axis=0))))


def _gravity_in(vals, t):
    """How the three axes ``vals`` carry gravity: "m/s^2" or "g" (the unit its magnitude tells), "removed", or None
    (a steady part that is no gravity in either unit).

    Gravity is the steady part of the reading: the running mean over :data:`_STEADY_S` carries most of the magnitude
    (its median at least 0.7 of ``|a|``'s) and reads 7-12.5 (m/s^2) or 0.7-1.3 (g).  With gravity removed the
    running mean is what the phone's motion and the sensor's bias leave: under half of ``|a|``, or under 0.5
    (on the Sensor Logger walks tried, 0.12-0.25 of ``|a|``; a phone in a pocket: 1.0 m/s^2 of 3.95; lying still:
    0.014 of 0.03 m/s^2)."""
    steady, mag = _steady(vals, t)
    if mag > 0 and steady >= 0.7 * mag:
        if 7.0 <= steady <= 12.5:
            return "m/s^2"
        if 0.7 <= steady <= 1.3:
            return "g"
    if steady < 0.5 * mag or steady < 0.5:
        return "removed"
    return None


def _axes(ds, label, what):
    names = [v for v in ds.data_vars if v != "segment" and ds[v].dims == ("time",)]
    if len(names) < 3:
        raise RecordingError(label, None, f"{len(names)} channel(s); expected the {what}'s three axes x, y, z")
    by_axis = {}
    for v in names:
        m = re.search(r"(?:^|[^a-z])([xyz])(?:[^a-z]|$)", v.lower())
        if m and m.group(1) not in by_axis:
            by_axis[m.group(1)] = v
    if len(by_axis) == 3:
        return [by_axis[a] for a in "xyz"]
    return names[:3]


def _si(ds, names, label, quantity, history):
    """The three axes in SI: their units as the file states them, else from gravity (accelerometer).

    Returns ``(values, unit, gravity)``: ``gravity`` False for an accelerometer whose reading has gravity removed
    (see :func:`_gravity_in`), True otherwise."""
    vals = [np.asarray(ds[v].values, dtype=float) for v in names]
    units = [ds[v].attrs.get("units", "unknown") for v in names]
    if quantity == "acceleration":
        t = np.asarray(ds["time"].values, dtype=float)
        if all(ds[v].attrs.get("quantity") == "acceleration" for v in names):
            return vals, "m/s^2", _gravity_in(vals, t) != "removed"
        mag = float(np.nanmedian(np.sqrt(sum(x**2 for x in vals))))
        how = _gravity_in(vals, t) if all(u in ("unknown", "m/s^2") for u in units) else None
        if how == "m/s^2":
            history.append(f"{label}: no units; |a| reads {mag:.3g}, gravity its steady part, so m/s^2")
            return vals, "m/s^2", True
        if how == "g":
            history.append(f"{label}: no units; |a| reads {mag:.3g}, gravity its steady part, so g (scaled to m/s^2)")
            return [x * _G for x in vals], "m/s^2", True
        if how == "removed" and mag < 30.0:
            history.append(
                f"{label}: no units and no steady part (|a| reads {mag:.3g}): acceleration with gravity removed, "
                "taken as m/s^2"
            )
            return vals, "m/s^2", False
        raise RecordingError(
            label,
            None,
            f"|a| reads {mag:.3g} in units {units[0]!r}, its steady part no gravity; expected an accelerometer in "
            "m/s^2 or g",
        )
    if all(u in ("rad/s", "unknown") for u in units):
        if "unknown" in units:
            history.append(f"{label}: no units; read as rad/s")
        return vals, "rad/s", True
    raise RecordingError(label, None, f"units {units[0]!r}; expected a gyroscope in rad/s")


def _barometer(ds, label, history):
    """(pressure [Pa] or None, altitude [m] or None)."""
    pressure = altitude = None
    for v in [v for v in ds.data_vars if v != "segment"]:
        x = np.asarray(ds[v].values, dtype=float)
        low, unit = v.lower(), ds[v].attrs.get("units", "unknown")
        med = float(np.nanmedian(x))
        if "alt" in low:
            altitude = x
        elif pressure is None and ("press" in low or unit in ("Pa", "hPa", "kPa") or 50 <= med <= 1.2e5):
            scale = {"Pa": 1.0, "hPa": 100.0, "kPa": 1000.0}.get(unit)
            if scale is None:  # no unit: the range tells kPa (ADVIO), hPa (phyphox, Sensor Logger) or Pa
                scale = 1000.0 if 50 <= med <= 120 else 100.0 if 500 <= med <= 1200 else 1.0
            pressure = x * scale
        elif altitude is None and pressure is not None and np.nanmax(np.abs(x)) < 1e4:
            altitude = x  # ADVIO: pressure [kPa], relative altitude [m]
    if altitude is not None:
        history.append(f"{label}: relative altitude [m] from the phone")
    return pressure, altitude


def phone_export_folder(path, head):
    """The folder of a phone export that ``path`` (a folder) names: itself where it holds phone sensor files, else its
    one subfolder that holds an accelerometer's file (ADVIO's sequence folder: ``iphone/`` beside ``ground-truth/``,
    ``pixel/`` and ``tango/``); None where neither does.  ``head(folder, name) -> bytes`` as for
    :func:`phone_sensor_files`.  A folder with several such subfolders is refused, naming them."""
    listing = os.listdir(path)
    names = [n for n in listing if os.path.isfile(os.path.join(path, n))]
    if phone_sensor_files(names, lambda name: head(path, name), phyphox=_is_phyphox(listing)):
        return path
    subs = []
    for d in sorted(listing):
        sub = os.path.join(path, d)
        if os.path.isdir(sub) and not d.startswith("."):
            try:
                inner = os.listdir(sub)
            except OSError:
                continue
            files = [n for n in inner if os.path.isfile(os.path.join(sub, n))]
            found = phone_sensor_files(files, lambda name, sub=sub: head(sub, name), phyphox=_is_phyphox(inner))
            if "accelerometer" in found:
                subs.append(d)
    if len(subs) > 1:
        raise RecordingError(
            path,
            None,
            f"is a folder of {len(subs)} phone exports ({', '.join(subs)}): give one of them as the recording",
        )
    return os.path.join(path, subs[0]) if subs else None


def read_phone_export(path, options=None):
    """Read a folder or zip archive of phone sensor files as one recording (see the module's notes)."""
    options = dict(options or {})
    path = os.fspath(path)
    history = []
    if os.path.isdir(path):
        names = [os.path.join(path, n) for n in os.listdir(path) if os.path.isfile(os.path.join(path, n))]
        members = {n: None for n in names}
        kind = "folder"
        listing = os.listdir(path)

        def head(name):
            with open(name, "rb") as f:
                return f.read(512)

    else:
        with open(path, "rb") as f:
            blob = f.read()
        try:
            zf = zipfile.ZipFile(io.BytesIO(blob))
        except zipfile.BadZipFile as exc:
            raise RecordingError(path, None, f"zip archive that cannot be read ({exc})") from None
        members = {i.filename: zf for i in zf.infolist() if not i.is_dir()}
        kind = "zip archive"
        listing = list(members)

        def head(name):
            with zf.open(name) as f:
                return f.read(512)

    found = phone_sensor_files(members, head, phyphox=_is_phyphox(listing))
    if "accelerometer" not in found:
        listed = ", ".join(os.path.basename(n) for n in sorted(members)[:8]) or "none"
        raise RecordingError(
            path, None, f"{kind} with no accelerometer file ({listed}); expected accelerometer.csv (and gyro.csv ...)"
        )
    skipped = sorted(os.path.basename(n) for n in members if n not in found.values())
    if skipped:
        history.append(f"{kind}: not read: " + ", ".join(skipped))

    blobs = []  # the sensor files' bytes, hashed together into the recording's sha256

    def load(sensor):
        name = found[sensor]
        label = name if kind == "folder" else f"{path}:{name}"
        if kind == "folder":
            with open(name, "rb") as f:
                data = f.read()
        else:
            data = members[name].read(name)
        blobs.append(data)
        return _read_one(label, data, options), label

    acc, acc_label = load("accelerometer")
    t = np.asarray(acc["time"].values, dtype=float)
    channels = []
    vals, unit, with_gravity = _si(acc, _axes(acc, acc_label, "accelerometer"), acc_label, "acceleration", history)
    rate_acc = float(acc.attrs.get("sample_rate_hz", np.nan))
    held = set()

    def joined(ds, label, x):
        ts = np.asarray(ds["time"].values, dtype=float)
        if (ts[0] > t[0] or ts[-1] < t[-1]) and label not in held:
            held.add(label)
            history.append(
                f"{label}: spans {ts[0]:.3f}-{ts[-1]:.3f} s, the accelerometer {t[0]:.3f}-{t[-1]:.3f} s: held at its "
                "ends outside its span"
            )
        return np.interp(t, ts, x)

    if not with_gravity and "gravity" in found:
        grav, label = load("gravity")
        gnames = _axes(grav, label, "gravity sensor")
        gvals = [np.asarray(grav[v].values, dtype=float) for v in gnames]
        gunit = _gravity_in(gvals, np.asarray(grav["time"].values, dtype=float))
        if gunit not in ("m/s^2", "g"):
            raise RecordingError(
                label, None, "no steady magnitude near 9.81 m/s^2 or 1 g; expected the phone's gravity"
            )
        scale = _G if gunit == "g" else 1.0
        vals = [x + scale * joined(grav, label, g) for x, g in zip(vals, gvals)]
        history.append(
            f"{acc_label}: gravity removed; {os.path.basename(label)} (in {gunit}) added back, laid on its time stamps, "
            "as a phone with gravity reads"
        )
    elif not with_gravity:
        history.append(
            f"{acc_label}: gravity removed and no gravity file beside it: |a| holds no gravity, and walking's step "
            "shows at twice its rate in it"
        )
    for ax, x in zip("xyz", vals):
        channels.append(Channel(f"acc_{ax}", x, unit, f"accelerometer {ax}", "acceleration"))
    natives = {f"acc_{ax}": rate_acc for ax in "xyz"}

    if "gyroscope" in found:
        gyr, label = load("gyroscope")
        gvals, gunit, _ = _si(gyr, _axes(gyr, label, "gyroscope"), label, "angular_velocity", history)
        for ax, x in zip("xyz", gvals):
            channels.append(Channel(f"gyro_{ax}", joined(gyr, label, x), gunit, f"gyroscope {ax}", "other"))
            natives[f"gyro_{ax}"] = float(gyr.attrs.get("sample_rate_hz", np.nan))
        history.append(f"{label}: joined onto the accelerometer's time stamps by linear interpolation")
    if "barometer" in found:
        bar, label = load("barometer")
        pressure, altitude = _barometer(bar, label, history)
        rate = float(bar.attrs.get("sample_rate_hz", np.nan))
        if pressure is not None:
            channels.append(Channel("pressure", joined(bar, label, pressure), "Pa", "air pressure", "other"))
            natives["pressure"] = rate
        if altitude is not None:
            channels.append(Channel("altitude", joined(bar, label, altitude), "m", "relative altitude", "other"))
            natives["altitude"] = rate
    ds = build_recording(
        time=t,
        channels=channels,
        segment=None,
        path=path,
        data_bytes=b"".join(blobs),
        reader="vibkit.io.phone",
        sample_rate_hz=rate_acc,
        history=[f"{kind} of phone sensor files: " + ", ".join(f"{k} {os.path.basename(v)}" for k, v in found.items())]
        + history,
        metadata={"phone_sensors": ", ".join(found)},
    )
    for name, rate in natives.items():
        ds[name].attrs["native_rate_hz"] = rate
        ds[name].attrs["sensor"] = name.split("_")[0].replace("acc", "accelerometer").replace("gyro", "gyroscope")
    for name in ("pressure", "altitude"):
        if name in ds.data_vars:
            ds[name].attrs["sensor"] = "barometer"
    ds.attrs["source_file"] = path
    return ds
