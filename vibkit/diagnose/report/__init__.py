"""PDF reports: the multi-page diagnostic report of a recording and the one-page fleet report.

The only part of vibkit that draws pages, one module per page kind:

* :mod:`.common`: the :class:`Report` record, the reproducible date, atomic PDF output, drawing helpers;
* :mod:`.context`: the analysis behind the diagnostic report (:class:`~.context.ReportContext`);
* :mod:`.verdict`: cover and verdict pages;
* :mod:`.signal_pages`: time signal (Hampel spikes), spectrum, spectrogram, order spectrum;
* :mod:`.ride_pages`: ride-quality pages (:func:`plot_ride`);
* :mod:`.comparison_pages`: simulation against recording (:func:`plot_comparison`), harmonics;
* :mod:`.appendix`: data quality and parameters;
* :mod:`.document`: :func:`write_report`, which calls the page functions in order;
* :mod:`.fleet`: :func:`write_fleet_report`.

matplotlib is imported only when a page is drawn.
"""

from .common import FIXED_EPOCH, Report, _pdf_in_memory, atomic_path, report_date  # noqa: F401 (re-exported)
from .comparison_pages import plot_comparison
from .document import write_report
from .fleet import FLEET_PAGE_MAX_UNITS, write_fleet_report  # noqa: F401 (re-exported)
from .ride_pages import plot_ride

__all__ = ["Report", "write_report", "plot_comparison", "plot_ride", "report_date", "atomic_path", "write_fleet_report"]
