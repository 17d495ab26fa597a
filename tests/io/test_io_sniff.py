"""The layout sniff's shortcut: a line holding neither the delimiter nor a quote is one cell, the line stripped.

``vibkit.io.text.layout._sniff`` takes such lines as that cell without splitting them (a fleet of small files paid the
split of the last 200 lines for every delimiter a file does not use); these tests hold the splitter to what the
shortcut assumes, and the sniff to the answers it gives when it splits every line.
"""

from hypothesis import given, settings
from hypothesis import strategies as st

from vibkit.io.text import layout
from vibkit.io.text.cells import _Splitter

CHARS = st.sampled_from(list('0123456789.,;\t|-+eE: "#anifAN\u00a0\x0b') + ["nan", "inf", "-Inf", "1e-3", "12:00:01"])
LINES = st.lists(CHARS, max_size=12).map("".join)


@settings(max_examples=400, deadline=None)
@given(LINES, st.sampled_from(",;\t|"), st.booleans())
def test_a_line_without_the_delimiter_or_a_quote_splits_into_the_line_stripped(line, d, trailing):
    if d in line or '"' in line:
        return
    assert _Splitter(d, trailing)(line) == [line.strip()]


FILES = [
    ["time_s,accel_m_s2", *(f"{i / 200:.6f},{(-1) ** i * 0.37 * i:.6f}" for i in range(300))],
    ["x", *(f"{0.01 * i:.4f}" for i in range(50)), "inf", "nan", " 5.5 "],  # one column: every delimiter one cell
    ["t;a", *(f"{i},5;{i % 7},25" for i in range(40))],  # decimal commas
    ["# note", "t\ta\tb", *(f"{i}\t{i * 0.5}\t-{i}" for i in range(40))],
    ["12:00:01 1.5", "12:00:02 1.75", "text line", "12:00:03 2.0"],
]


@settings(max_examples=200, deadline=None)
@given(st.lists(LINES, min_size=1, max_size=30))
def test_the_sniff_reads_lines_as_it_does_when_it_splits_every_line(lines):
    assert_same_sniff(lines)


def test_the_sniff_of_common_layouts_is_the_one_that_splits_every_line():
    for lines in FILES:
        assert_same_sniff(lines)


def assert_same_sniff(lines):
    text = "\n".join(lines)
    got = [layout._sniff(lines, None, dec, text) for dec in (None, ".", ",")]
    saved = layout._one_cell
    layout._one_cell = lambda body, d: False  # every line split, as before the shortcut
    try:
        want = [layout._sniff(lines, None, dec, text) for dec in (None, ".", ",")]
    finally:
        layout._one_cell = saved
    assert got == want
