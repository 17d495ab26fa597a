"""NI LabVIEW Measurement files (``.lvm``), read from what their headers state.

Layout (NI, "Specification of the LabVIEW Measurement File"): a file header (``LabVIEW Measurement``,
``Writer_Version``, ``Decimal_Separator``, ``Multi_Headings``, ``X_Columns`` ... ``***End_of_Header***``),
then one or more segments, each a segment header (``Channels``, ``Samples``, ``Date``, ``Time``,
``Y_Unit_Label``, ``X0``, ``Delta_X`` with one value per column ... ``***End_of_Header***``), a row of
column names (``X_Value``, the channels, ``Comment``) and tab-separated rows.

* ``X_Columns`` ``No``: no time column, time = ``X0 + i * Delta_X``; ``One``: the first column is
  time; ``Multi``: one ``X_Value`` column before each channel.
* Header values stand in the column of their channel (``Samples<TAB>51200<TAB><TAB>51200``).
* A decimal comma (``Decimal_Separator ,``) applies to the data and the header numbers.
* Channels with 0 samples (empty fields in every row) and the text ``Comment`` column are dropped;
  a channel sampled at a rate other than the first channel's is dropped (named in the history).
* Several segments become segments of the recording (never bridged): each starts at its own
  ``Date``/``Time`` when they follow one another, else right after the previous one.  Under
  ``Multi_Headings No`` and ``X_Columns No`` a block longer than ``Samples`` (> 1) holds several
  segments of ``Samples`` rows; with an X column its values are the time stamps.
* ``Y_Unit_Label`` gives each channel's unit (``g``, ``m/s^2``, ``Volts``, ``Newtons``), converted to SI.
"""

from __future__ import annotations

import re
from datetime import datetime

import numpy as np

from ..runtime.reader_options import spell
from .errors import RecordingError
from .recording import Channel, build_recording, safe_name, unique_names
from .text.units import parse_unit

__all__ = ["sniff_lvm", "read_lvm"]

_END = "***End_of_Header***"
_LABELS = {"volts": "V", "volt": "V", "newtons": "N", "newton": "N", "meters": "m", "millivolts": "mV"}


def sniff_lvm(probe) -> bool:
    return probe.head.lstrip(b"\xef\xbb\xbf").startswith(b"LabVIEW Measurement")


def _num(text, dec):
    t = text.strip()
    if dec == ",":
        t = t.replace(",", ".")
    return float(t) if t else np.nan


def _stamp(date, time, dec):
    """A segment's Date (2013/02/19) and Time (09:51:40,727...) as a datetime, or None."""
    try:
        frac = time.replace(",", ".") if dec == "," or "," in time else time
        hh, mm, rest = frac.split(":")
        sec = float(rest)
        y, mo, d = (int(x) for x in re.split(r"[/.-]", date.strip()))
        base = datetime(y, mo, d, int(hh), int(mm), int(sec))
        return base, sec - int(sec)
    except (ValueError, AttributeError):
        return None


def read_lvm(path, data, options):
    """A LabVIEW ``.lvm`` file (see the module docstring)."""
    try:
        text = data.decode("utf-8-sig")
    except UnicodeDecodeError:
        text = data.decode("cp1252", errors="replace")  # LabVIEW writes the degree sign in Latin-1
    lines = text.splitlines()
    head, i = {}, 1
    while i < len(lines) and not lines[i].startswith(_END):
        cells = lines[i].split("\t")
        if cells[0]:
            head[cells[0]] = cells[1].strip() if len(cells) > 1 else ""
        i += 1
    if i >= len(lines):
        raise RecordingError(path, None, f"LabVIEW file header without '{_END}'; expected one")
    dec = head.get("Decimal_Separator", ".") or "."
    xcols = head.get("X_Columns", "One")
    multi = head.get("Multi_Headings", "Yes").lower() == "yes"
    history = [
        f"LabVIEW Measurement file (Writer_Version {head.get('Writer_Version', '?')}): X_Columns {xcols}, "
        f"Multi_Headings {'Yes' if multi else 'No'}, decimal mark '{dec}'"
    ]
    segments = []
    i += 1
    while i < len(lines):
        if not lines[i].strip():
            i += 1
            continue
        seg_head, start_line = {}, i + 1
        while i < len(lines) and not lines[i].startswith(_END):
            cells = lines[i].split("\t")
            if cells[0]:
                seg_head[cells[0]] = [c.strip() for c in cells[1:]]
            i += 1
        if i >= len(lines):
            raise RecordingError(path, start_line, f"segment header without '{_END}'; expected one")
        i += 1
        names = lines[i].split("\t") if i < len(lines) and lines[i].startswith("X_Value") else None
        if names is None:
            raise RecordingError(path, i + 1, "expected the row of column names (X_Value ...) after the segment header")
        i += 1
        rows, first_row = [], i + 1
        while (
            i < len(lines)
            and lines[i].strip()
            and not lines[i].split("\t")[0].strip().startswith(("Channels", "Notes", "Samples"))
        ):
            rows.append((i + 1, lines[i].split("\t")))
            i += 1
        segments.append((start_line, seg_head, names, rows, first_row))
    if not segments:
        raise RecordingError(path, None, "LabVIEW file with no segment; expected a segment header and rows")
    return _assemble(path, data, head, dec, xcols, multi, segments, history, options)


def _columns(path, seg_head, names, xcols, line):
    """[(column index, name, x column or None, per-column header dict)] of the channels of a segment."""
    out = []
    for c in range(1, len(names)):
        nm = names[c].strip()
        if not nm or nm == "X_Value" or nm == "Comment":
            continue
        vals = {k: (v[c - 1] if c - 1 < len(v) else "") for k, v in seg_head.items()}
        xc = 0 if xcols.lower() == "one" else (c - 1 if xcols.lower() == "multi" else None)
        out.append((c, nm, xc, vals))
    if not out:
        raise RecordingError(path, line, "LabVIEW segment without channels; expected names after X_Value")
    return out


def _assemble(path, data, head, dec, xcols, multi, segments, history, options):
    cols0 = _columns(path, segments[0][1], segments[0][2], xcols, segments[0][0])
    ref = None
    keep = []
    for c, nm, xc, vals in cols0:
        n = vals.get("Samples", "")
        if n.strip() == "0":
            history.append(f"channel '{nm}' has 0 samples (empty fields in every row): dropped")
            continue
        try:
            dx = _num(vals.get("Delta_X", ""), dec)
        except ValueError:
            dx = np.nan
        if not (np.isfinite(dx) and dx > 0):
            raise RecordingError(path, segments[0][0], f"channel '{nm}' has no Delta_X > 0; expected its sample period")
        if ref is None:
            ref = dx
        elif abs(dx / ref - 1) > 1e-6:
            history.append(f"channel '{nm}' sampled every {dx:g} s, not {ref:g} s like the first: dropped")
            continue
        keep.append((c, nm, xc, vals))
    if not keep:
        raise RecordingError(path, segments[0][0], "every channel of the LabVIEW file is empty; expected samples")
    want = options.get("channel")
    if want is not None:
        wl = [w.strip().lower() for w in ([want] if isinstance(want, str) else want)]
        sel = [k for k in keep if k[1].lower() in wl or safe_name(k[1], "").lower() in wl]
        if len(sel) < len(wl):
            raise RecordingError(
                path, None, f"no channel {want!r} ({spell('channel')}); channels: " + ", ".join(k[1] for k in keep)
            )
        keep = sel
    fs = _rate(keep[0][3].get("Delta_X", ""), ref, history)
    ref = 1.0 / fs
    # blocks: (rows, header stamp)
    blocks = []
    for start_line, seg_head, _names, rows, _first_row in segments:
        nsamp = seg_head.get("Samples", [""])[keep[0][0] - 1] if seg_head.get("Samples") else ""
        per = int(float(nsamp)) if re.fullmatch(r"[0-9]+", nsamp.strip() or "x") else len(rows)
        date = (seg_head.get("Date") or [""])[keep[0][0] - 1] if seg_head.get("Date") else ""
        time = (seg_head.get("Time") or [""])[keep[0][0] - 1] if seg_head.get("Time") else ""
        stamp = _stamp(date, time, dec)
        if not multi and keep[0][2] is None and per > 1 and len(rows) > per and len(rows) % per == 0:
            history.append(
                f"{len(rows)} rows under a header of {per} samples per channel (Multi_Headings No): "
                f"{len(rows) // per} segments of {per} rows, placed end to end (the file gives no start for them)"
            )
            for k in range(0, len(rows), per):
                blocks.append((rows[k : k + per], stamp if k == 0 else None))
        else:
            if per and len(rows) < per:
                history.append(
                    f"segment at line {start_line}: header says {per} samples, the file holds {len(rows)} rows"
                )
            blocks.append((rows, stamp))
    times, values, seg_ids = [], [[] for _ in keep], []
    t_end, first_stamp = None, blocks[0][1]
    for b, (rows, stamp) in enumerate(blocks):
        if not rows:
            continue
        n = len(rows)
        x = None
        if keep[0][2] is not None:
            x = np.array([_cell(path, r, keep[0][2], dec, ln) for ln, r in rows])
        if x is not None and np.all(np.isfinite(x)):
            t = x - x[0]
        else:
            t = np.arange(n) * ref
        if b == 0:
            off = 0.0
        elif stamp is not None and first_stamp is not None:
            rel = (stamp[0] - first_stamp[0]).total_seconds() + stamp[1] - first_stamp[1]
            off = rel if rel > t_end else t_end + ref
        else:
            off = t_end + ref
        times.append(t + off)
        t_end = float(times[-1][-1])
        seg_ids.append(np.full(n, len(seg_ids)))
        for k, (c, _nm, _xc, _v) in enumerate(keep):
            values[k].append(np.array([_cell(path, r, c, dec, ln) for ln, r in rows]))
    t = np.concatenate(times)
    if np.any(np.diff(t) <= 0):
        raise RecordingError(path, None, "LabVIEW X values do not increase; expected time going forward")
    steps = np.diff(t)
    if t.size > 2 and keep[0][2] is not None and np.max(np.abs(steps - ref)) > 0.01 * ref and len(blocks) == 1:
        history.append(f"X values step {steps.min():.6g} to {steps.max():.6g} s, not Delta_X {ref:g} s: kept as stamps")
    channels, names = [], unique_names([safe_name(k[1], f"channel_{k[0]}") for k in keep])
    for k, (_c, nm, _xc, vals) in enumerate(keep):
        label = vals.get("Y_Unit_Label", "").strip()
        u = parse_unit(_LABELS.get(label.lower(), label)) if label else None
        v = np.concatenate(values[k])
        if u is not None and u.factor is not None:
            v, unit, q = v * u.factor, u.si, u.quantity
            history.append(f"channel '{nm}' in {label} (Y_Unit_Label)" + (f" -> {unit}" if u.factor != 1 else ""))
        else:
            unit, q = (label or "unknown"), "other"
            history.append(f"channel '{nm}': unit {label!r} kept as found" if label else f"channel '{nm}': no unit")
        channels.append(Channel(names[k], v, unit, nm, q, {"source_name": nm, "column": nm}))
    seg = np.concatenate(seg_ids)
    nseg = int(seg.max()) + 1
    if nseg > 1:
        history.append(f"{nseg} segments, kept as segments, not bridged")
    metadata = {"segment_count": nseg, "device": "NI LabVIEW"}
    if first_stamp is not None:
        metadata["start_time"] = (first_stamp[0]).isoformat() + f"{first_stamp[1]:.6f}"[1:]
    for k in ("Operator", "Writer_Version"):
        if head.get(k):
            metadata[k.lower()] = head[k]
    return build_recording(
        time=t,
        channels=channels,
        segment=seg,
        path=path,
        data_bytes=data,
        reader="vibkit.io.lvm",
        sample_rate_hz=fs,
        history=history,
        metadata=metadata,
    )


def _rate(text, dx, history):
    """The sample rate Delta_X states [Hz]: 1/Delta_X, or the whole number of Hz it was rounded from.

    LabVIEW writes Delta_X with a fixed number of decimals (``0.000977`` for 1/1024 s); a whole
    rate whose period, rounded to those decimals, gives the text is taken, and said so.
    """
    m = re.fullmatch(r"\s*[0-9]*[.,]([0-9]+)\s*", text)
    fs = 1.0 / dx
    whole = round(fs)
    if m and whole > 0 and abs(whole / fs - 1) < 1e-3 and round(1.0 / whole, len(m.group(1))) == dx and whole != fs:
        history.append(
            f"Delta_X {text.strip()} s is 1/{whole} s written with {len(m.group(1))} decimals: sample rate "
            f"{whole} Hz (1/Delta_X would give {fs:.6g} Hz)"
        )
        return float(whole)
    history.append(f"sample rate {fs:.6g} Hz from Delta_X {dx:g} s")
    return fs


def _cell(path, row, c, dec, line):
    text = row[c] if c < len(row) else ""
    try:
        return _num(text, dec)
    except ValueError:
        raise RecordingError(path, line, f"expected a number in column {c + 1}, found {text!r}") from None
