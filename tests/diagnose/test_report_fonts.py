"""The report's pages in the PDF's standard fonts (Helvetica, Courier) where those show every text, else in the
embedded DejaVu fonts; a paragraph's lines evenly spaced either way."""

import io
import re
from pathlib import Path

import pytest

from vibkit.diagnose.report.common import PageSink, standard_fonts_show

HELVETICA_AFM = Path("fonts", "pdfcorefonts", "Helvetica.afm")


def _pdf_of(pages, header=None, size=10):
    """The PDF bytes of ``pages`` (lists of texts, one figure each) saved through a PageSink."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    from matplotlib.backends.backend_pdf import PdfPages

    buf = io.BytesIO()
    with matplotlib.rc_context({"pdf.compression": 0}), PdfPages(buf) as pdf:
        sink = PageSink(pdf, header=header)
        for i, texts in enumerate(pages):
            fig = plt.figure(figsize=(6, 4))
            for j, text in enumerate(texts):
                fig.text(0.1, 0.8 - 0.3 * j, text, fontsize=size, va="top", linespacing=1.2)
            sink.emit(fig, f"page {i}")
        if header is not None:
            sink.close()
    return buf.getvalue(), sink


def _base_fonts(pdf):
    return set(re.findall(rb"/BaseFont\s*/([A-Za-z0-9+-]+)", pdf))


def test_windows_1252_is_what_the_standard_fonts_show():
    assert standard_fonts_show(["plain", "m/s^2", "chain's", "\u00b5m", "+- 2.9 %", "\u00e9t\u00e9 \u00b0C \u00b2"])
    assert not standard_fonts_show(["plain", "\u03bcm"])  # the Greek mu, not the micro sign
    assert not standard_fonts_show(["\u2212 1"])  # matplotlib's minus sign: the report draws '-' instead
    assert not standard_fonts_show(["\u6a5f\u68b0"])
    assert standard_fonts_show([])


def test_a_page_in_windows_1252_is_in_helvetica_and_one_beyond_it_embeds_dejavu():
    pdf, _ = _pdf_of([["the chain's pitch"], ["a sensor in \u03bcm"]])
    fonts = _base_fonts(pdf)
    assert "Helvetica".encode() in fonts  # page 1
    assert any(b"DejaVuSans" in f for f in fonts)  # page 2, embedded (a subset)


def test_a_report_with_one_text_beyond_windows_1252_embeds_dejavu_on_every_page():
    pdf, sink = _pdf_of([["the chain's pitch"], ["plain"]], header="unit \u03bc-7  |  page header")
    assert not any(f.startswith(b"Helvetica") for f in _base_fonts(pdf))
    assert all("unit \u03bc-7  |  page header" in texts for _, texts in sink.pages)
    pdf, _ = _pdf_of([["the chain's pitch"], ["plain"]], header="unit 7  |  page header")
    assert _base_fonts(pdf) == {b"Helvetica"}


def test_a_paragraph_in_helvetica_has_its_lines_evenly_spaced():
    """Lines whose glyphs reach as high and as low (an 'l' and a 'p' on each) have their baselines 1.2 x
    (ascender + descender) apart, as Helvetica's AFM file states them, whatever else a line holds: an apostrophe,
    a quote or a '^' sits high above the baseline but rises no higher than an 'l', so it must not push its line
    down. (matplotlib 3.11 spaces lines by their glyphs' extent, so lines that reach lower or higher than their
    neighbours are spaced otherwise, in any font.)"""
    pdfium = pytest.importorskip("pypdfium2")
    import matplotlib

    afm = (Path(matplotlib.get_data_path()) / HELVETICA_AFM).read_text(encoding="latin-1")
    ascender = float(re.search(r"^Ascender\s+(-?\d+)", afm, re.M).group(1))
    descender = float(re.search(r"^Descender\s+(-?\d+)", afm, re.M).group(1))
    step = 1.2 * (ascender - descender) / 1000 * 10  # [pt] at 10 pt
    lines = ["lp one", "lp chain's", "lp ' \" ^ * \u00b0", "lp m/s^2", "lp last"]
    pdf, _ = _pdf_of([["\n".join(lines)]])
    assert _base_fonts(pdf) == {b"Helvetica"}
    doc = pdfium.PdfDocument(pdf)
    tp = doc[0].get_textpage()
    text = tp.get_text_range()
    # the first letter of each line ('l') sits on its baseline: its box's bottom is the baseline
    starts = [m.start() for m in re.finditer(r"(?m)^\S", text)]
    assert len(starts) == len(lines)
    baselines = [tp.get_charbox(i)[1] for i in starts]
    gaps = [a - b for a, b in zip(baselines, baselines[1:])]
    doc.close()
    assert gaps == pytest.approx([step] * len(gaps), abs=0.25), (gaps, step)


def test_the_standard_fonts_weight_is_not_warned_about_and_other_warnings_pass(caplog):
    """Helvetica's AFM file calls its regular weight Medium: matplotlib warns once per font that it used it for
    'normal'; the report keeps that off the terminal while saving, and nothing else."""
    import logging

    from vibkit.diagnose.report.common import standard_fonts

    caplog.set_level(logging.WARNING)
    # a size never used before, so that matplotlib looks the font up again (it warns once per lookup)
    pdf, _ = _pdf_of([["weights: normal"]], size=13.7)
    assert _base_fonts(pdf) == {b"Helvetica"}
    assert not [r for r in caplog.records if "Failed to find font weight" in r.getMessage()]
    log = logging.getLogger("matplotlib.font_manager")
    with standard_fonts(True):
        log.warning("findfont: Failed to find font weight %s for %s, now using %s.", "normal", "Helvetica", "medium")
        log.warning("findfont: Failed to find font weight %s for %s, now using %s.", "bold", "Helvetica", "medium")
    log.warning("findfont: Failed to find font weight %s for %s, now using %s.", "normal", "Helvetica", "medium")
    assert [r.getMessage() for r in caplog.records] == [
        "findfont: Failed to find font weight bold for Helvetica, now using medium.",
        "findfont: Failed to find font weight normal for Helvetica, now using medium.",
    ]
