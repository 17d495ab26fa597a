"""The PDF diagnostic report of a recording: :func:`write_report` analyses it once
(:func:`~vibkit.diagnose.report.context.analyse`) and calls one page function per page kind, in the
order of :data:`PAGES`.

The pages: the verdict (page 1), the recording and escalator, time signal with events, spectrum with harmonic markers, spectrogram,
order spectrum, ride quality (when it can be assessed), simulation against recording and harmonics (given a
scene), data quality, parameters.  The report is dated now; with ``SOURCE_DATE_EPOCH`` set the same
inputs give the same bytes (nothing random is drawn).
"""

from __future__ import annotations

import os

from ... import __version__
from ...runtime.safe_output import check_output_path
from .appendix import data_quality_page, parameters_page
from .common import PageSink, Report, _pdf_in_memory
from .comparison_pages import harmonics_page, simulation_page
from .context import analyse
from .links_page import links_page
from .ride_pages import ride_quality_pages
from .signal_pages import order_spectrum_page, spectrogram_page, spectrum_page, time_signal_page
from .verdict import recording_page, verdict_page

__all__ = ["PAGES", "write_report"]

#: the page functions, in page order; each is ``page(doc, ctx)`` with ``doc`` a
#: :class:`~vibkit.diagnose.report.common.PageSink` and ``ctx`` a
#: :class:`~vibkit.diagnose.report.context.ReportContext`, and emits zero or more pages
PAGES = (
    verdict_page,
    recording_page,
    time_signal_page,
    spectrum_page,
    spectrogram_page,
    order_spectrum_page,
    links_page,
    ride_quality_pages,
    simulation_page,
    harmonics_page,
    data_quality_page,
    parameters_page,
)


def write_report(
    recording,
    out_path,
    *,
    scene=None,
    speed=None,
    speed_sigma=None,
    channel=None,
    nominal_pitch=None,
    limits_percent=None,
    sample_rate=None,
    duration=None,
    band=None,
    hampel_half_window_s=0.1,
    hampel_false_alarm_rate=1e-4,
    progress=False,
    overwrite=False,
    read_options=None,
    date=None,
    profile=None,
    segment=None,
    marker_s=None,
) -> Report:
    """Write the PDF diagnostic report of a recording.

    Parameters
    ----------
    recording : str or os.PathLike
        Recording file (anything :func:`vibkit.read_recording` reads).
    out_path : str or os.PathLike
        PDF to write (atomically); never one of the inputs.
    scene : str, os.PathLike or Scene, optional
        Scene describing the escalator and sensor; simulated and compared with the recording.
    speed : float, optional
        Chain speed [m/s], the one speed of every page and of the comparison; default the profile's
        rated speed, else the recording's ``chain_speed_m_s``, else the scene's.
    speed_sigma : float or str, optional
        Its standard deviation [m/s], or a percentage of it (``"0.05%"``); None: not stated (a profile's
        rated speed then takes the profile's sigma).
    channel : str, optional
    nominal_pitch : float, optional
        [m]; default the scene's link pitch.
    limits_percent : (float, float, float), optional
        Elongation limits [%] (default 1.5, 2, 3).
    sample_rate : float, optional
        For files without time. [Hz]
    duration : float, optional
        Simulated time [s] (default the scene's).
    band : (float, float), optional
        Link-pass search band. [Hz]
    hampel_half_window_s : float
        Half window of the spike detector [s] (longer than a spike: a knock lasts tens of ms).
    hampel_false_alarm_rate : float
        Per-sample false-alarm probability of the spike detector on Gaussian noise.
    overwrite : bool
        Replace an existing regular file ``out_path`` (default False: an existing file is refused; the
        CLI passes ``--force``).
    read_options : dict, optional
        More :func:`vibkit.read_recording` arguments (``time_unit``, ``units``, ``repair_time`` ...).
    date : str or datetime.datetime, optional
        When the recording was made (ISO 8601); default the file's start time, if it states one.
    profile : Profile, optional
        The escalator profile (:func:`vibkit.model.profile.load_profile`): page 1 names its unit; its rated
        speed, nominal pitch and teeth are the defaults; a scene's simulated ride page is shown only when
        the scene is this unit's.
    segment : (float, float), optional
        The recording's ride segment [s] (default: detected), for its ride-quality page.
    marker_s : float, optional
        When a marked link passed the sensor [s from the recording's start]: the links page numbers from it
        (:func:`vibkit.diagnose.links.find_worn_links`).

    Returns
    -------
    Report

    Raises
    ------
    ValueError
        The output is one of the inputs or not a ``.pdf``; bad options; or the errors of
        :func:`vibkit.read_recording` and :func:`vibkit.load_scene`.
    """
    import matplotlib

    matplotlib.use("Agg")
    from matplotlib.backends.backend_pdf import PdfPages

    out = os.fspath(out_path)
    if not out.lower().endswith(".pdf"):
        raise ValueError(f"output {out!r} must be a .pdf file")
    inputs = [os.fspath(recording)] + ([os.fspath(scene)] if isinstance(scene, (str, os.PathLike)) else [])
    for p in inputs:
        if os.path.exists(out) and os.path.samefile(out, p):
            raise ValueError(f"output {out!r} is an input file; refusing to overwrite it")
    check_output_path(out, overwrite=overwrite, inputs=inputs)  # before any work
    ctx = analyse(
        recording,
        scene=scene,
        speed=speed,
        speed_sigma=speed_sigma,
        channel=channel,
        nominal_pitch=nominal_pitch,
        limits_percent=limits_percent,
        sample_rate=sample_rate,
        duration=duration,
        band=band,
        hampel_half_window_s=hampel_half_window_s,
        hampel_false_alarm_rate=hampel_false_alarm_rate,
        progress=progress,
        read_options=read_options,
        date=date,
        profile=profile,
        segment=segment,
        marker_s=marker_s,
    )
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
        {"pdf.compression": 6, "font.size": 9, "axes.titlesize": 10, "svg.hashsalt": "vibkit", "path.simplify": True}
    ):
        with _pdf_in_memory(out, overwrite=overwrite, inputs=inputs) as buf, PdfPages(buf, metadata=meta) as pdf:
            doc = PageSink(pdf)
            for page in PAGES:
                page(doc, ctx)
    return Report(out, doc.pages, ctx.pitch, ctx.comparison, summary)
