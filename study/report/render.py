"""Text rendering of the report: Markdown tables and a small Markdown-to-HTML converter.

The report is written once, as Markdown (``reports/index.md``), and the self-contained HTML
(``reports/report.html``) is converted from that same text, so both always hold the same content.
The converter handles exactly the subset of Markdown the report (and ``errata.md``) uses:

1. ATX headings (``#`` to ``######``);
2. pipe tables (a header row, a ``|---|`` separator with optional ``:`` alignment, body rows;
   ``\\|`` is a literal bar inside a cell);
3. bullet lists (lines starting with ``- ``);
4. a line holding only an image, ``![caption](path)``, which becomes a figure with the image
   embedded as base64 PNG;
5. paragraphs; inline ``code``, ``**bold**`` and ``[text](link)``.

Anything else is rendered as a plain paragraph, escaped, never as raw HTML.
"""

from __future__ import annotations

import base64
import html
import re
from pathlib import Path
from typing import Callable, Sequence

import numpy as np
import pandas as pd

_HEADING = re.compile(r"^(#{1,6})\s+(.*?)\s*#*\s*$")
_IMAGE_LINE = re.compile(r"^!\[([^\]]*)\]\(([^)\s]+)\)\s*$")
_CELL_SPLIT = re.compile(r"(?<!\\)\|")
_SEPARATOR_CELL = re.compile(r"^\s*:?-{3,}:?\s*$")
_CODE_SPAN = re.compile(r"`([^`]*)`")
_BOLD = re.compile(r"\*\*(.+?)\*\*")
_LINK = re.compile(r"\[([^\]]+)\]\(([^)\s]+)\)")

HTML_STYLE = """
body { font-family: -apple-system, "Segoe UI", Helvetica, Arial, sans-serif; max-width: 1100px;
       margin: 2em auto; padding: 0 1em; line-height: 1.45; color: #1f2328; }
h1, h2, h3 { border-bottom: 1px solid #d0d7de; padding-bottom: .2em; }
.table-wrap { overflow-x: auto; margin: 1em 0; }
table { border-collapse: collapse; font-size: 0.85em; }
th, td { border: 1px solid #d0d7de; padding: 3px 7px; vertical-align: top; }
th { background: #f6f8fa; }
tr:nth-child(even) td { background: #fbfbfc; }
code { background: #f3f4f6; padding: 0 3px; border-radius: 3px; font-size: 0.92em; }
figure { margin: 1.2em 0; }
figure img { max-width: 100%; height: auto; border: 1px solid #eee; }
figcaption { font-size: 0.9em; color: #555; }
""".strip()


# --- Markdown writing --------------------------------------------------------------------------
def md_cell(text: object) -> str:
    """One table cell: bars escaped, newlines flattened."""
    return str(text).replace("|", "\\|").replace("\n", " ")


def md_table(header: Sequence[str], rows: Sequence[Sequence[object]],
             right_align: Sequence[bool] | None = None) -> str:
    """A pipe table. ``right_align[j]`` right-aligns column j (use it for numbers)."""
    if right_align is None:
        right_align = [False] * len(header)
    if len(right_align) != len(header):
        raise ValueError(f"right_align has {len(right_align)} entries, expected one per column ({len(header)})")
    lines = ["| " + " | ".join(md_cell(h) for h in header) + " |",
             "|" + "|".join("---:" if r else "---" for r in right_align) + "|"]
    for row in rows:
        if len(row) != len(header):
            raise ValueError(f"table row {list(row)!r} has {len(row)} cells, expected {len(header)}")
        lines.append("| " + " | ".join(md_cell(c) for c in row) + " |")
    return "\n".join(lines)


def fmt_number(x, digits: int = 3) -> str:
    """A number with ``digits`` significant digits; '–' for NaN/inf; non-numbers as they are."""
    try:
        x = float(x)
    except (TypeError, ValueError):
        return str(x)
    return "–" if not np.isfinite(x) else f"{x:.{digits}g}"


def fmt_int(x) -> str:
    """A count as an integer; non-numbers as they are."""
    try:
        return f"{int(round(float(x)))}"
    except (TypeError, ValueError):
        return str(x)


def _verdict(text: str) -> str:
    return {"True": "holds", "False": "fails"}.get(text, text)


def frame_table(text: pd.DataFrame, values: pd.DataFrame | None = None, verdicts: bool = False) -> str:
    """Markdown table of a frame of saved strings; columns numeric in ``values`` are right-aligned.

    ``verdicts=True`` shows True/False cells as 'holds'/'fails'.
    """
    values = text if values is None else values
    right = [pd.api.types.is_numeric_dtype(values[c]) and not pd.api.types.is_bool_dtype(values[c])
             for c in text.columns]
    rows = [[_verdict(v) if verdicts else v for v in row] for row in text.itertuples(index=False)]
    return md_table(list(text.columns), rows, right)


def demote_headings(markdown: str, levels: int) -> str:
    """Shift every ATX heading down by ``levels`` (capped at ``######``), e.g. to embed a document."""
    out = []
    for line in markdown.splitlines():
        m = _HEADING.match(line)
        out.append("#" * min(len(m.group(1)) + levels, 6) + " " + m.group(2) if m else line)
    return "\n".join(out)


# --- Markdown to HTML --------------------------------------------------------------------------
def inline_html(text: str) -> str:
    """Escape ``text`` and render code spans, bold and links (nothing inside code is touched)."""
    parts = []
    pos = 0
    for m in _CODE_SPAN.finditer(text):
        parts.append(_inline_plain(text[pos:m.start()]))
        parts.append(f"<code>{html.escape(m.group(1))}</code>")
        pos = m.end()
    parts.append(_inline_plain(text[pos:]))
    return "".join(parts)


def _inline_plain(text: str) -> str:
    text = html.escape(text, quote=False)
    text = _BOLD.sub(r"<strong>\1</strong>", text)
    return _LINK.sub(lambda m: f'<a href="{html.escape(m.group(2))}">{m.group(1)}</a>', text)


def _split_row(line: str) -> list[str]:
    body = line.strip()
    body = body[1:] if body.startswith("|") else body
    body = body[:-1] if body.endswith("|") and not body.endswith("\\|") else body
    return [c.strip().replace("\\|", "|") for c in _CELL_SPLIT.split(body)]


def _is_table_start(lines: list[str], i: int) -> bool:
    if i + 1 >= len(lines) or not lines[i].lstrip().startswith("|"):
        return False
    cells = _split_row(lines[i + 1])
    return bool(cells) and all(_SEPARATOR_CELL.match(c) for c in cells)


def _table_html(lines: list[str]) -> str:
    header, align = _split_row(lines[0]), _split_row(lines[1])
    styles = [' style="text-align:right"' if a.strip().endswith(":") else "" for a in align]
    styles += [""] * (len(header) - len(styles))
    out = ['<div class="table-wrap"><table>', "<thead><tr>"]
    out += [f"<th{styles[j]}>{inline_html(h)}</th>" for j, h in enumerate(header)]
    out.append("</tr></thead><tbody>")
    for line in lines[2:]:
        cells = _split_row(line)
        out.append("<tr>" + "".join(f"<td{styles[j] if j < len(styles) else ''}>{inline_html(c)}</td>"
                                    for j, c in enumerate(cells)) + "</tr>")
    out.append("</tbody></table></div>")
    return "\n".join(out)


def png_data_uri(path: Path) -> str:
    """``data:image/png;base64,...`` for a PNG file."""
    return "data:image/png;base64," + base64.b64encode(Path(path).read_bytes()).decode("ascii")


def markdown_to_html(markdown: str, image_source: Callable[[str], str], title: str) -> str:
    """Convert the report's Markdown to one self-contained HTML page.

    Parameters
    ----------
    markdown : the document (see the module docstring for the syntax handled)
    image_source : maps an image path as written in the Markdown to the ``src`` to use (a data URI)
    title : the page title
    """
    lines = markdown.splitlines()
    body: list[str] = []
    i = 0
    while i < len(lines):
        line = lines[i]
        if not line.strip():
            i += 1
            continue
        heading = _HEADING.match(line)
        image = _IMAGE_LINE.match(line)
        if heading:
            level = len(heading.group(1))
            body.append(f"<h{level}>{inline_html(heading.group(2))}</h{level}>")
            i += 1
        elif image:
            caption, src = image.groups()
            body.append(f'<figure><img src="{image_source(src)}" alt="{html.escape(caption)}">'
                        f"<figcaption>{inline_html(caption)}</figcaption></figure>")
            i += 1
        elif _is_table_start(lines, i):
            j = i + 2
            while j < len(lines) and lines[j].lstrip().startswith("|"):
                j += 1
            body.append(_table_html(lines[i:j]))
            i = j
        elif line.startswith("- "):
            items = []
            while i < len(lines) and lines[i].startswith("- "):
                text = lines[i][2:]
                i += 1
                while i < len(lines) and lines[i].startswith("  ") and lines[i].strip():
                    text += " " + lines[i].strip()
                    i += 1
                items.append(f"<li>{inline_html(text)}</li>")
            body.append("<ul>\n" + "\n".join(items) + "\n</ul>")
        else:
            text = []
            while (i < len(lines) and lines[i].strip() and not _HEADING.match(lines[i])
                   and not _IMAGE_LINE.match(lines[i]) and not lines[i].startswith("- ")
                   and not _is_table_start(lines, i)):
                text.append(lines[i].strip())
                i += 1
            body.append(f"<p>{inline_html(' '.join(text))}</p>")
    return ("<!DOCTYPE html>\n<html lang=\"en\">\n<head>\n<meta charset=\"utf-8\">\n"
            f"<title>{html.escape(title)}</title>\n<style>\n{HTML_STYLE}\n</style>\n</head>\n<body>\n"
            + "\n".join(body) + "\n</body>\n</html>\n")
