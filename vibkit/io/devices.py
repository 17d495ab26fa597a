"""Device exports the generic text reader cannot read, containers, and binary logs vibkit names but does not read.

Each layout is read from what its header states; every decision goes into the dataset's ``history``:

* Empatica E4 (``ACC.csv``, ``BVP.csv``, ``EDA.csv``, ``TEMP.csv``, ``HR.csv``): row 1 the start time
  (Unix epoch s, repeated per column), row 2 the sample rate [Hz], then the samples; ``ACC.csv``
  holds x, y, z in 1/64 g.  ``IBI.csv`` (beat-to-beat intervals) is not a sampled signal: refused.
* ActiGraph ActiLife RAW CSV: a dashed banner ``... date format M/d/yyyy at 30 Hz ...``, then
  ``Start Time``, ``Start Date`` lines, a dashed line, an optional column row
  (``Accelerometer X,...``), values in g.  Header lines may be padded with ``,,``.
* Containers: gzip (``.gz``) and zip holding exactly one recording are unpacked, and the recording
  inside is read by the entry of :data:`vibkit.io.registry.FORMATS` that claims it.
* WitMotion WT901 SD-card logs (binary ``0x55`` packets): named, with what reads them, and refused.
* Spreadsheet workbooks (Excel ``.xls``/``.xlsx``, OpenDocument ``.ods``, Apple ``.numbers``; phyphox exports
  one as "Excel"): named and refused, asking for the CSV export (reading them would need a dependency each).

The LabVIEW ``.lvm`` reader is :mod:`vibkit.io.lvm`.
"""

from __future__ import annotations

import gzip
import io
import os
import re
import zipfile
import zlib
from datetime import datetime, timezone

import numpy as np

from ..runtime.reader_options import spell
from .errors import RecordingError
from .limits import max_recording_bytes
from .phone import is_phone_export, read_phone_export
from .recording import Channel, build_recording, safe_name, sha256_of
from .text.units import parse_unit

__all__ = [
    "sniff_e4",
    "read_e4",
    "sniff_actigraph",
    "read_actigraph",
    "sniff_gzip",
    "sniff_zip",
    "read_gzip",
    "read_zip",
    "sniff_witmotion",
    "read_witmotion",
    "sniff_spreadsheet",
    "read_spreadsheet",
]

# ----------------------------------------------------------------------------------------- Empatica E4
#: E4 file name (upper case, no suffix) -> (channel names, unit as found, quantity, what it is)
_E4_FILES = {
    "ACC": (("x", "y", "z"), "g/64", "acceleration", "3-axis accelerometer, 1/64 g per count"),
    "BVP": (("bvp",), None, "other", "blood volume pulse (photoplethysmograph)"),
    "EDA": (("eda",), "uS", "other", "electrodermal activity [microsiemens]"),
    "TEMP": (("temp",), "degC", "other", "skin temperature [degrees Celsius]"),
    "HR": (("hr",), "bpm", "other", "heart rate derived from BVP [beats per minute]"),
}
_E4_NUM = r"[0-9]+(?:\.[0-9]*)?"
_E4_ROW1 = re.compile(rf"^\s*{_E4_NUM}(?:\s*,\s*{_E4_NUM})*\s*$")
_EPOCH_S = (3e8, 4.2e9)


def _head_lines(head: bytes, n: int):
    try:
        text = head.decode("utf-8-sig", errors="strict")
    except UnicodeDecodeError:
        return None
    return text.splitlines()[:n]


def _cells(line: str):
    return [c.strip() for c in line.split(",")]


def sniff_e4(probe) -> bool:
    """Row 1: one Unix epoch time (s) per column, all equal; row 2: one rate per column, all equal; or IBI."""
    lines = _head_lines(probe.head, 3)
    if not lines or len(lines) < 2:
        return False
    c1 = _cells(lines[0])
    if len(c1) == 2 and c1[1] == "IBI" and re.fullmatch(_E4_NUM, c1[0]):
        return _EPOCH_S[0] <= float(c1[0]) <= _EPOCH_S[1]
    if not (_E4_ROW1.match(lines[0]) and _E4_ROW1.match(lines[1]) and len(lines) >= 3):
        return False
    c2 = _cells(lines[1])
    if len(c1) != len(c2) or len(set(c1)) != 1 or len(set(c2)) != 1 or len(c1) > 3:
        return False
    t0, fs = float(c1[0]), float(c2[0])
    return _EPOCH_S[0] <= t0 <= _EPOCH_S[1] and 0 < fs <= 1e4 and len(_cells(lines[2])) == len(c1)


def read_e4(path, data, options):
    """An Empatica E4 export (see the module docstring)."""
    text = _decode_text(path, data)
    lines = text.splitlines()
    c1 = _cells(lines[0])
    if len(c1) == 2 and c1[1] == "IBI":
        raise RecordingError(
            path,
            1,
            "Empatica E4 IBI.csv holds beat-to-beat intervals (time of each beat, interval), not a "
            "sampled signal; read ACC.csv (acceleration) or BVP.csv of the same session",
        )
    t0 = float(c1[0])
    fs = float(_cells(lines[1])[0])
    rows = [ln for ln in lines[2:] if ln.strip()]
    if len(rows) < 2:
        raise RecordingError(path, 3, "Empatica E4 export with fewer than 2 samples; expected at least 2")
    try:
        values = np.array([[float(c) for c in _cells(r)] for r in rows], dtype=float)
    except ValueError:
        for i, r in enumerate(lines[2:], start=3):
            if r.strip() and any(not re.fullmatch(r"[+-]?[0-9.]+(?:[eE][+-]?[0-9]+)?", c) for c in _cells(r)):
                raise RecordingError(
                    path, i, f"expected {len(c1)} number(s) per row (Empatica E4), found {r!r}"
                ) from None
        raise
    if values.ndim != 2 or values.shape[1] != len(c1):
        raise RecordingError(path, 3, f"expected {len(c1)} number(s) per row (Empatica E4)")
    stem = os.path.splitext(os.path.basename(str(path)))[0].upper()
    known = _E4_FILES.get(stem)
    history = [
        f"Empatica E4 export: row 1 start time {c1[0]} (Unix epoch s), row 2 sample rate {fs:g} Hz; "
        f"{values.shape[0]} samples from line 3"
    ]
    if known is None or len(known[0]) != values.shape[1]:
        names = ("x", "y", "z") if values.shape[1] == 3 else tuple(f"value_{k + 1}" for k in range(values.shape[1]))
        unit_text, quantity, what = (None, "other", "unknown E4 stream: the file name does not say which")
        if values.shape[1] == 3:
            unit_text, quantity, what = "g/64", "acceleration", "3 columns: the accelerometer, 1/64 g per count"
    else:
        names, unit_text, quantity, what = known
    history.append(f"{os.path.basename(str(path))}: {what}")
    channels = []
    for k, name in enumerate(names):
        ch = _channel(name, values[:, k], unit_text, quantity, f"{name}", history)
        channels.append(ch)
    channels = _keep_channels(path, channels, options.get("channel"))
    start = datetime.fromtimestamp(t0, tz=timezone.utc).isoformat()
    return build_recording(
        time=np.arange(values.shape[0]) / fs,
        channels=channels,
        segment=None,
        path=path,
        data_bytes=data,
        reader="vibkit.io.devices.e4",
        sample_rate_hz=fs,
        history=history,
        metadata={"start_time": start, "time_offset_s": t0, "device": "Empatica E4", "segment_count": 1},
    )


# ----------------------------------------------------------------------------------------- ActiGraph
_AG_BANNER = re.compile(r"^-+\s*Data File Created By ActiGraph", re.IGNORECASE)
_AG_TIME = re.compile(r"(time ?stamp|date ?time|time|date)", re.IGNORECASE)


def sniff_actigraph(probe) -> bool:
    lines = _head_lines(probe.head, 1)
    return bool(lines) and bool(_AG_BANNER.match(lines[0].strip()))


def _ag_date(path, line_no, text, fmt):
    """A date ``M/d/yyyy`` or ``d/M/yyyy`` (as the banner's ``date format`` says) -> (year, month, day)."""
    m = re.fullmatch(r"([0-9]{1,2})[/.-]([0-9]{1,2})[/.-]([0-9]{4})", text)
    if not m:
        raise RecordingError(path, line_no, f"expected a start date like 2/14/2019, found {text!r}")
    a, b, y = (int(g) for g in m.groups())
    month_first = fmt is None or fmt.lower().startswith("m")
    return (y, a, b) if month_first else (y, b, a)


def read_actigraph(path, data, options):
    """An ActiGraph ActiLife RAW CSV export (see the module docstring)."""
    text = _decode_text(path, data)
    lines = text.splitlines()
    banner = lines[0]
    m = re.search(r"at\s+([0-9]+(?:\.[0-9]+)?)\s*Hz", banner, re.IGNORECASE)
    if not m:
        raise RecordingError(path, 1, "ActiGraph banner without 'at N Hz'; expected the sample rate there")
    fs = float(m.group(1))
    fm = re.search(r"date format\s+(\S+)", banner, re.IGNORECASE)
    date_fmt = fm.group(1) if fm else None
    meta, start_time, start_date, dashes = {}, None, None, None
    for i in range(1, min(len(lines), 40)):
        ln = lines[i].rstrip().rstrip(",").strip()
        if re.fullmatch(r"-{5,}", ln):
            dashes = i
            break
        if ln.lower().startswith("start time"):
            start_time = (i + 1, ln[len("start time") :].strip())
        elif ln.lower().startswith("start date"):
            start_date = (i + 1, ln[len("start date") :].strip())
        elif ":" in ln:
            k, _, v = ln.partition(":")
            meta[k.strip()] = v.strip()
    if dashes is None:
        raise RecordingError(path, None, "ActiGraph header without its closing dashed line; expected one")
    first = dashes + 1
    names = ["Accelerometer X", "Accelerometer Y", "Accelerometer Z"]
    history = [f"ActiGraph ActiLife RAW CSV: 'at {fs:g} Hz' in the banner (line 1); values in g"]
    if first < len(lines) and re.search(r"[A-Za-z]", lines[first]):
        names = [c for c in _cells(lines[first]) if c]
        history.append(f"column names on line {first + 1}")
        first += 1
    else:
        history.append(f"no column-name row: data from line {first + 1}, columns read as {', '.join(names)}")
    value_cols = [k for k, nm in enumerate(names) if not _AG_TIME.fullmatch(nm)]
    rows, rownums = [], []
    for i in range(first, len(lines)):
        if not lines[i].strip():
            continue
        cells = _cells(lines[i])[: len(names)]
        try:
            rows.append([float(cells[k]) for k in value_cols if k < len(cells)])
        except ValueError:
            raise RecordingError(
                path, i + 1, f"expected {len(names)} numbers (ActiGraph RAW), found {lines[i]!r}"
            ) from None
        if len(cells) != len(names):
            raise RecordingError(path, i + 1, f"expected {len(names)} fields (ActiGraph RAW), found {len(cells)}")
        rownums.append(i + 1)
    if len(rows) < 2:
        raise RecordingError(path, first + 1, "ActiGraph export with fewer than 2 samples; expected at least 2")
    values = np.asarray(rows, dtype=float)
    metadata = {"device": "ActiGraph", "segment_count": 1}
    if "Serial Number" in meta:
        metadata["serial_number"] = meta["Serial Number"]
    if start_time and start_date:
        y, mo, d = _ag_date(path, start_date[0], start_date[1], date_fmt)
        hh, mm, ss = (int(x) for x in re.findall(r"[0-9]+", start_time[1])[:3])
        metadata["start_time"] = datetime(y, mo, d, hh, mm, ss).isoformat()
        history.append(
            f"start {metadata['start_time']} (local time) from 'Start Date' line {start_date[0]} read as "
            f"{date_fmt or 'M/d/yyyy'} and 'Start Time' line {start_time[0]}"
        )
    if len(value_cols) < len(names):
        history.append("the Timestamp column is not read: time = sample index / the banner's rate, from the start")
    channels = [
        _channel(names[k], values[:, j], "g", "acceleration", names[k], history) for j, k in enumerate(value_cols)
    ]
    channels = _keep_channels(path, channels, options.get("channel"))
    return build_recording(
        time=np.arange(values.shape[0]) / fs,
        channels=channels,
        segment=None,
        path=path,
        data_bytes=data,
        reader="vibkit.io.devices.actigraph",
        sample_rate_hz=fs,
        history=history,
        metadata=metadata,
    )


# ----------------------------------------------------------------------------------------- containers
def sniff_gzip(probe) -> bool:
    return probe.head[:2] == b"\x1f\x8b"


def sniff_zip(probe) -> bool:
    return probe.head[:4] in (b"PK\x03\x04", b"PK\x05\x06")


def read_gzip(path, data, options, detect_format):
    """A gzip file: its one member is read as the recording it holds (by the entry ``detect_format`` finds, the
    registry's :func:`~vibkit.io.registry.detect_format`)."""
    limit = max_recording_bytes()
    d = zlib.decompressobj(16 + zlib.MAX_WBITS)
    try:
        inner = d.decompress(data, limit + 1)
        if len(inner) <= limit and (not d.eof or d.unused_data.strip(b"\0")):  # cut short, or several members
            inner = gzip.decompress(data)
    except (zlib.error, EOFError, OSError) as exc:
        raise RecordingError(path, None, f"gzip file that cannot be unpacked ({exc}); expected a whole .gz") from None
    if len(inner) > limit:
        raise RecordingError(
            path,
            None,
            f"unpacks to more than the {limit} byte limit for a recording "
            "(raise it with the environment variable VIBKIT_MAX_RECORDING_BYTES)",
        )
    base = os.path.basename(str(path))
    member = base[:-3] if base.lower().endswith(".gz") else os.path.splitext(base)[0] or base
    if member.lower().endswith(".tar") or inner[257:262] == b"ustar":
        raise RecordingError(path, None, "a tar archive (.tar.gz); expected one gzipped recording: unpack it first")
    return _read_member(path, data, member, inner, options, "gzip", detect_format)


def _member_head(zf, name, size=512):
    """The first ``size`` bytes of a zip member (empty where it cannot be unpacked)."""
    try:
        with zf.open(name) as f:
            return f.read(size)
    except (zipfile.BadZipFile, RuntimeError, NotImplementedError, OSError, zlib.error):
        return b""


def read_zip(path, data, options, detect_format):
    """A zip archive holding exactly one recording (folders, ``__MACOSX`` and dot files aside), read by the entry
    ``detect_format`` finds (the registry's :func:`~vibkit.io.registry.detect_format`)."""
    try:
        zf = zipfile.ZipFile(io.BytesIO(data))
        infos = [
            i
            for i in zf.infolist()
            if not i.is_dir()
            and not i.filename.startswith("__MACOSX/")
            and not os.path.basename(i.filename).startswith(".")
        ]
    except (zipfile.BadZipFile, OSError, ValueError) as exc:
        raise RecordingError(path, None, f"zip archive that cannot be read ({exc}); expected a whole .zip") from None
    if is_phone_export([i.filename for i in infos], head=lambda name: _member_head(zf, name)):
        return read_phone_export(path, options)
    if len(infos) != 1:
        listed = ", ".join(i.filename for i in infos[:6]) + (" ..." if len(infos) > 6 else "")
        raise RecordingError(
            path,
            None,
            f"zip archive holding {len(infos)} files ({listed or 'none'}); expected exactly one recording: "
            "unpack it and name the file to read",
        )
    info = infos[0]
    if info.file_size > max_recording_bytes():
        raise RecordingError(
            path,
            None,
            f"{info.filename} unpacks to more than the {max_recording_bytes()} byte limit for a recording "
            "(raise it with the environment variable VIBKIT_MAX_RECORDING_BYTES)",
        )
    try:
        inner = zf.read(info)
    except (zipfile.BadZipFile, RuntimeError, NotImplementedError, OSError, zlib.error) as exc:
        raise RecordingError(path, None, f"cannot unpack {info.filename} ({exc}); expected a plain zip") from None
    return _read_member(path, data, info.filename, inner, options, "zip", detect_format)


def _read_member(path, data, member, inner, options, kind, detect_format):
    if not inner:
        raise RecordingError(path, None, f"{member} inside the {kind} file is empty; expected a recording")
    inner_path = f"{path}/{member}"
    entry = detect_format(inner_path, inner, options.get("encoding"))
    ds = entry.read(inner_path, inner, options)
    ds.attrs["container_member"] = member
    ds.attrs["container_sha256"] = ds.attrs["sha256"]
    ds.attrs["source_file"] = os.path.basename(str(path))
    ds.attrs["sha256"] = sha256_of(data)
    ds.attrs["history"] = f"{kind} file unpacked: {member} ({len(inner)} bytes) read by '{entry.name}'\n" + str(
        ds.attrs.get("history", "")
    )
    return ds


# ----------------------------------------------------------------------------------------- WitMotion
_WIT_TYPES = {0x50: "time", 0x51: "acceleration", 0x52: "angular rate", 0x53: "angle", 0x54: "magnetic field"}


def _wit_packets(head: bytes, at: int = 0, n: int = 8) -> int:
    """Number of consecutive valid 11-byte WitMotion packets (0x55, type, 8 bytes, checksum) from ``at``."""
    k = 0
    while k < n and at + 11 <= len(head):
        p = head[at : at + 11]
        if p[0] != 0x55 or not 0x50 <= p[1] <= 0x5F or sum(p[:10]) & 0xFF != p[10]:
            break
        k += 1
        at += 11
    return k


def sniff_witmotion(probe) -> bool:
    head = probe.head
    for start in range(min(11, len(head))):
        if head[start : start + 1] == b"\x55" and _wit_packets(head, start) >= 4:
            return True
    return False


def read_witmotion(path, data, options):
    start = next(s for s in range(11) if _wit_packets(data, s) >= 4)
    kinds = sorted(
        {_WIT_TYPES.get(data[i + 1], f"0x{data[i + 1]:02X}") for i in range(start, min(len(data), 4400), 11)}
    )
    raise RecordingError(
        path,
        None,
        "WitMotion WT901 binary log (0x55 packets: " + ", ".join(kinds) + "), which vibkit does not read; "
        "export it to CSV with WitMotion's own software (WitMotion PC software or the WitMotion app) and read that CSV",
    )


# ----------------------------------------------------------------------------------------- spreadsheets
_SPREADSHEET_SUFFIXES = (".xls", ".xlsx", ".xlsm", ".ods", ".numbers")
_OLE2 = b"\xd0\xcf\x11\xe0\xa1\xb1\x1a\xe1"  # the compound file of .xls (and of other Office 97 files)


def _spreadsheet_kind(head: bytes, suffix: str):
    """What spreadsheet the first bytes ``head`` of a file with suffix ``suffix`` (``.xls``) make, or None."""
    if head[:8] == _OLE2:
        return "an Excel 97-2003 workbook (.xls: an OLE2 compound file)"
    if head[:4] == b"PK\x03\x04":
        if b"application/vnd.oasis.opendocument.spreadsheet" in head[:200]:
            return "an OpenDocument spreadsheet (.ods)"
        if b"xl/" in head or (b"[Content_Types].xml" in head[:100] and suffix in _SPREADSHEET_SUFFIXES):
            return "an Excel workbook (.xlsx)"
    if suffix in _SPREADSHEET_SUFFIXES:
        return f"a spreadsheet workbook ({suffix})"
    return None


def sniff_spreadsheet(probe) -> bool:
    return _spreadsheet_kind(probe.head, probe.suffix) is not None


def read_spreadsheet(path, data, options):
    kind = _spreadsheet_kind(bytes(data[:65536]), os.path.splitext(os.fspath(path))[1].lower())
    raise RecordingError(
        path,
        None,
        f"{kind or 'a spreadsheet workbook'}, which vibkit does not read; expected CSV: export or save the data as CSV "
        "(phyphox: 'CSV (Comma, decimal point)'; a spreadsheet program: one sheet as CSV)",
    )


# ----------------------------------------------------------------------------------------- shared
def _decode_text(path, data) -> str:
    try:
        return data.decode("utf-8-sig")
    except UnicodeDecodeError:
        return data.decode("cp1252", errors="replace")


def _channel(name, values, unit_text, quantity, source, history):
    u = parse_unit(unit_text) if unit_text else None
    if u is not None and u.factor is not None:
        vals, si, q = values * u.factor, u.si, u.quantity
        if u.factor != 1:
            history.append(f"{name} in {unit_text} -> {si} (x {u.factor:.6g})")
    else:
        vals, si, q = values, unit_text or "unknown", quantity
    return Channel(safe_name(name, "channel"), np.asarray(vals, dtype=float), si, name, q, {"source_name": source})


def _keep_channels(path, channels, channel):
    if channel is None:
        return channels
    want = [channel] if isinstance(channel, str) else list(channel)
    keep = []
    for w in want:
        hit = [c for c in channels if w.strip().lower() in (c.name.lower(), c.long_name.lower())]
        if not hit:
            raise RecordingError(
                path,
                None,
                f"no channel {w!r} ({spell('channel')}); channels: " + ", ".join(c.long_name for c in channels),
            )
        keep += hit
    return keep
