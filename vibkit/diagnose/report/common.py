"""What every report page shares: the :class:`Report` record, the reproducible date, atomic PDF output,
and the small drawing helpers (text collection, number format, tables, page titles).

No heavy import at module level: matplotlib is imported by the functions that draw.
"""

from __future__ import annotations

import datetime as _dt
import math
import os
from dataclasses import dataclass, field

__all__ = ["Report", "report_date", "atomic_path", "PageSink"]

#: date used in the PDF when SOURCE_DATE_EPOCH is not set (the PDF stays reproducible)
FIXED_EPOCH = 946684800  # 2000-01-01T00:00:00Z
_PAGE = (8.27, 11.69)  # A4 portrait [in]
_WIDE = (11.69, 8.27)  # A4 landscape [in]


@dataclass(frozen=True)
class Report:
    """What :func:`~vibkit.diagnose.report.write_report` (or ``write_fleet_report``) wrote.

    Attributes
    ----------
    path : str
    pages : list of (str, list of str)
        Page title and every text drawn on it (for tests and indexing).
    pitch : PitchEstimate or None
    comparison : Comparison or None
    summary : dict
        The verdict table as a JSON-ready dict.
    """

    path: str
    pages: list
    pitch: object = None
    comparison: object = None
    summary: dict = field(default_factory=dict)


def report_date() -> _dt.datetime:
    """UTC date of the report: ``SOURCE_DATE_EPOCH`` if set, else a fixed epoch (2000-01-01).

    Raises
    ------
    ValueError
        ``SOURCE_DATE_EPOCH`` is not an integer number of seconds.
    """
    raw = os.environ.get("SOURCE_DATE_EPOCH")
    if raw is None or raw == "":
        sec = FIXED_EPOCH
    else:
        try:
            sec = int(raw)
        except ValueError:
            raise ValueError(f"SOURCE_DATE_EPOCH must be an integer number of seconds, got {raw!r}") from None
    return _dt.datetime.fromtimestamp(sec, tz=_dt.timezone.utc)


class atomic_path:
    """Context manager yielding a temporary path next to ``path``; on success it replaces ``path``.

    A thin wrapper of :func:`vibkit.runtime.safe_output.atomic_output` (regular files only, fsync, rename,
    the temporary file removed on any error or signal).
    """

    def __init__(self, path, suffix="", *, overwrite=True, inputs=()):
        self.path = os.fspath(path)
        self.suffix = suffix
        self._cm = None
        self._kw = {"overwrite": overwrite, "inputs": inputs}

    def __enter__(self):
        from ...runtime.safe_output import atomic_output

        self._cm = atomic_output(self.path, **self._kw)
        self.tmp = self._cm.__enter__()
        return self.tmp

    def __exit__(self, exc_type, exc, tb):
        return self._cm.__exit__(exc_type, exc, tb)


class _pdf_in_memory:
    """Collect a PDF in memory; on success write it to ``path`` atomically (a full disk leaves nothing)."""

    def __init__(self, path, *, overwrite, inputs):
        self.path, self.overwrite, self.inputs = path, overwrite, inputs

    def __enter__(self):
        import io

        self.buf = io.BytesIO()
        return self.buf

    def __exit__(self, exc_type, exc, tb):
        if exc_type is None:
            from ...runtime.safe_output import write_bytes

            write_bytes(self.buf.getbuffer(), self.path, overwrite=self.overwrite, inputs=self.inputs)
        return False


def _texts(fig):
    import matplotlib.text

    out = [t.get_text() for t in fig.findobj(matplotlib.text.Text) if t.get_text() and t.get_visible()]
    for ax in fig.axes:
        for tab in ax.tables:
            out += [c.get_text().get_text() for _, c in sorted(tab.get_celld().items()) if c.get_text().get_text()]
    return out


def _fmt(v, unit="", digits=4):
    if v is None or (isinstance(v, float) and not math.isfinite(v)):
        return "n/a"
    return f"{v:.{digits}g} {unit}".strip()


def _table(ax, rows, col_widths=(0.42, 0.58), fontsize=9):
    ax.axis("off")
    tab = ax.table(cellText=rows, colWidths=list(col_widths), loc="upper center", cellLoc="left")
    tab.auto_set_font_size(False)
    tab.set_fontsize(fontsize)
    tab.scale(1.0, 1.35)
    return tab


def _page_title(fig, title, subtitle=""):
    fig.suptitle(title, fontsize=14, fontweight="bold", x=0.06, ha="left", y=0.975)
    if subtitle:
        fig.text(0.06, 0.945, subtitle, fontsize=8.5, color="0.3")


class PageSink:
    """Where the page functions put their figures: each :meth:`emit` records the page's title and every
    text drawn on it, saves the figure into the open PDF and closes it."""

    def __init__(self, pdf):
        self.pdf = pdf
        self.pages = []

    def emit(self, fig, title):
        import matplotlib.pyplot as plt

        self.pages.append((title, _texts(fig)))
        self.pdf.savefig(fig)
        plt.close(fig)
