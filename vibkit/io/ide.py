"""enDAQ / Slam Stick ``.ide`` recordings (EBML with the DocType ``mide``), read by idelib (the ``ide`` extra).

An ``.ide`` file holds several sensor channels (the main accelerometer, a DC accelerometer, pressure and
temperature, orientation ...), each with its own sample clock and its subchannels (``X``, ``Y``, ``Z``).
By default the channel read is the accelerometer channel with the most samples (the recorder's main one),
all its subchannels, named ``channel/subchannel`` (``Main Acceleration/X``) in the unit the recorder states
(``g``, converted to m/s^2); ``channel=`` names other subchannels, of one channel at a time.  The time base
is the recorder's own time stamps (microseconds, which jitter by a few percent of a period), the sample rate
their mean step; the recording's start is the session's UTC start where the file gives it.  Calibration is
idelib's (the recorder's polynomials, applied as it reads).
"""

from __future__ import annotations

import io

import numpy as np

from .errors import RecordingError
from .sampled import Column, assemble, select_columns

__all__ = ["sniff_ide", "read_ide"]

_EBML = b"\x1a\x45\xdf\xa3"


def sniff_ide(probe) -> bool:
    """An EBML file whose DocType is ``mide`` (in its first bytes), or the ``.ide`` suffix."""
    head = probe.head
    return (head[:4] == _EBML and b"mide" in head[:64]) or probe.suffix == ".ide"


def _is_acceleration(channel) -> bool:
    return any(str(s.units[0]).lower() == "acceleration" for s in channel.subchannels)


def read_ide(path, data, options):
    """An enDAQ ``.ide`` file (see the module docstring)."""
    if data[:4] != _EBML:
        raise RecordingError(path, None, "not an enDAQ .ide file (no EBML header); expected a recorder's .ide file")
    try:
        import idelib
    except ImportError:
        raise RecordingError(path, None, "reading enDAQ .ide files needs idelib: pip install 'vibkit[ide]'") from None
    try:
        doc = idelib.importer.openFile(io.BytesIO(data), quiet=True)
        idelib.importer.readData(doc)
    except Exception as exc:  # idelib raises what its EBML parser meets (ValueError, KeyError, IOError ...)
        raise RecordingError(path, None, f"cannot read as an enDAQ .ide file: {type(exc).__name__}: {exc}") from None
    try:
        return _recording(path, data, doc, options)
    finally:
        doc.close()


def _recording(path, data, doc, options):
    per_channel, columns, times = {}, [], {}
    for ch in sorted(doc.channels.values(), key=lambda c: c.id):
        session = ch.getSession()
        if len(session) < 2:
            continue  # a channel that recorded nothing (or one sample: no time base)
        arr = np.atleast_2d(session.arraySlice())
        cols = []
        for k, sub in enumerate(ch.subchannels):
            name = f"{ch.name}/{sub.name}"
            attrs = {"source_name": name, "ide_channel": int(ch.id), "ide_quantity": str(sub.units[0])}
            cols.append(Column(name, np.asarray(arr[k + 1], dtype=np.float64), str(sub.units[1]) or None, attrs))
        per_channel[ch.id] = (ch, cols)
        columns += cols
        times[ch.id] = np.asarray(arr[0], dtype=np.float64) * 1e-6  # idelib's time stamps are in microseconds
    if not columns:
        raise RecordingError(path, None, "enDAQ .ide file without samples; expected a recording")
    want = options.get("channel")
    if want is None:
        acc = [cid for cid, (ch, _) in per_channel.items() if _is_acceleration(ch)]
        pool = acc or list(per_channel)
        cid = max(pool, key=lambda c: (times[c].size, -c))
        chosen = per_channel[cid][1]
        history = [
            f"enDAQ .ide file read with idelib: {len(per_channel)} channel(s) with samples; read "
            f"'{per_channel[cid][0].name}' (the accelerometer with the most samples; channel= names others)"
        ]
    else:
        chosen = select_columns(path, columns, want)
        ids = sorted({c.attrs["ide_channel"] for c in chosen})
        if len(ids) > 1:
            raise RecordingError(
                path,
                None,
                "channel= names subchannels of channels with their own clocks ("
                + ", ".join(f"'{per_channel[i][0].name}'" for i in ids)
                + "); read them one channel at a time",
            )
        cid = ids[0]
        history = [f"enDAQ .ide file read with idelib: channel '{per_channel[cid][0].name}', {len(chosen)} read"]
    info = doc.recorderInfo or {}
    meta = [("format", "enDAQ IDE")]
    for key, label in (("ProductName", "recorder"), ("PartNumber", "recorder_part_number")):
        if info.get(key):
            meta.append((label, str(info[key])))
    if info.get("RecorderSerial") is not None:
        meta.append(("recorder_serial", str(info["RecorderSerial"])))
    start = getattr(doc.sessions[-1], "utcStartTime", None) if getattr(doc, "sessions", None) else None
    if start:
        t0 = np.datetime64(int(start), "s").astype("datetime64[us]") + np.timedelta64(
            int(round(times[cid][0] * 1e6)), "us"
        )
        meta.append(("start_time", str(t0) + "Z"))
    opts = dict(options, channel=None)  # chosen here; assemble would match the names again
    return assemble(
        path,
        data,
        reader="vibkit.io.ide",
        columns=chosen,
        options=opts,
        history=history,
        time=times[cid] - times[cid][0],
        metadata=meta,
    )
