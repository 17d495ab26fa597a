"""The PDF diagnostic report of a recording: :func:`write_report` analyses it once
(:func:`~vibkit.diagnose.report.context.analyse`) and calls one page function per page kind, in the
order of :data:`PAGES` (a list of :class:`PageBuilder`).

The pages: the verdict (page 1), the recording and escalator, time signal with events, spectrum with harmonic markers, spectrogram,
order spectrum, ride quality (when it can be assessed), one page per escalator ride found in a phone's walk, simulation against recording and harmonics (given a
scene), data quality, parameters, glossary.  Every page is headed by the unit, the recording, its date, the
chain speed and "page n of N"; page 1 says why any page is absent.  The report is dated now; with ``SOURCE_DATE_EPOCH`` set the same
inputs give the same bytes (nothing random is drawn).
"""

from __future__ import annotations

import os
from collections.abc import Callable
from dataclasses import dataclass, field

from ... import __version__
from ...runtime.report_options import ReportOptions, takes_report_options
from ...runtime.safe_output import check_output_path
from .appendix import data_quality_page, glossary_page, parameters_page
from .common import PageSink, Report, _pdf_in_memory, speed_value
from .comparison_pages import harmonics_page, simulation_page
from .context import analyse
from .links_page import links_page
from .ride_pages import ride_pages_absent, ride_quality_pages
from .rides_pages import phone_ride_pages, phone_rides_absent
from .signal_pages import order_spectrum_page, spectrogram_page, spectrum_page, time_signal_page
from .verdict import recording_page, verdict_page

__all__ = ["PAGES", "PageBuilder", "write_report", "page_header"]


@dataclass(frozen=True)
class PageBuilder:
    """One kind of page of the report.

    Attributes
    ----------
    name : str
        The page's name as page 1 lists it when absent.
    draw : callable
        ``draw(doc, ctx)`` with ``doc`` a :class:`~vibkit.diagnose.report.common.PageSink` and ``ctx`` a
        :class:`~vibkit.diagnose.report.context.ReportContext`; emits zero or more pages (one per ride, say).
    absent : callable
        ``absent(ctx)``: why this report has none of these pages (one line for page 1), or "" when it has.
    """

    name: str
    draw: Callable
    absent: Callable = field(default=lambda ctx: "")


def _no_order_spectrum(ctx):
    return "" if ctx.found else "no link pass found, so nothing to resample to constant link-pass phase"


def _no_links(ctx):
    if ctx.links is not None:
        return ""
    return "the links were not scanned (why: 'worn links' under Evidence)" if ctx.links_note else "not scanned"


def _no_comparison(ctx):
    return "" if ctx.comparison is not None else ctx.comparison_absent or "no simulation compared"


#: the report's pages, in page order (a new kind of page: one more :class:`PageBuilder`)
PAGES = [
    PageBuilder("verdict", verdict_page),
    PageBuilder("recording and escalator", recording_page),
    PageBuilder("time signal", time_signal_page),
    PageBuilder("spectrum", spectrum_page),
    PageBuilder("spectrogram", spectrogram_page),
    PageBuilder("order spectrum", order_spectrum_page, _no_order_spectrum),
    PageBuilder("links", links_page, _no_links),
    PageBuilder("ride quality", ride_quality_pages, ride_pages_absent),
    PageBuilder("escalator rides (phone)", phone_ride_pages, phone_rides_absent),
    PageBuilder("simulation against recording", simulation_page, _no_comparison),
    PageBuilder("harmonics", harmonics_page, _no_comparison),
    PageBuilder("data quality", data_quality_page),
    PageBuilder("parameters", parameters_page),
    PageBuilder("glossary", glossary_page),
]


def page_header(ctx) -> str:
    """The line that heads every page: unit, recording, measurement date, chain speed."""
    p = ctx.profile
    unit = f"unit {p.unit}" if p is not None and getattr(p, "unit", "") else "unit not named"
    measured = ctx.measurement_date.strftime("%Y-%m-%d") if ctx.measurement_date is not None else "date not stated"
    name = ctx.summary["file"]
    if len(name) > 48:
        name = name[:22] + "..." + name[-23:]
    return f"{unit}  |  {name}  |  measured {measured}  |  chain speed {speed_value(ctx).split(',')[0]}"


@takes_report_options
def write_report(recording, out_path, *, overwrite=False, **options) -> Report:
    """Write the PDF diagnostic report of a recording.

    Parameters
    ----------
    recording : str or os.PathLike
        Recording file (anything :func:`vibkit.read_recording` reads).
    out_path : str or os.PathLike
        PDF to write (atomically); never one of the inputs.
    overwrite : bool
        Replace an existing regular file ``out_path`` (default False: an existing file is refused; the
        CLI passes ``--force``).
    **options

    Returns
    -------
    Report

    Raises
    ------
    ValueError
        The output is one of the inputs or not a ``.pdf``; bad options; or the errors of
        :func:`vibkit.read_recording` and :func:`vibkit.load_scene`.
    """
    opts = ReportOptions.of("write_report", options)
    import matplotlib

    matplotlib.use("Agg")
    from matplotlib.backends.backend_pdf import PdfPages

    out = os.fspath(out_path)
    if not out.lower().endswith(".pdf"):
        raise ValueError(f"output {out!r} must be a .pdf file")
    scene = opts.scene
    inputs = [os.fspath(recording)] + ([os.fspath(scene)] if isinstance(scene, (str, os.PathLike)) else [])
    for p in inputs:
        if os.path.exists(out) and os.path.samefile(out, p):
            raise ValueError(f"output {out!r} is an input file; refusing to overwrite it")
    check_output_path(out, overwrite=overwrite, inputs=inputs)  # before any work
    ctx = analyse(recording, **opts.as_dict())
    date, summary = ctx.date, ctx.summary
    meta = {
        "Title": f"vibkit report: {summary['file']}",
        "Author": f"vibkit {__version__}",
        "Subject": "escalator drive-chain vibration diagnostic",
        "Creator": f"vibkit {__version__}",
        "CreationDate": date,
        "ModDate": date,
    }
    with matplotlib.rc_context(
        {
            "pdf.compression": 6,
            "font.size": 9,
            "axes.titlesize": 10,
            "svg.hashsalt": "vibkit",
            "path.simplify": True,
            "axes.unicode_minus": False,
        }
    ):
        with _pdf_in_memory(out, overwrite=overwrite, inputs=inputs) as buf, PdfPages(buf, metadata=meta) as pdf:
            doc = PageSink(pdf, header=page_header(ctx))
            # (a moving walk's rides are named as its pages name it)
            doc.absent = [(b.name.replace("escalator", ctx.unit_kind), why) for b in PAGES if (why := b.absent(ctx))]
            for builder in PAGES:
                builder.draw(doc, ctx)
            doc.close()
    return Report(out, doc.pages, ctx.pitch, ctx.comparison, summary)
