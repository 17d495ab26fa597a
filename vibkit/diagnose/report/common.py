"""What every report page shares: the :class:`Report` record, the reproducible date, atomic PDF output,
and the small drawing helpers (text collection, number format, tables, page titles).

No heavy import at module level: matplotlib is imported by the functions that draw.
"""

from __future__ import annotations

import contextlib
import datetime as _dt
import functools
import logging
import math
import os
import textwrap
from dataclasses import dataclass, field

from ...runtime.constants import A4_LANDSCAPE_IN, A4_PORTRAIT_IN
from ...runtime.safe_output import atomic_output, write_bytes
from ..rounding import (  # noqa: F401 (the one rounding rule, and the plots' length unit)
    SPEED_SIGMA_NOT_STATED,
    fmt_interval,
    fmt_length,
    fmt_pm,
    fmt_value,
    length_scale,
)

__all__ = ["Report", "report_date", "atomic_path", "PageSink", "TextColumn", "fmt_pm", "fmt_length", "length_scale"]

#: the report's labels, each with one meaning on every page (stated once, where it first appears)
HARMONIC_SNR = "harmonic SNR"
HARMONIC_SNR_DEFINITION = "power of the fitted link-pass harmonics over the residual noise power, per sample"
PITCH_RATIO = "pitch ratio"
PITCH_RATIO_DEFINITION = "pitch recorded / pitch simulated, each speed / link-pass frequency"
FREQUENCY_RATIO = "f rec / f sim"

#: an example SOURCE_DATE_EPOCH (2000-01-01T00:00:00Z), kept for callers that pinned it
FIXED_EPOCH = 946684800
_PAGE = A4_PORTRAIT_IN
_WIDE = A4_LANDSCAPE_IN  # [in]


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
    """UTC date of the report: now, or ``SOURCE_DATE_EPOCH`` when it is set (reproducible bytes).

    Raises
    ------
    ValueError
        ``SOURCE_DATE_EPOCH`` is not an integer number of seconds.
    """
    raw = os.environ.get("SOURCE_DATE_EPOCH")
    if raw is None or raw == "":
        return _dt.datetime.now(_dt.timezone.utc).replace(microsecond=0)
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
            write_bytes(self.buf.getbuffer(), self.path, overwrite=self.overwrite, inputs=self.inputs)
        return False


def _text_artists(artist):
    """Every text artist under ``artist``, in ``findobj``'s order, without making the ticks of an axis that is
    not drawn (a table's axes are switched off): they would be made for nothing, about a millisecond each."""
    import matplotlib.axis
    import matplotlib.text

    out = []
    for child in artist.get_children():
        if isinstance(child, matplotlib.axis.Axis) and not (child.axes.axison and child.get_visible()):
            out += [*_text_artists(child.label), child.label, *_text_artists(child.offsetText), child.offsetText]
            continue
        out += _text_artists(child)
    if isinstance(artist, matplotlib.text.Text):
        out.append(artist)
    return out


def _texts(fig):
    out = [t.get_text() for t in _text_artists(fig) if t.get_text() and t.get_visible()]
    for ax in fig.axes:
        for tab in ax.tables:
            out += [c.get_text().get_text() for _, c in sorted(tab.get_celld().items()) if c.get_text().get_text()]
    return out


def standard_fonts_show(texts) -> bool:
    """Whether the PDF's standard fonts (Helvetica, Courier; matplotlib's ``pdf.use14corefonts``) show every
    one of ``texts``: they are written in Windows-1252, and a character outside it would print as ``?``.

    A page in the standard fonts is saved without laying out, subsetting and embedding a TrueType font glyph
    by glyph (about two thirds of the time the report's pages took to save); a page with any other character
    keeps matplotlib's embedded DejaVu fonts. Mathematical text (the log axes' ``10^-2``) is drawn in DejaVu either way.
    """
    try:
        for text in texts:
            text.encode("cp1252")
    except UnicodeEncodeError:
        return False
    return True


def _medium_is_normal(record) -> bool:
    """False for matplotlib's warning that a normal weight was not found and "medium" was used: the standard
    fonts' AFM files call their regular weight Medium, so every text in Helvetica or Courier would warn."""
    return not (
        record.msg == "findfont: Failed to find font weight %s for %s, now using %s."
        and isinstance(record.args, tuple)
        and len(record.args) == 3
        and (str(record.args[0]), str(record.args[2])) == ("normal", "medium")
    )


@contextlib.contextmanager
def _quiet_medium_is_normal(on: bool):
    """While the standard fonts are used (``on``), no warning that their Medium weight is used for normal."""
    if not on:
        yield
        return
    log = logging.getLogger("matplotlib.font_manager")
    log.addFilter(_medium_is_normal)
    try:
        yield
    finally:
        log.removeFilter(_medium_is_normal)


@functools.cache
def _afm_tops_misread() -> bool:
    """Whether matplotlib measures an apostrophe in Helvetica as rising more than an em (see :func:`standard_fonts`)."""
    import matplotlib

    try:  # a private module: a matplotlib that moved or changed it is taken as reading right
        from matplotlib._afm import AFM

        with open(os.path.join(matplotlib.get_data_path(), "fonts", "pdfcorefonts", "Helvetica.afm"), "rb") as fh:
            _, bottom, _, height, _ = AFM(fh).get_str_bbox_and_descent("'")
    except (ImportError, AttributeError, OSError, TypeError, ValueError):
        return False
    return bottom + height > 1000


@contextlib.contextmanager
def standard_fonts(on: bool):
    """Save figures in the PDF's standard fonts (``on``; see :func:`standard_fonts_show`) with each line's
    height read right.

    matplotlib 3.11 reads a glyph's box in an AFM file, (left, bottom, right, top), as (left, bottom, width,
    height) when it measures a string (``AFM.get_str_bbox_and_descent``): the top of a glyph that does not
    sit on the baseline is taken as its bottom plus its top, so a line with an apostrophe, a quote or ``^``
    is measured up to half an em too tall, and a wrapped paragraph's lines are spaced unevenly, some
    touching. Where that reading is found (an apostrophe measured as rising more than an em), a string's
    top is taken, while saving, as its highest glyph's top: each glyph measured alone, whose height
    matplotlib gives as its top. Nothing else of matplotlib is changed, and nothing outside the save.
    """
    import matplotlib

    with matplotlib.rc_context({"pdf.use14corefonts": on}), _quiet_medium_is_normal(on):
        if not on:
            yield
            return
        if not _afm_tops_misread():
            yield
            return
        from matplotlib._afm import AFM

        measure = AFM.get_str_bbox_and_descent

        tops = {}  # (font, glyph): its top

        def top(afm, c):
            key = (id(afm), c)
            if key not in tops:
                tops[key] = measure(afm, c)[3]
            return tops[key]

        def read_right(afm, s):
            left, bottom, width, _, descent = measure(afm, s)
            return left, bottom, width, max((top(afm, c) for c in set(s) if c != "\n"), default=0) - bottom, descent

        AFM.get_str_bbox_and_descent = read_right
        try:
            yield
        finally:
            AFM.get_str_bbox_and_descent = measure


def pitch_figure(pitch) -> str:
    """The pitch as every page states it: rounded to its sigma, or (speed uncertainty not stated) to 0.01 mm
    and saying so; never ``+- 0``."""
    if pitch.speed_sigma_stated:
        return fmt_length(pitch.pitch_m, pitch.pitch_sigma_m)
    return f"{1000 * pitch.pitch_m:.2f} mm ({SPEED_SIGMA_NOT_STATED})"


def elongation_figure(pitch) -> str:
    """The elongation as every page states it (see :func:`pitch_figure`)."""
    if pitch.speed_sigma_stated:
        return fmt_pm(pitch.elongation_percent, pitch.elongation_sigma_percent, "%", sign=True)
    return f"{pitch.elongation_percent:+z.2f} % ({SPEED_SIGMA_NOT_STATED})"


def speed_value(ctx) -> str:
    """The run's speed alone (``0.50000 +- 0.00025 m/s``, or ``0.5 m/s, uncertainty not stated``), for a table."""
    run = ctx.run_speed
    if run is None or run.value is None:
        return "not known (give --speed)"
    if run.sigma is None or not run.sigma > 0:
        return f"{run.value:g} m/s, uncertainty not stated"
    return fmt_pm(run.value, run.sigma, "m/s")


def speed_source(ctx) -> str:
    """Where the run's speed came from ("-" without one)."""
    run = ctx.run_speed
    return "-" if run is None or run.value is None else run.source


def speed_sigma_source(ctx) -> str:
    """Where the speed's sigma came from; "" where it is the speed's own (given) or not stated."""
    run = ctx.run_speed
    if run is None or run.value is None or not run.sigma or run.sigma_source in ("", "given"):
        return ""
    return run.sigma_source


def speed_figure(ctx) -> str:
    """The run's one speed as every page states it."""
    run = ctx.run_speed
    if run is None or run.value is None:
        return "not known (give --speed)"
    return run.text


class TextColumn:
    """Lines of text put down a page from the top, wrapped to a width, never overlapping: each call
    moves the cursor ``y`` (figure fraction) down by the height of what it drew."""

    def __init__(self, fig, *, x, y, width):
        self.fig, self.x, self.y, self.width = fig, x, y, width
        w_in, self.h_in = fig.get_size_inches()
        self.w_in = w_in

    def _chars(self, width, size, weight):
        # average glyph width of DejaVu Sans is about 0.55 em (bold 0.62); keep a margin
        return max(10, int(width * self.w_in * 72 / (size * (0.66 if weight == "bold" else 0.58))))

    def _step(self, n_lines, size):
        return n_lines * size * 1.32 / 72 / self.h_in

    def gap(self, dy):
        self.y -= dy

    def text(self, text, size, *, weight="normal", color="black", family=None):
        lines = textwrap.wrap(str(text), self._chars(self.width, size, weight)) or [""]
        self.fig.text(
            self.x,
            self.y,
            "\n".join(lines),
            fontsize=size,
            fontweight=weight,
            color=color,
            va="top",
            family=family,
            linespacing=1.2,
        )
        self.y -= self._step(len(lines), size)

    def pairs(self, rows, size, *, key_width=0.25):
        """Two columns: what (grey) and value, the value wrapped to the rest of the width."""
        for key, value in rows:
            kl = textwrap.wrap(str(key), self._chars(key_width - 0.01, size, "normal")) or [""]
            vl = textwrap.wrap(str(value), self._chars(self.width - key_width, size, "normal")) or [""]
            self.fig.text(self.x, self.y, "\n".join(kl), fontsize=size, color="0.35", va="top", linespacing=1.2)
            self.fig.text(self.x + key_width, self.y, "\n".join(vl), fontsize=size, va="top", linespacing=1.2)
            self.y -= self._step(max(len(kl), len(vl)), size) + 0.002


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
    """Title and subtitle at the top left, placed in inches from the top (the same on portrait and
    landscape pages), the subtitle under the title and wrapped to the page's width."""
    w_in, h_in = fig.get_size_inches()
    y = 1 - 0.3 / h_in
    fig.text(0.06, y, title, fontsize=14, fontweight="bold", va="top")
    if subtitle:
        chars = int(0.88 * w_in * 72 / (8.5 * 0.58))
        fig.text(
            0.06,
            y - 14 * 1.45 / 72 / h_in,
            "\n".join(textwrap.wrap(subtitle, chars)),
            fontsize=8.5,
            color="0.3",
            va="top",
        )


class PageSink:
    """Where the page functions put their figures.

    Without ``header`` each :meth:`emit` records the page's title and every text drawn on it, saves the
    figure into the open PDF and closes it.  With ``header`` (the line that heads every page: unit,
    recording, date, speed) each page gets that line and "page n of N" at its top; the pages are held
    until :meth:`close`, which knows N, numbers them, records their texts and saves them in order.
    """

    def __init__(self, pdf, header=None):
        self.pdf = pdf
        self.header = header
        self.pages = []
        self._held = []  # (figure, its "page n of N" text artist)
        #: (page, why it is not in this report), set before the first page is drawn (page 1 lists them)
        self.absent = []

    def emit(self, fig, title):
        import matplotlib.pyplot as plt

        if self.header is None:
            self.pages.append((title, _texts(fig)))
            with standard_fonts(standard_fonts_show(self.pages[-1][1])):
                self.pdf.savefig(fig)
            plt.close(fig)
            return
        w_in, h_in = fig.get_size_inches()
        y = 1 - 0.1 / h_in
        fig.text(0.06, y, self.header, fontsize=7, color="0.35", va="top")
        number = fig.text(0.96, y, "page 99 of 99", fontsize=7, color="0.35", va="top", ha="right")
        self.pages.append((title, []))
        self._held.append((fig, number))

    def close(self):
        """Number the held pages ("page n of N"), record their texts and save them in order: all in the PDF's
        standard fonts where they show every text of every page (:func:`standard_fonts_show`), else all in
        the embedded DejaVu fonts."""
        import matplotlib.pyplot as plt

        n = len(self._held)
        for i, (fig, number) in enumerate(self._held):
            number.set_text(f"page {i + 1} of {n}")
            self.pages[i] = (self.pages[i][0], _texts(fig))
        standard = standard_fonts_show(text for _, texts in self.pages for text in texts)
        with standard_fonts(standard):
            for fig, _ in self._held:
                self.pdf.savefig(fig)
                plt.close(fig)
        self._held = []
