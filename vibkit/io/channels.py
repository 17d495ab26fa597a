"""Which channel of a recording a user means: by vibkit's name or as the file wrote it.

A reader renames columns into safe variable names (``"vz_ms"`` -> ``vz``,
``"Acceleration x (m/s^2)"`` -> ``acceleration_x``) and keeps the header as
found in the variable's attrs (``source_name``, ``column``).  A user names a
channel as the file writes it, so :func:`resolve_channel` accepts the variable
name, the header as found and the name without its unit, case-insensitively.

Columns that count samples (``index``, ``sample number``, ``#``, ``n``, or a
strict +1 integer ramp) carry ``sample_counter = 1`` and are no channels: the
readers keep them as coordinates along ``time`` (a channel only when asked for by
name), never chosen by default.
"""

from __future__ import annotations

import re

import numpy as np

from ..runtime.reader_options import spell

__all__ = [
    "resolve_channel",
    "with_component",
    "is_counter_name",
    "is_counter_ramp",
    "COUNTER_ATTR",
    "STATUS_ATTR",
    "is_status",
    "mark_status",
    "channel_series",
    "own_samples",
]

#: variable attr marking a column that counts samples
COUNTER_ATTR = "sample_counter"
_COUNTER_NAME = re.compile(
    r"^(?:#|n|nr|no\.?|num|number|idx|index|row|record|count|counter"
    r"|(?:sample|muestra|punto|data ?point)s?(?:[ _-]?(?:#|n|nr|no\.?|num|number|index|idx|count|counter))?"
    r"|(?:#|n|nr|no\.?|num|number|index|idx)[ _-]?(?:de[ _-])?(?:sample|muestra|point|row)s?)$",
    re.IGNORECASE,
)


#: variable attr marking a status column (an accuracy or state code, or a column that never changes)
STATUS_ATTR = "status_column"
_STATUS_NAME = re.compile(r"^(?:accuracy|status|state|flags?|quality|valid(?:ity)?|error|battery)(?:[ _].*)?$", re.I)


def is_status(name, values) -> bool:
    """Whether a column is a status and not a signal: named like one (``accuracy``, ``status``) and holding
    few distinct integers, or holding one value only."""
    try:
        v = np.asarray(values, dtype=float).ravel()
    except (TypeError, ValueError):  # text or stamps: not a signal vibkit analyses anyway
        return False
    finite = np.isfinite(v)
    if not finite.all():  # a copy only when some values are missing
        v = v[finite]
    del finite
    if v.size < 2:
        return False
    if np.all(v == v[0]):
        return True
    return bool(_STATUS_NAME.match(str(name).strip())) and np.all(v == np.round(v)) and np.unique(v).size <= 16


def mark_status(channels, history):
    """Mark the status columns among reader channels (attr :data:`STATUS_ATTR`), saying so in ``history``."""
    found = []
    for ch in channels:
        if is_status(ch.long_name, ch.values):
            ch.attrs[STATUS_ATTR] = 1
            found.append(ch.name)
    if found:
        history.append(
            "status or constant column(s) " + ", ".join(found) + ": kept, never the channel analysed by default"
        )


def channel_series(recording, name):
    """(time [s], values) of one channel's own samples: the rows where it holds a value (sparse exports)."""
    v = np.asarray(recording[name].values, dtype=float)
    t = np.asarray(recording["time"].values, dtype=float)
    ok = np.isfinite(v)
    return t[ok], v[ok]


def own_samples(recording, name):
    """The recording cut to the rows where channel ``name`` holds a value, when it is sparse (attr ``sparse``:
    a sensor that wrote only some rows); else the recording itself.

    Analyses of a sparse channel run on its own samples and times, never on values filled in between them.
    """
    if not int(recording[name].attrs.get("sparse", 0)):
        return recording
    return recording.isel(time=np.flatnonzero(np.isfinite(np.asarray(recording[name].values, dtype=float))))


def _norm(text) -> str:
    return " ".join(str(text).split()).lower()


def is_counter_name(name: str) -> bool:
    """Whether a column name says it counts samples (``index``, ``sample number``, ``#``, ``n`` ...)."""
    return bool(_COUNTER_NAME.match(str(name).strip().strip("\"'").strip()))


def is_counter_ramp(values) -> bool:
    """Whether values are a strict +1 integer ramp (0, 1, 2 ... or k, k+1 ...), at least 3 long."""
    v = np.asarray(values)
    if v.ndim != 1 or v.size < 3 or v.dtype.kind not in "iuf":
        return False
    if v.dtype.kind == "f" and (not np.isfinite(v[0]) or v[0] != np.round(v[0]) or abs(v[0]) > 2**52):
        return False
    if v[1] - v[0] != 1 or v[-1] - v[0] != v.size - 1:  # cheap tests first: long recordings
        return False
    return bool(np.all(np.diff(v) == 1))


def _channels(recording):
    return [str(v) for v in recording.data_vars if v != "segment" and recording[v].dims == ("time",)]


def _counters(recording):
    """Columns that count samples: coordinates along time (or, in older results, data variables) marked so."""
    return [
        str(v)
        for v in recording.variables
        if v not in ("time", "segment")
        and recording[v].dims == ("time",)
        and int(recording[v].attrs.get(COUNTER_ATTR, 0))
    ]


def _is_status_var(recording, name) -> bool:
    da = recording[name]
    return bool(int(da.attrs.get(STATUS_ATTR, 0))) or (da.size > 1 and is_status("", da.values))


def _where(recording) -> str:
    src = recording.attrs.get("source_file", "")
    return f"{src}: " if src else ""


def resolve_channel(recording, channel=None) -> str:
    """The variable name of the channel to analyse.

    Parameters
    ----------
    recording : xarray.Dataset
        A recording (see :func:`vibkit.read_recording`).
    channel : str, optional
        The variable name, or the column header as the file writes it
        (``"vz_ms"``, ``"Acceleration x (m/s^2)"``), or that header without its
        unit; case and runs of blanks do not matter.  Default: the first channel
        that is not a sample counter.

    Returns
    -------
    str
        A data variable of ``recording`` along ``time``.

    Raises
    ------
    ValueError
        No such channel (the message names the file and lists the channels with
        the names the file wrote), no channel at all, or only sample counters.
    """
    counters = _counters(recording)
    names = _channels(recording) + [c for c in counters if c not in recording.data_vars]
    where = _where(recording)
    if not names:
        raise ValueError(f"{where}recording has no 1-D channel along 'time'")
    if channel is None:
        for n in names:
            if n not in counters and not _is_status_var(recording, n):
                return n
        for n in names:
            if n not in counters:
                return n
        raise ValueError(
            f"{where}the only channel(s) {', '.join(repr(n) for n in names)} count samples "
            f"(index, sample number); name one with {spell('channel')} to analyse it anyway"
        )
    want = _norm(channel)
    for keys in (("__name__",), ("source_name", "column", "trace_id"), ("channel_code",), ("long_name",)):
        for n in names:
            attrs = recording[n].attrs
            cands = [n if k == "__name__" else attrs.get(k) for k in keys]
            if any(c is not None and _norm(c) == want for c in cands):
                return n
    listed = []
    for n in names:
        src = recording[n].attrs.get("source_name")
        listed.append(n if not src or _norm(src) == n.lower() else f"{n} (file: {src!r})")
    hint = ""
    multi = _multi(recording)
    if multi:
        first = multi[0]
        hint = "; components: " + ", ".join(
            f"{v}[{', '.join(d[1:])}]" for v, d in ((m, recording[m].dims) for m in multi)
        )
        hint += f", e.g. {first}[{', '.join(str(recording[d].values[0]) for d in recording[first].dims[1:])}]"
    raise ValueError(f"{where}channel {channel!r} is not in the recording (channels: {', '.join(listed)}{hint})")


_COMPONENT = re.compile(r"^\s*([A-Za-z_]\w*)\s*\[(.+)\]\s*$")


def _multi(recording):
    """Variables along time and other labelled dimensions (a simulation's ``roller_acceleration``)."""
    return [
        str(v)
        for v in recording.data_vars
        if recording[v].ndim > 1
        and recording[v].dims[0] == "time"
        and all(d in recording.coords for d in recording[v].dims[1:])
    ]


def with_component(recording, channel):
    """``recording`` with the component ``channel`` of a variable along time and other dimensions added
    as a channel of that name: ``"roller_acceleration[59, z]"`` is roller 59's z axis (the labels in
    the order of the variable's dimensions after time, as its coordinates write them). Unchanged when
    ``channel`` is not such a name or is already a channel.

    Raises
    ------
    ValueError
        The variable has no such labels (the message lists the ones it has).
    """
    m = _COMPONENT.match(str(channel or ""))
    if m is None or channel in recording.data_vars or m.group(1) not in _multi(recording):
        return recording
    name = m.group(1)
    var = recording[name]
    dims = var.dims[1:]
    labels = [x.strip().strip("'\"") for x in m.group(2).split(",")]
    where = _where(recording)
    if len(labels) != len(dims):
        raise ValueError(
            f"{where}{name} has {len(dims)} dimension(s) after time ({', '.join(dims)}): name one label each"
        )
    index = {}
    for dim, label in zip(dims, labels):
        have = [str(c) for c in recording[dim].values]
        if label not in have:
            raise ValueError(f"{where}{name} has no {dim} {label!r} ({dim}: {', '.join(have)})")
        index[dim] = have.index(label)
    comp = var.isel(index, drop=True)
    comp.attrs = dict(var.attrs, component_of=name)
    out = recording.copy()
    out[str(channel)] = comp
    return out
