"""Metadata lines of a text recording: ``key: value`` pairs, free comment text, sample rate and scale.

The sample rate (``Sampling rate = 200 Hz``) and the counts scale (``2048 counts
per g``) found here are what :mod:`vibkit.io.text.csv` uses when the file's columns
do not say them.  The keys one logger alone uses (PicoQuake's ``data_rate``, GCDC's
``Headers``) come from its profile in :mod:`vibkit.io.text.loggers`.
"""

from __future__ import annotations

import math
import re
from datetime import datetime

from .cells import _NUM
from .loggers import header_keys, rate_key_patterns
from .units import parse_unit

__all__ = []

#: metadata keys that hold the sample rate in any logger's file (a logger's own key is in its profile)
_GENERIC_RATE_KEYS = (
    r"sampl\w*[\s_-]*(?:rate|freq)",
    r"samplerate",
    r"^fs\b",
    r"frecuencia\s*de\s*muestreo",
    r"^odr$",
    r"sampling",
    r"muestreo",
    r"abtastrate",
)
_RATE_KEY = re.compile("|".join(_GENERIC_RATE_KEYS + rate_key_patterns()), re.IGNORECASE)
_SCALE = re.compile(
    r"([0-9]+(?:[.,][0-9]*)?(?:[eE][+-]?[0-9]+)?)\s*,?\s*(?:counts?|lsb|cts|digits)\s*"
    r"(?:/|per)\s*([^\s,;]+)",
    re.IGNORECASE,
)


def _meta_pair(line: str, delim: str, dec: str):
    """('key', value) from a metadata line, or (None, text) for free text."""
    s = line.strip()
    s = s.lstrip("#;%/! \t").strip()
    if not s:
        return None, ""
    seps = [":", "=", "\t"] + ([delim] if delim not in (" ", "\t") else [])
    pos = [(s.find(c), c) for c in seps if s.find(c) > 0]
    if not pos:
        return None, (s.rstrip(delim + " ") if delim != " " else s)
    p, _ = min(pos)
    key = s[:p].strip().strip('"').strip()
    value = s[p + 1 :].strip()
    if delim not in (" ",):
        value = value.strip(delim + " ")
    value = value.strip('"').strip()
    if not key or len(key) > 48 or len(key.split()) > 5 or not re.search(r"[A-Za-z]", key) or not value:
        return None, (s.rstrip(delim + " ") if delim != " " else s)
    for dm in (dec, "."):
        if _NUM[dm].fullmatch(value):
            v = value.replace(",", ".")
            return key, (int(v) if re.fullmatch(r"[+-]?[0-9]+", v) and abs(int(v)) < 2**53 else float(v))
    return key, value


def _nested(pairs):
    """The pairs, each followed by the ``key = value`` pairs inside its value.

    ``# Config: data_rate = 2000.0 Hz, filter = 488 Hz`` (PicoQuake) holds ``data_rate``.
    """
    for lineno, key, value in pairs:
        yield lineno, key, value
        if isinstance(value, str) and "=" in value:
            for part in value.split(","):
                k, sep, v = part.partition("=")
                if sep and k.strip() and v.strip():
                    yield lineno, k.strip(), v.strip()


def _rate_from_meta(pairs):
    """(rate [Hz], line, key) from a sample-rate metadata pair (or one inside a pair's value), or None."""
    for lineno, key, value in _nested(pairs):
        if not _RATE_KEY.search(key):
            continue
        text = f"{value}"
        m = re.search(r"([0-9]+(?:[.,][0-9]*)?(?:[eE][+-]?[0-9]+)?)\s*,?\s*([A-Za-z/]*)", text)
        if not m:
            continue
        rate = float(m.group(1).replace(",", "."))
        unit = (m.group(2) or "").lower()
        if "khz" in unit or "khz" in key.lower():
            rate *= 1e3
        elif unit and not (unit.startswith(("hz", "sps", "samples", "s/s", "muestras"))):
            continue
        if math.isfinite(rate) and rate > 0:
            return rate, lineno, key
    return None


def _scale_from_meta(pairs):
    """(factor counts->SI, si unit, line, text) from a 'N counts per <unit>' metadata pair, or None."""
    for lineno, key, value in pairs:
        m = _SCALE.search(f"{value}")
        if not m:
            continue
        per = float(m.group(1).replace(",", "."))
        unit = parse_unit(m.group(2))
        if unit is None or unit.factor is None or not per > 0:
            continue
        return unit.factor / per, unit, lineno, f"{key}: {value}"
    return None


def _metadata(lines, indices, delim: str, dec: str):
    """(pairs, free): ``(line, key, value)`` of the metadata lines among ``lines[indices]``, and their free text."""
    pairs, free = [], []
    for i in indices:
        key, value = _meta_pair(lines[i], delim, dec)
        if key is None:
            if value:
                free.append(value)
        else:
            pairs.append((i + 1, key, value))
    return pairs, free


def _header_from_meta(pairs, n: int):
    """(column names, line, key) from a metadata line naming ``n`` columns (GCDC's ``Headers``), or None.

    The keys are the profiles' ``header_keys`` (:mod:`vibkit.io.text.loggers`).
    """
    keys = header_keys()
    for lineno, key, value in pairs:
        if key.lower() in keys and isinstance(value, str):
            cells = [c.strip() for c in re.split(r"[,;\t]", value)]
            if len(cells) == n:
                return cells, lineno, key
    return None


#: metadata keys that name when a recording started (a logger's, a person's): English, German, Spanish
_START_KEY = re.compile(
    r"(start|start[ _-]?(time|date|datetime)|starttime|started|begin|beginn|date|datum|date[ _-]?time|recorded|"
    r"recording[ _-]?(start|date|time)|aufnahme(beginn)?|fecha|inicio|fecha[ _-]?(de[ _-]?)?inicio)",
    re.IGNORECASE,
)
_DMY_DOTS = re.compile(r"(\d{1,2})\.(\d{1,2})\.(\d{4}|\d{2})(?:[ T,]+(\d{1,2}:\d{2}(?::\d{2}(?:\.\d+)?)?))?")
_DMY_SLASH = re.compile(r"(\d{1,2})/(\d{1,2})/(\d{4})(?:[ T,]+(\d{1,2}:\d{2}(?::\d{2}(?:\.\d+)?)?))?")
_YMD_SLASH = re.compile(r"(\d{4})/(\d{1,2})/(\d{1,2})(?:[ T,]+(\d{1,2}:\d{2}(?::\d{2}(?:\.\d+)?)?))?")


class AmbiguousDate(ValueError):
    """A slashed date whose day and month could be either way round (05/04/2026)."""


def _start_value(text):
    """An ISO 8601 text of a start written as ISO 8601, day.month.year (German; a two-digit year is 20yy),
    year/month/day or a slashed date whose day is above 12, with an optional time; None for anything else.
    Raises :class:`AmbiguousDate` for a slashed date that may be day/month or month/day (not guessed)."""
    s = str(text).strip()
    d = None
    try:
        d = datetime.fromisoformat(s.replace("Z", "+00:00"))
    except ValueError:
        m = _DMY_SLASH.fullmatch(s)
        if m:
            a, b = int(m.group(1)), int(m.group(2))
            if a <= 12 and b <= 12 and a != b:
                raise AmbiguousDate(s) from None
            if a <= 12 < b:  # month/day
                s = f"{b}.{a}.{m.group(3)}" + (f" {m.group(4)}" if m.group(4) else "")
            else:
                s = f"{a}.{b}.{m.group(3)}" + (f" {m.group(4)}" if m.group(4) else "")
        for rx, order in ((_DMY_DOTS, (3, 2, 1)), (_YMD_SLASH, (1, 2, 3))):
            m = rx.fullmatch(s)
            if m:
                y, mo, da = (int(m.group(i)) for i in order)
                y = y + 2000 if y < 100 else y
                try:
                    d = datetime.fromisoformat(f"{y:04d}-{mo:02d}-{da:02d}" + (f"T{m.group(4)}" if m.group(4) else ""))
                except ValueError:
                    return None
    if d is None or not 1970 <= d.year <= 2100:
        return None
    return d.isoformat()


def start_from_meta(pairs):
    """``(ISO 8601 start or None, line, key, value)`` from the first metadata line that names a start
    (``start``, ``date``, ``Datum``, ``recorded`` ...; :data:`_START_KEY`) with a date it can read, else None; the
    start is None (and the line given) where the date may be day/month or month/day."""
    ambiguous = None
    for lineno, key, value in pairs:
        if isinstance(value, str) and _START_KEY.fullmatch(key.strip()):
            try:
                iso = _start_value(value)
            except AmbiguousDate:
                ambiguous = ambiguous or (None, lineno, key, value)
                continue
            if iso is not None:
                return iso, lineno, key, value
    return ambiguous
