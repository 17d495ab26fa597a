"""The HTML a notebook shows for a diagnostic's result (``_repr_html_``): a title and a table of its numbers.

Every value is escaped; numbers are given as the result's own text gives them (rounded to their uncertainty).
"""

from __future__ import annotations

import html

__all__ = ["result_table_html"]


def result_table_html(title: str, rows: list[tuple[str, object]], *, columns: list[str] | None = None) -> str:
    """A ``<div>`` holding a bold title and a table.

    Parameters
    ----------
    title : str
        The line above the table (the result's kind and its main finding).
    rows : list of (str, object)
        Name and value of each row; with ``columns``, the value is a sequence of cells, one per column.
    columns : list of str, optional
        Column headings after the name's column (a table of several columns, one row per axis, say).
    """
    esc = html.escape
    head = ""
    if columns:
        head = "<thead><tr><th></th>" + "".join(f"<th>{esc(c)}</th>" for c in columns) + "</tr></thead>"
    body = []
    for name, value in rows:
        cells = value if columns else [value]
        tds = "".join(f'<td style="text-align:left">{esc(str(c))}</td>' for c in cells)
        body.append(f'<tr><th style="text-align:left">{esc(name)}</th>{tds}</tr>')
    return f"<div><p><b>{esc(title)}</b></p><table>{head}<tbody>{''.join(body)}</tbody></table></div>"
