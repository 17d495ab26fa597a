"""Columns of a text recording: their names, which are channels, and the channels' values in SI units."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ...runtime.reader_options import ReaderOptionError, as_flags, spell
from ..channels import COUNTER_ATTR, is_counter_name, is_counter_ramp
from ..errors import RecordingError
from ..recording import Channel, safe_name, unique_names
from .cells import _parse_numbers
from .units import parse_unit, split_name_unit

__all__ = []


@dataclass
class _ColumnNames:
    """The names of a file's columns, in the three forms a user may give."""

    split: list  # (name without unit, unit text or None, note or None) per column
    names: list  # name without unit
    vars: list  # variable name in the dataset
    shown: list  # the header as found, or 'column <k>'

    def match(self, want):
        """The index of the column ``want`` names, or None."""
        return _match_column(want, self.shown, self.names, self.vars)


def _column_names(header, n, unit_row, header_line, unit_line, history) -> _ColumnNames:
    """Names of the ``n`` columns from the header row (or None) and the units row below it (or None)."""
    if header is None:
        header = [f"column {j + 1}" for j in range(n)]
        history.append(f"no header row; columns named channel_0 ... channel_{n - 1}")
        split_names = [(f"channel_{j}", None, None) for j in range(n)]
    else:
        split_names = [split_name_unit(h) if h else (f"channel_{j}", None, None) for j, h in enumerate(header)]
    if unit_row is not None and header_line is not None:
        for j, u in enumerate(unit_row):
            u = u.strip("()[]{} ")
            if u and split_names[j][1] is None:
                split_names[j] = (split_names[j][0], u, None)
        history.append(f"units row on line {unit_line}")
    names = [s[0] for s in split_names]
    vars_ = unique_names([safe_name(nm, f"channel_{j}") for j, nm in enumerate(names)])
    vars_ = [v + "_channel" if v in ("time", "segment") else v for v in vars_]
    header_disp = [h if h else f"column {j + 1}" for j, h in enumerate(header)]
    return _ColumnNames(split_names, names, vars_, header_disp)


def _match_column(want, headers, names, vars_):
    w = " ".join(str(want).split()).lower()
    for j in range(len(headers)):
        if w in (" ".join(str(headers[j]).split()).lower(), names[j].lower(), vars_[j].lower()):
            return j
    return None


def _select_channels(path, channel, tcol, colnames: _ColumnNames, n, header_line, clocks=()):
    """(indices of the channel columns, whether the caller named them); clock columns only when named."""
    header_disp = colnames.shown
    chan_idx = [j for j in range(n) if j != tcol and j not in clocks]
    explicit = channel is not None
    if explicit:
        wanted = [channel] if isinstance(channel, str) else list(channel)
        picked = []
        for w in wanted:
            j = colnames.match(w)
            if j is None or j == tcol:
                raise RecordingError(
                    path,
                    header_line,
                    f"no channel {w!r}; channels: " + ", ".join(repr(header_disp[k]) for k in range(n) if k != tcol),
                )
            picked.append(j)
        chan_idx = list(dict.fromkeys(picked))
    if not chan_idx:
        raise RecordingError(path, header_line, "no data column besides the time column")
    return chan_idx, explicit


def _unit_overrides(path, units, chan_idx, colnames: _ColumnNames):
    """{column index: unit text} from the ``units`` option."""
    header_disp = colnames.shown
    if units is not None and not isinstance(units, (str, dict)):
        raise ValueError(f"units must be a unit string or a dict column -> unit, got {type(units).__name__}")
    override = {}
    if isinstance(units, dict):
        for key, u in units.items():
            j = colnames.match(key)
            if j is None:
                given = spell("units", {key: u}) if as_flags() else "units"  # --units NAME=UNIT
                raise ReaderOptionError(
                    "units",
                    f"{given}: no column {key!r} in {path}; columns: " + ", ".join(repr(h) for h in header_disp),
                )
            override[j] = u
    elif isinstance(units, str):
        override = {j: units for j in chan_idx}
    return override


def _build_channels(
    path, cols, rownums, dec, chan_idx, explicit, override, colnames: _ColumnNames, scale_meta, header_line, history
):
    """The channels of columns ``chan_idx``, in SI units where the unit is known."""
    header_disp, split_names, vars_ = colnames.shown, colnames.split, colnames.vars
    channels = []
    for j in chan_idx:
        head = header_disp[j]
        nm, unit_text, note = split_names[j]
        cells = cols[j]
        vals, missing, bad, inf = _parse_numbers(cells, dec)
        if bad.size and bad.size == np.count_nonzero(~missing) and not explicit and len(chan_idx) > 1:
            history.append(f"column '{head}' holds text, not numbers; skipped")
            continue
        if bad.size:
            i = int(bad[0])
            raise RecordingError(path, int(rownums[i]), f"expected a number in column '{head}', found '{cells[i]}'")
        if inf.size:  # an infinity is no measurement: missing like NaN (interpolated or cut as NaN is), and said so
            vals = vals.copy()
            vals[inf] = np.nan
            history.append(
                f"column '{head}': {inf.size} infinite value(s) (first on line {int(rownums[int(inf[0])])}) read "
                "as missing, like NaN"
            )
        nmiss = int(np.count_nonzero(np.isnan(vals)))
        if nmiss == vals.size:
            msg = (
                f"all values in column '{head}' are missing (NaN or empty), lines "
                f"{rownums[0]}-{rownums[-1]}; expected numbers"
            )
            if explicit or len(chan_idx) == 1:
                raise RecordingError(path, None, msg)
            history.append(msg.replace("; expected numbers", "; column skipped"))
            continue
        if nmiss:
            history.append(f"column '{head}': {nmiss} missing value(s) kept as NaN")
        attrs = {"column": head, "source_name": head}
        named = is_counter_name(nm) and unit_text is None and np.all(np.isnan(vals) | (vals == np.round(vals)))
        if named or is_counter_ramp(vals):
            attrs[COUNTER_ATTR] = 1
            why = "its name" if named else "a +1 integer ramp"
            history.append(f"column '{head}' counts samples ({why}); kept as a coordinate, not a channel")
            if explicit:
                attrs["requested"] = 1
        if j in override:
            u_text = override[j]
            unit = parse_unit(u_text) if isinstance(u_text, str) else None
            if unit is None:
                raise ReaderOptionError(
                    "units",
                    f"{spell('units', {head: u_text}) if as_flags() else f'units[{head!r}]={u_text!r}'} (for {path}) "
                    "is not a unit vibkit knows; expected e.g. "
                    "'m/s^2', 'g', 'mm', 'm', 'mm/s', 'counts' or a scaled one like 'g/2048'",
                )
            source = f"{u_text} (given)"
        elif unit_text is not None:
            unit = parse_unit(unit_text)
            source = unit_text
            if note:
                history.append(note)
        else:
            unit, source = None, None
        if (unit is None and unit_text is None or unit is not None and unit.factor is None) and scale_meta:
            factor, su, lineno, stext = scale_meta
            history.append(
                f"column '{head}' in counts, scale from header line {lineno} ('{stext}') -> {su.si} (x {factor:.9g})"
            )
            vals = vals * factor
            attrs["original_units"] = "counts"
            ch_units, quantity = su.si, su.quantity
        elif unit is None:
            if unit_text is None:
                history.append(
                    f"column '{head}' has no unit; values kept as found (units 'unknown'; "
                    f"pass {spell('units', {vars_[j]: '...'})})"
                )
                ch_units = "unknown"
            else:
                history.append(f"unit '{unit_text}' of column '{head}' not recognised; values kept as found")
                ch_units = unit_text
            quantity = "other"
        elif unit.factor is None:
            history.append(
                f"column '{head}' in counts with no scale; kept in counts "
                f"(pass {spell('units', {vars_[j]: 'g/<counts per g>'})})"
            )
            ch_units, quantity = "counts", "other"
            attrs["original_units"] = source
        else:
            if unit.factor != 1.0:
                history.append(f"column '{head}' in {source} -> {unit.si} (x {unit.factor:.9g})")
                vals = vals * unit.factor
            elif j in override:
                history.append(f"column '{head}' in {source}")
            attrs["original_units"] = unit.text
            ch_units, quantity = unit.si, unit.quantity
        channels.append(Channel(vars_[j], vals, ch_units, nm, quantity, attrs))
    if not channels:
        raise RecordingError(path, header_line, "no numeric data column found")
    return channels
