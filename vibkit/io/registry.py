"""Which reader reads a file: one table of formats, each a sniffer and a reader, tried in a fixed order.

:func:`vibkit.io.read_recording` checks the path and the options, reads the file's bytes once, and
hands them to the first entry of :data:`FORMATS` whose sniffer claims them, or to the entry the user
names with ``format=``; a text file over :data:`vibkit.io.largefile.STREAM_BYTES` is handed to the ``text``
entry as a :class:`~vibkit.io.largefile.LargeFile` (its head; the reader streams the rest), and to any other
entry as its bytes.  The order of :data:`FORMATS` is the priority, and it is fixed:

1. ``matlab`` and ``hdf5``: MATLAB MAT-files (a ``MATLAB 5.0``/``MATLAB 7.3 MAT-file`` header, or the
   ``.mat`` suffix; :mod:`vibkit.io.matlab`), plain HDF5 (signature ``\\x89HDF`` without netCDF-4's
   attributes in the first bytes, no netCDF suffix; :mod:`vibkit.io.hdf5`, which hands a netCDF-4
   file it meets to the netCDF reader);
2. ``netcdf``: netCDF4/HDF5 (signature ``\\x89HDF``) or netCDF3 (``CDF\\x01``, ``CDF\\x02``) by
   content, or a suffix of :data:`NETCDF_SUFFIXES` whatever the content (vibkit's own results,
   read by :mod:`vibkit.io.netcdf`);
3. ``gzip`` and ``zip``: containers by signature (``\\x1f\\x8b``, ``PK\\x03\\x04``), unpacked, the one
   recording inside read by the entry that claims it (:mod:`vibkit.io.devices`); before ``zip``,
   ``spreadsheet``: Excel and OpenDocument workbooks (the OLE2 signature, an ``.xlsx`` zip's ``xl/`` members,
   or the suffix) named and refused, asking for CSV;
4. ``witmotion``: WitMotion WT901 SD-card logs (valid ``0x55`` packets): named and refused, saying
   what reads them;
5. ``wav``, ``tdms``, ``uff``: WAV (``RIFF....WAVE``), NI TDMS (``TDSm`` or ``.tdms``, read by npTDMS,
   the ``tdms`` extra), UFF/UNV (a ``-1`` delimiter line and a dataset number, any suffix: UFF is
   never read as CSV) (:mod:`vibkit.io.wav`, :mod:`vibkit.io.tdms`, :mod:`vibkit.io.uff`); ``ide``: enDAQ
   ``.ide`` (EBML with DocType ``mide``, or the suffix; read by idelib, the ``ide`` extra; :mod:`vibkit.io.ide`);
6. ``seismic``: a suffix of :data:`SEISMIC_SUFFIXES` whatever the content, binary content (a NUL
   byte in the first 64 KiB that is not UTF-16/32 text, unless ``encoding=`` is given), or obspy's
   ASCII layouts that start with a ``TIMESERIES`` line (read by :mod:`vibkit.io.seismic`);
7. ``e4``, ``actigraph``, ``lvm``: text layouts whose header the generic text reader cannot read:
   Empatica E4 (start time and rate rows), ActiGraph RAW CSV (``Data File Created By ActiGraph``
   banner), NI LabVIEW ``.lvm`` (``LabVIEW Measurement``) (:mod:`vibkit.io.devices`, :mod:`vibkit.io.lvm`);
8. ``text``: everything else: CSV, TSV, logger and spreadsheet exports (read by
   :mod:`vibkit.io.text.csv`, which refuses what is not text).

A content signature beats a suffix only where the entry with the signature comes first; the last
entry claims every file, so every file has a reader and the choice never depends on anything but
the file's name, its bytes and ``encoding=``.

Adding a format or a logger
---------------------------
A new *file format* (a binary logger, a compressed container) is one :class:`Format` entry in
:data:`FORMATS`, placed before the first entry that would otherwise claim its files (before
``seismic`` for binary content, before ``text`` for a text layout that the text reader cannot
read), with

* ``sniff(probe)``: a cheap check of :class:`Probe` (the suffix, the first 64 KiB, the options);
  it must not parse the whole file and must not raise;
* ``read(path, data, options)``: the reader (its module imported here, at the top); ``options`` holds every reading option of ``read_recording``
  (all its keywords but ``max_bytes`` and ``format``), and the reader passes on those it understands;
* one test file ``tests/io/test_format_<name>.py`` reading a real file (or one written in the
  documented layout) and asserting that :func:`detect_format` names the entry; a file shipped in
  ``data/`` also gets its line in ``SHIPPED`` of ``tests/io/test_registry.py``.

A container (``.gz``, ``.zip`` of one recording) is an entry like any other: its reader unpacks
``data`` and hands the inner name and bytes to ``detect_format(inner, inner_data).read(...)``.
A binary format vibkit does not read is an entry too: its sniffer knows the signature, and its
reader raises :class:`~vibkit.io.errors.RecordingError` naming the format and what reads it.

A new *text logger or app* (a CSV export whose columns do not say their units, a header line
with the rate under its own key) is not a format: it is one :class:`~vibkit.io.text.loggers.LoggerProfile`
in :data:`vibkit.io.text.loggers.PROFILES` and one test file; see that module.
``tests/io/test_registry.py`` checks that every file shipped in ``data/`` is read by the entry
it lists for it, and that the order above decides between sniffers that both claim a file.
"""

from __future__ import annotations

import os
from dataclasses import dataclass
from typing import Any, Callable

from ..runtime.reader_options import options_of
from . import devices
from .lvm import read_lvm, sniff_lvm
from .netcdf import read_netcdf
from .seismic import read_seismic
from .text.csv import read_csv
from .text.layout import utf16_without_bom

__all__ = [
    "Format",
    "Probe",
    "FORMATS",
    "SEISMIC_SUFFIXES",
    "NETCDF_SUFFIXES",
    "format_names",
    "get_format",
    "detect_format",
]

#: suffixes sent to obspy whatever their content
SEISMIC_SUFFIXES = (
    ".mseed",
    ".miniseed",
    ".msd",
    ".seed",
    ".sac",
    ".gse",
    ".gse2",
    ".segy",
    ".sgy",
    ".su",
    ".ah",
    ".css",
    ".knet",
    ".sh",
    ".q",
)
#: suffixes sent to xarray whatever their content
NETCDF_SUFFIXES = (".nc", ".nc4", ".netcdf", ".h5", ".hdf5", ".he5", ".cdf")
_HDF5 = b"\x89HDF\r\n\x1a\n"
_NETCDF3 = (b"CDF\x01", b"CDF\x02")
_BOMS = (b"\xff\xfe\x00\x00", b"\x00\x00\xfe\xff", b"\xff\xfe", b"\xfe\xff")  # UTF-32/UTF-16 text
#: bytes a sniffer sees at most (the whole file stays in ``data`` for the reader)
HEAD_BYTES = 65536


@dataclass(frozen=True)
class Probe:
    """What a sniffer may look at.

    Attributes
    ----------
    path : str
        The file as given.
    suffix : str
        Its last suffix in lower case (``".csv"``; ``""`` for none).
    head : bytes
        The first :data:`HEAD_BYTES` bytes.
    encoding : str or None
        The ``encoding=`` the user forced (a forced encoding says the file is text).
    """

    path: str
    suffix: str
    head: bytes
    encoding: str | None = None


@dataclass(frozen=True)
class Format:
    """One entry of the reader table.

    Attributes
    ----------
    name : str
        What ``format=`` calls it.
    description : str
        One line: what files it reads.
    sniff : callable
        ``sniff(probe: Probe) -> bool``: whether the entry claims the file.
    read : callable
        ``read(path: str, data: bytes, options: dict) -> xarray.Dataset``.
    """

    name: str
    description: str
    sniff: Callable[[Probe], bool]
    read: Callable[..., Any]


def _sniff_netcdf(p: Probe) -> bool:
    return p.head.startswith(_HDF5) or p.head[:4] in _NETCDF3 or p.suffix in NETCDF_SUFFIXES


def _text_with_nul(p: Probe) -> bool:
    """Whether content with NUL bytes is UTF-16/32 text (a byte-order mark, or UTF-16 without one)."""
    return p.head.startswith(_BOMS) or utf16_without_bom(p.head) is not None


def _sniff_seismic(p: Probe) -> bool:
    if p.suffix in SEISMIC_SUFFIXES:
        return True
    if b"\x00" in p.head and p.encoding is None and not _text_with_nul(p):
        return True  # binary content that is not HDF5/netCDF: obspy reads it or says why not
    # obspy's ASCII layouts (TSPAIR, SLIST) start with a 'TIMESERIES NET_STA_LOC_CHA, N samples, R sps' line
    return p.head.lstrip(b"\xef\xbb\xbf \r\n").startswith(b"TIMESERIES ")


def _read_netcdf(path, data, options):
    return read_netcdf(path, data, channel=options["channel"], repair_time=options["repair_time"])


#: the options every reader takes, and the text reader's (declared once: vibkit.io.reader_options)
_COMMON = options_of("all")
_TEXT_OPTIONS = options_of("text")


def _read_seismic(path, data, options):
    return read_seismic(path, data, units=options["units"], **{k: options[k] for k in _COMMON})


def _container(read):
    """A container's reader (:mod:`vibkit.io.devices`), the entry that reads its one member found by
    :func:`detect_format`."""
    return lambda path, data, options: read(path, data, options, detect_format)


def _read_text(path, data, options):
    return read_csv(path, data, **{k: options[k] for k in _TEXT_OPTIONS})


def _module(module, name):
    """The reader ``name`` of ``vibkit.io.<module>``, imported when called (``read(path, data, options)``)."""

    def read(path, data, options):
        import importlib

        return getattr(importlib.import_module(f"vibkit.io.{module}"), name)(path, data, options)

    return read


def _sniff(module, name):
    """The sniffer ``name`` of ``vibkit.io.<module>``, imported when called (``sniff(probe)``)."""

    def sniff(p):
        import importlib

        return getattr(importlib.import_module(f"vibkit.io.{module}"), name)(p)

    return sniff


#: the reader table, in priority order (see the module docstring)
FORMATS: tuple[Format, ...] = (
    Format(
        "matlab",
        "MATLAB MAT-files: v4/v5/v7 (scipy) and v7.3 (HDF5 with a 'MATLAB 7.3' header), by header or .mat suffix",
        _sniff("matlab", "sniff_matlab"),
        _module("matlab", "read_matlab"),
    ),
    Format(
        "hdf5",
        "plain HDF5 (not netCDF): datasets of samples with a sample_rate/fs attribute or a time dataset",
        _sniff("hdf5", "sniff_hdf5"),
        _module("hdf5", "read_hdf5"),
    ),
    Format(
        "netcdf", "netCDF4/HDF5 and netCDF3 (vibkit's results), by signature or suffix", _sniff_netcdf, _read_netcdf
    ),
    Format(
        "gzip",
        "gzip files (.gz) holding one recording, unpacked and read",
        devices.sniff_gzip,
        _container(devices.read_gzip),
    ),
    Format(
        "spreadsheet",
        "spreadsheet workbooks (Excel .xls/.xlsx, OpenDocument .ods): named and refused, asking for CSV",
        devices.sniff_spreadsheet,
        devices.read_spreadsheet,
    ),
    Format(
        "zip",
        "zip archives holding exactly one recording, unpacked and read",
        devices.sniff_zip,
        _container(devices.read_zip),
    ),
    Format(
        "witmotion",
        "WitMotion WT901 SD-card binary logs (0x55 packets): named and refused, with what reads them",
        devices.sniff_witmotion,
        devices.read_witmotion,
    ),
    Format(
        "wav",
        "WAV files: integer PCM (counts) and 32/64-bit float samples",
        _sniff("wav", "sniff_wav"),
        _module("wav", "read_wav"),
    ),
    Format(
        "tdms",
        "NI TDMS files (needs the tdms extra: npTDMS), by signature 'TDSm' or .tdms suffix",
        _sniff("tdms", "sniff_tdms"),
        _module("tdms", "read_tdms"),
    ),
    Format(
        "uff",
        "Universal File Format (UFF/UNV) dataset 58 time responses, ASCII and binary 58b, by the '-1' delimiter",
        _sniff("uff", "sniff_uff"),
        _module("uff", "read_uff"),
    ),
    Format(
        "ide",
        "enDAQ / Slam Stick .ide recordings (needs the ide extra: idelib), by EBML DocType 'mide' or .ide suffix",
        _sniff("ide", "sniff_ide"),
        _module("ide", "read_ide"),
    ),
    Format(
        "seismic",
        "waveform formats obspy reads (miniSEED, SAC, GSE2, ...): by suffix, binary content or a TIMESERIES line",
        _sniff_seismic,
        _read_seismic,
    ),
    Format(
        "e4",
        "Empatica E4 exports (row 1 start time, row 2 sample rate, then samples; ACC.csv in 1/64 g)",
        devices.sniff_e4,
        devices.read_e4,
    ),
    Format(
        "actigraph",
        "ActiGraph ActiLife RAW CSV ('Data File Created By ActiGraph ... at 30 Hz' banner, values in g)",
        devices.sniff_actigraph,
        devices.read_actigraph,
    ),
    Format("lvm", "NI LabVIEW Measurement files (.lvm)", sniff_lvm, read_lvm),
    Format(
        "text",
        "CSV, TSV, logger and spreadsheet exports (every file no entry above claims)",
        lambda p: True,
        _read_text,
    ),
)


def format_names() -> tuple[str, ...]:
    """The registered format names, in priority order."""
    return tuple(f.name for f in FORMATS)


def get_format(name) -> Format:
    """The entry called ``name`` (``format=`` of :func:`vibkit.io.read_recording`).

    Raises
    ------
    ValueError
        No entry has that name; the message lists the registered names.
    """
    for f in FORMATS:
        if isinstance(name, str) and f.name == name.strip().lower():
            return f
    raise ValueError(f"format must be one of {', '.join(repr(n) for n in format_names())}, got {name!r}")


def detect_format(path, data: bytes, encoding=None) -> Format:
    """The first entry of :data:`FORMATS` whose sniffer claims the file (the last claims every file)."""
    probe = Probe(os.fspath(path), os.path.splitext(os.fspath(path))[1].lower(), data[:HEAD_BYTES], encoding)
    for f in FORMATS:
        if f.sniff(probe):
            return f
    raise AssertionError("the last entry of FORMATS claims every file")  # pragma: no cover
