"""NI TDMS files (LabVIEW, DIAdem, NI DAQ): channels of groups, read by npTDMS (the ``tdms`` extra).

Each channel with a waveform time base (the properties ``wf_increment`` [s] and
``wf_start_offset`` [s], as NI DAQmx and LabVIEW write them) is one channel named
``group/channel``, in the unit of its ``unit_string`` property (converted to SI; ``units=``
overrides); ``wf_start_time`` becomes the recording's start time.  Channels of one file that
are sampled differently are read one group or channel at a time with ``channel=``; a channel
without ``wf_increment`` needs ``sample_rate=``.
"""

from __future__ import annotations

import io

import numpy as np

from ..runtime.reader_options import spell
from .errors import RecordingError
from .sampled import Column, assemble, select_columns

__all__ = ["sniff_tdms", "read_tdms"]


def sniff_tdms(probe) -> bool:
    """A TDMS file (lead-in ``TDSm``), its index (``TDSh``, ``.tdms_index``) or the ``.tdms`` suffix."""
    return probe.head[:4] in (b"TDSm", b"TDSh") or probe.suffix in (".tdms", ".tdms_index")


def read_tdms(path, data, options):
    """A TDMS file (see the module docstring)."""
    if data[:4] == b"TDSh":
        raise RecordingError(
            path, None, "a TDMS index file (.tdms_index) holds no samples; expected the .tdms file it indexes"
        )
    try:
        from nptdms import TdmsFile
    except ImportError:
        raise RecordingError(path, None, "reading TDMS files needs npTDMS: pip install 'vibkit[tdms]'") from None
    try:
        f = TdmsFile.read(io.BytesIO(data))
    except Exception as exc:  # npTDMS raises ValueError/KeyError/struct.error for what it cannot parse
        raise RecordingError(path, None, f"cannot read as a TDMS file: {type(exc).__name__}: {exc}") from None
    cols, bases = [], {}
    for g in f.groups():
        for ch in g.channels():
            vals = np.asarray(ch[:])
            if vals.dtype.kind not in "iufb" or vals.size == 0:
                continue
            p = ch.properties
            name = f"{g.name}/{ch.name}"
            attrs = {"source_name": name, "tdms_group": g.name, "tdms_channel": ch.name}
            c = Column(name, vals.astype(np.float64), p.get("unit_string"), attrs)
            cols.append(c)
            inc = p.get("wf_increment")
            bases[name] = (
                float(inc) if inc else None,
                float(p.get("wf_start_offset", 0.0) or 0.0),
                p.get("wf_start_time"),
            )
    if not cols:
        raise RecordingError(path, None, "TDMS file without numeric channels; expected waveform channels")
    chosen = select_columns(path, cols, options.get("channel"))
    b0 = bases[chosen[0].name]
    for c in chosen[1:]:
        b = bases[c.name]
        if c.values.size != chosen[0].values.size or (b[0] or 0) != (b0[0] or 0):
            raise RecordingError(
                path,
                None,
                f"channel {c.name!r} ({c.values.size} samples, increment {b[0]} s) is not sampled like "
                f"{chosen[0].name!r} ({chosen[0].values.size} samples, increment {b0[0]} s); "
                f"read them one at a time with {spell('channel')}",
            )
    history = [f"TDMS file read with npTDMS: {len(cols)} numeric channel(s), {len(chosen)} read"]
    rate = None
    if b0[0]:
        rate = 1.0 / b0[0]
        history.append(f"sample rate {rate:.9g} Hz from wf_increment {b0[0]:g} s")
    elif options.get("sample_rate") is None:
        raise RecordingError(
            path,
            None,
            f"channel {chosen[0].name!r} has no wf_increment; expected a waveform channel, or give {spell('sample_rate')}",
        )
    meta = [("format", "TDMS")]
    if b0[2] is not None:
        start = np.datetime64(b0[2], "us") + np.timedelta64(int(round(b0[1] * 1e6)), "us")
        meta.append(("start_time", str(start) + "Z"))
    return assemble(
        path,
        data,
        reader="vibkit.io.tdms",
        columns=chosen,
        options=options,
        history=history,
        rate=rate,
        metadata=meta,
    )
