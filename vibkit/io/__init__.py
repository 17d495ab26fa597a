"""Read field recordings and write vibkit results.

:func:`read_recording` turns a file into a recording (an :class:`xarray.Dataset`
following vibkit's data contract), choosing the reader by content and suffix from
the table in :mod:`vibkit.io.registry`, in this order:

* MATLAB MAT-files (v5 and v7.3) -> :mod:`vibkit.io.matlab`; plain HDF5 (not netCDF) -> :mod:`vibkit.io.hdf5`;
* netCDF4/HDF5 (vibkit's own results; signature ``\\x89HDF``) and netCDF3
  (``CDF\\x01``) -> :mod:`vibkit.io.netcdf`;
* WAV, NI TDMS, UFF/UNV dataset 58 -> :mod:`vibkit.io.wav`, :mod:`vibkit.io.tdms`, :mod:`vibkit.io.uff`;
* waveform formats obspy reads (miniSEED, SAC, ...: by suffix, or binary content
  that is not HDF5) -> :mod:`vibkit.io.seismic`;
* gzip and zip files holding one recording: unpacked, the recording read as below;
* device exports with their own header (Empatica E4, ActiGraph RAW CSV, LabVIEW ``.lvm``)
  -> :mod:`vibkit.io.devices`, :mod:`vibkit.io.lvm`; a WitMotion binary log is named and refused;
* text (CSV, TSV, logger and spreadsheet exports) -> :mod:`vibkit.io.text.csv`.

Every dataset carries ``source_file``, ``sha256``, ``reader``,
``sample_rate_hz`` and ``history`` (each decision on its own line).
A file that cannot be read honestly raises :class:`RecordingError`, whose
``str()`` is one line naming the file, the line and what was expected.
"""

from __future__ import annotations

import math
import os
import stat
from typing import TYPE_CHECKING

from ..runtime.reader_options import READER_OPTIONS, ReaderOptionError, either
from . import largefile
from .channels import resolve_channel
from .errors import RecordingError
from .largefile import LargeFile
from .limits import _MAX_ENV, DEFAULT_MAX_RECORDING_BYTES, _gib, max_recording_bytes
from .netcdf import write_result
from .phone import phone_export_folder, read_phone_export
from .registry import NETCDF_SUFFIXES, SEISMIC_SUFFIXES, detect_format, format_names, get_format
from .text.fastpath import _HEAD_BYTES
from .text.layout import streamable_text

if TYPE_CHECKING:  # for the annotations only: importing vibkit.io stays cheap
    import xarray

__all__ = [
    "source_name",
    "read_recording",
    "write_result",
    "resolve_channel",
    "RecordingError",
    "SEISMIC_SUFFIXES",
    "NETCDF_SUFFIXES",
    "DEFAULT_MAX_RECORDING_BYTES",
    "max_recording_bytes",
    "format_names",
]


def read_bounded(f, size_hint: int, limit: int) -> bytes:
    """At most ``limit + 1`` bytes of the binary stream ``f``, with memory in proportion to what it holds.

    The first read asks for the size the file states (``size_hint`` + 1, at least 64 KiB), so a
    regular file is read in one call; a stream that holds more (a file that grows, ``/proc``,
    stdin) is read on in chunks that double, never past ``limit + 1``: a buffer of the limit's
    size is never reserved up front.
    """
    want = min(limit + 1, max(int(size_hint) + 1, 1 << 16))
    data = f.read(want)
    if len(data) < want:
        return data
    chunks, total = [data], len(data)
    while total <= limit:
        chunk = f.read(min(limit + 1 - total, max(total, 1 << 20)))
        if not chunk:
            break
        chunks.append(chunk)
        total += len(chunk)
    return b"".join(chunks)


#: bytes of a file's head looked at before the rest is read (the registry's sniffers see as many)
HEAD_BYTES = 1 << 16


def check_head(spath: str, head: bytes) -> None:
    """Refuse, from its head alone, a file no reader can make a recording of before the whole file is read and
    scanned (obspy would look for every waveform format through a 2 GB file of zero bytes for minutes)."""
    if len(head) >= 512 and not head.strip(b"\x00"):
        raise RecordingError(
            spath,
            None,
            f"its first {_gib_or_kib(len(head))} are zero bytes: not a recording (a file never written, or a "
            "disk image); nothing read past them",
        )


def _gib_or_kib(n: int) -> str:
    return f"{n // 1024} KiB" if n % 1024 == 0 else f"{n} bytes"


def _open_checked(spath: str, limit: int, stream: bool = False):
    """Open a regular file for reading, refusing anything else before it is opened.

    Returns its bytes, or with ``stream`` a :class:`~vibkit.io.largefile.LargeFile` (its head) for a file
    over :data:`vibkit.io.largefile.STREAM_BYTES`."""
    if not os.path.lexists(spath):
        raise RecordingError(spath, None, "file not found")
    try:
        st = os.stat(spath)
    except OSError as exc:
        raise RecordingError(spath, None, f"cannot be read: {exc.strerror or exc}") from None
    mode = st.st_mode
    if stat.S_ISDIR(mode):
        raise RecordingError(spath, None, "is a folder, expected a file")
    if not stat.S_ISREG(mode):
        kind = (
            "a named pipe (FIFO)"
            if stat.S_ISFIFO(mode)
            else "a character device"
            if stat.S_ISCHR(mode)
            else "a block device"
            if stat.S_ISBLK(mode)
            else "a socket"
            if stat.S_ISSOCK(mode)
            else "not a regular file"
        )
        raise RecordingError(spath, None, f"is {kind}, not a regular file; expected a recording file on disk")
    if st.st_size > limit:
        raise RecordingError(
            spath,
            None,
            f"is {_gib(st.st_size)}, larger than the {_gib(limit)} limit for a "
            f"recording (raise it with {either('max_bytes', f'the environment variable {_MAX_ENV}')})",
        )
    try:
        fd = os.open(spath, os.O_RDONLY | getattr(os, "O_NONBLOCK", 0) | getattr(os, "O_NOCTTY", 0))
    except OSError as exc:
        raise RecordingError(spath, None, f"cannot be read: {exc.strerror or exc}") from None
    try:  # the path may have been swapped between stat and open
        st2 = os.fstat(fd)
        if not stat.S_ISREG(st2.st_mode):
            raise RecordingError(spath, None, "is not a regular file; expected a recording file on disk")
        with os.fdopen(fd, "rb", closefd=False) as f:
            check_head(spath, f.read(HEAD_BYTES))
            f.seek(0)
            if stream and st2.st_size > largefile.STREAM_BYTES:  # the head only: the text reader streams the rest
                return LargeFile(spath, st2.st_size, f.read(_HEAD_BYTES), limit)
            data = read_bounded(f, st2.st_size, limit)
    except OSError as exc:
        raise RecordingError(spath, None, f"cannot be read: {exc.strerror or exc}") from None
    finally:
        os.close(fd)
    if len(data) > limit:
        raise RecordingError(
            spath,
            None,
            f"holds more than the {_gib(limit)} limit for a recording "
            f"(raise it with {either('max_bytes', f'the environment variable {_MAX_ENV}')})",
        )
    return data


def _check_options(sample_rate, resample, gap_factor, delimiter, decimal, date_order=None):
    if sample_rate is not None:
        try:
            fs = float(sample_rate)
        except (TypeError, ValueError):
            fs = math.nan
        if not (math.isfinite(fs) and fs > 0):
            raise ReaderOptionError("sample_rate", f"sample_rate must be a positive number of Hz, got {sample_rate!r}")
    if resample not in (None, "linear"):
        raise ReaderOptionError(
            "resample", f"resample must be None (keep the samples as they are) or 'linear', got {resample!r}"
        )
    try:
        gf = float(gap_factor)
    except (TypeError, ValueError):
        gf = math.nan
    if not (math.isfinite(gf) and gf > 1):
        raise ReaderOptionError("gap_factor", f"gap_factor must be a number of sample periods > 1, got {gap_factor!r}")
    if delimiter is not None and delimiter not in (",", ";", "\t", "|", " "):
        raise ReaderOptionError(
            "delimiter", f"delimiter must be one of ',', ';', '\\t', '|', ' ' (whitespace), got {delimiter!r}"
        )
    if decimal is not None and decimal not in (".", ","):
        raise ReaderOptionError("decimal", f"decimal must be '.' or ',', got {decimal!r}")
    if date_order is not None and date_order not in ("dmy", "mdy"):
        raise ReaderOptionError(
            "date_order", f"date_order must be 'dmy' (day/month/year) or 'mdy' (month/day/year), got {date_order!r}"
        )


#: the path that names standard input (``vibkit pitch -``); its records name it :data:`STDIN_NAME`
STDIN = "-"
STDIN_NAME = "<stdin>"


def source_name(path) -> str:
    """The name messages and results give the recording at ``path``: :data:`STDIN_NAME` for ``-``."""
    path = os.fspath(path)
    return STDIN_NAME if path == STDIN else path


_stdin_read: list = [None, b""]  # the stream read and its bytes


def _read_stdin(fmt, limit, options):
    """Read a recording from standard input: its bytes (bounded by ``limit``), sniffed like a file's.

    Standard input is read once per process (a second read of ``"-"`` gets the same bytes).
    The text reader reads the bytes; a format whose library opens a path (netCDF, obspy's) gets
    them in a temporary file that is removed after the read, and its messages name ``<stdin>``.
    """
    import sys
    import tempfile

    stream = getattr(sys.stdin, "buffer", sys.stdin)
    if stream is None or stream.isatty():
        raise RecordingError(STDIN_NAME, None, "standard input is a terminal; pipe a recording into it (cat rec.csv |)")
    if stream is not _stdin_read[0]:  # read once: a second read of "-" (a retry with --channel) gets the same bytes
        try:
            _stdin_read[:] = [stream, read_bounded(stream, 0, limit)]
        except OSError as exc:
            raise RecordingError(STDIN_NAME, None, f"cannot be read: {exc.strerror or exc}") from None
    data = _stdin_read[1]
    if len(data) > limit:
        raise RecordingError(
            STDIN_NAME,
            None,
            f"holds more than the {_gib(limit)} limit for a recording "
            f"(raise it with {either('max_bytes', f'the environment variable {_MAX_ENV}')})",
        )
    if not data:
        raise RecordingError(STDIN_NAME, None, "is empty (0 bytes); expected a recording")
    entry = detect_format(STDIN_NAME, data, options["encoding"]) if fmt is None else fmt
    if entry.name == "text":
        return entry.read(STDIN_NAME, data, options)
    with tempfile.TemporaryDirectory(prefix="vibkit-stdin-") as folder:
        tmp = os.path.join(folder, "stdin" + (".nc" if entry.name == "netcdf" else ""))
        with open(tmp, "wb") as f:
            f.write(data)
        try:
            ds = entry.read(tmp, data, options)
        except RecordingError as err:
            raise RecordingError(STDIN_NAME, err.line, err.message.replace(tmp, STDIN_NAME)) from None
    ds.attrs["source_file"] = STDIN_NAME
    return ds


def _head(folder, name, size=512):
    """The first ``size`` bytes of a file in a folder (empty for a folder or a file that cannot be read)."""
    try:
        with open(os.path.join(folder, name), "rb") as f:
            return f.read(size)
    except OSError:
        return b""


def read_recording(
    path: str | os.PathLike[str],
    *,
    channel: str | list[str] | None = None,
    sample_rate: float | None = None,
    time_column: str | int | bool | None = None,
    time_unit: str | None = None,
    units: str | dict[str, str] | None = None,
    resample: str | None = None,
    gap_factor: float = 5.0,
    repair_time: bool = False,
    delimiter: str | None = None,
    decimal: str | None = None,
    encoding: str | None = None,
    max_bytes: int | None = None,
    format: str | None = None,
    date_order: str | None = None,
) -> xarray.Dataset:
    """Read a field recording (or a vibkit result) into an xarray Dataset.

    Parameters
    ----------
    path : str or os.PathLike
        CSV/text export, waveform file (miniSEED, SAC ...) or netCDF4/HDF5; ``"-"`` reads standard
        input (its format sniffed from its bytes; the result's ``source_file`` is ``<stdin>``).
    channel : str or list of str, optional
        Keep only these channels, matched (case-insensitively) against the
        column header as found, its name without unit, or the variable name;
        for waveform files the trace id, its variable name or channel code.
    sample_rate : float, optional
        Nominal sample rate. [Hz]  Required for a text file with no time column
        and no sample rate in its header; otherwise it overrides the nominal
        rate (used by ``resample="linear"``).
    time_column : str, int or False, optional
        The time column by name or 0-based index; False: the file has none.
        Default: the first column named like time (``time``, ``Time (s)``,
        ``Tiempo (ms)``, ``timestamp`` ...).
    time_unit : str, optional
        Unit of a numeric time column ("s", "ms", "us" ...), overriding the header.
    units : str or dict, optional
        Unit of every channel (str) or per channel (dict name -> unit), overriding
        the header: "m/s^2", "g", "mm", "m", "mm/s", "counts" or scaled counts
        such as "g/2048" (one count is 1/2048 g).
    resample : {None, "linear"}
        None keeps the samples and their time stamps as they are; "linear"
        resamples each segment to the nominal rate by linear interpolation.
    gap_factor : float
        A time step longer than this many median periods splits the recording
        into segments (bursts), which are never bridged.
    repair_time : bool
        False (default): time going backwards or repeated stamps are errors.
        True: sort by time and drop repeated stamps (first kept), recorded.
    delimiter : str, optional
        Text files: force the delimiter (",", ";", "\\t", "|", " " for whitespace).
    decimal : {".", ","}, optional
        Text files: force the decimal mark.
    encoding : str, optional
        Text files: force the encoding (default: UTF-8, else cp1252; UTF-16/32
        when the file starts with a byte-order mark).
    max_bytes : int, optional
        Refuse files larger than this. [bytes]  Default: the environment
        variable ``VIBKIT_MAX_RECORDING_BYTES``, else 4 GiB.  Only regular
        files are read: a folder, FIFO, device or socket is refused before it
        is opened.
    format : str, optional
        Read the file with this entry of the reader table (one of
        :func:`format_names`: ``"matlab"``, ``"hdf5"``, ``"netcdf"``, ``"wav"``, ``"uff"``,
        ``"seismic"``, ``"text"`` ...) instead of
        the one its content and suffix choose (see :mod:`vibkit.io.registry`).

    date_order : {"dmy", "mdy"}, optional
        Text files: the order of numeric dates ``05/11/2025``.  Default: the order a field above
        12 shows; dates that could be either are refused, naming this option.

    Returns
    -------
    xarray.Dataset
        Dimension ``time``; coordinate ``time`` [s]; one float64 variable per
        channel in SI units (attrs ``units``, ``long_name``, ``quantity``,
        ``column``); int32 ``segment`` when made of bursts; attrs
        ``source_file``, ``sha256``, ``reader``, ``sample_rate_hz`` [Hz],
        ``history`` and the metadata found in the file; files with a time
        column also get ``segment_count`` and ``time_jitter_rms_percent``,
        timestamped ones ``start_time``.

    Raises
    ------
    RecordingError
        The file is missing, empty, binary garbage or malformed (header only,
        text in numbers, ragged rows, time going backwards, one sample, all NaN
        ...); the message names the file and, where one applies, the line.
    ValueError
        An option is invalid (the message names it).

    Examples
    --------
    >>> ds = read_recording("data/field/leon-tensioner.csv")  # doctest: +SKIP
    >>> ds["tensioner_displacement"].attrs["units"]  # doctest: +SKIP
    'm'
    """
    _check_options(sample_rate, resample, gap_factor, delimiter, decimal, date_order)
    fmt = None if format is None else get_format(format)
    if not isinstance(path, (str, os.PathLike)):
        raise ValueError(f"path must be a file path (str or os.PathLike), got {type(path).__name__}")
    given = locals()
    # the readers' options, as vibkit.io.reader_options declares them (max_bytes and format are this function's)
    options = {o.name: given[o.name] for o in READER_OPTIONS if o.scope != "open"}
    spath = os.fspath(path)
    if spath == STDIN:
        return _read_stdin(fmt, max_recording_bytes(max_bytes), options)
    if os.path.isdir(spath):
        folder = phone_export_folder(spath, _head)
        if folder is None:
            listed = ", ".join(sorted(os.listdir(spath))[:8]) or "empty"
            raise RecordingError(
                spath,
                None,
                f"is a folder with no phone sensor files ({listed}); expected a recording file, or a phone export's "
                "folder or zip (accelerometer.csv, gyro.csv, barometer.csv ...)",
            )
        ds = read_phone_export(folder, options)
        if folder != spath:
            ds.attrs["history"] = f"folder {spath}: its phone export {os.path.basename(folder)}/ read\n" + str(
                ds.attrs.get("history", "")
            )
        return ds
    data = _open_checked(spath, max_recording_bytes(max_bytes), stream=True)
    if isinstance(data, LargeFile):
        entry = detect_format(spath, data.head, encoding) if fmt is None else fmt
        if entry.name == "text" and encoding is None and streamable_text(data.head):
            return entry.read(spath, data, options)  # streamed in bounded memory
        data = data.read_all()
    if not data:
        raise RecordingError(spath, None, "file is empty (0 bytes); expected a recording")
    entry = detect_format(spath, data, encoding) if fmt is None else fmt
    return entry.read(spath, data, options)
