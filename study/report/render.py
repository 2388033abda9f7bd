"""Text rendering of the report: Markdown writing helpers, and Markdown to one self-contained HTML page.

The report is written once, as Markdown (``reports/index.md``, readable on a code host), and the
HTML (``reports/report.html``) is rendered from that same text, so both always hold the same
content. The HTML rendering uses maintained libraries:

- markdown-it-py (CommonMark + GFM tables) with mdit-py-plugins: footnotes, heading anchors
  (GitHub-style ids) and ``$...$`` / ``$$...$$`` math;
- latex2mathml turns the math into MathML, which current browsers typeset natively, so the page
  needs no JavaScript and no network;
- this module adds a generated table of contents (levels 2 and 3), numbered figures (a paragraph
  holding only an image becomes a ``<figure>``; the image is embedded as a data URI, and a
  following ``*Figure N.* ...`` caption paragraph, see :func:`number_figures`, becomes its
  caption) and a horizontally scrolling container around every table, whose first (key) column
  stays in view; long prose cells wrap at a readable width.

Raw HTML in the Markdown is escaped, never passed through.
"""

from __future__ import annotations

import base64
import html
import re
from pathlib import Path
from typing import Callable, Sequence

import numpy as np
import pandas as pd
from latex2mathml.converter import convert as latex_to_mathml
from markdown_it import MarkdownIt
from markdown_it.rules_core import StateCore
from markdown_it.token import Token
from mdit_py_plugins.anchors import anchors_plugin
from mdit_py_plugins.dollarmath import dollarmath_plugin
from mdit_py_plugins.footnote import footnote_plugin

_HEADING = re.compile(r"^(#{1,6})\s+(.*?)\s*#*\s*$")
_IMAGE_LINE = re.compile(r"^!\[([^\]]*)\]\(([^)\s]+)\)\s*$")
_CAPTION = re.compile(r"^\*Figure (\d+)\.\*")
# A table cell with more text than this (and no math) is prose: it wraps at a readable width
# (CSS td.prose) instead of being squeezed by wide neighbours.
PROSE_CELL_CHARS = 80
_MARKDOWN_SPECIAL = re.compile(r"([\\`*_\[\]<>$])")
# Headings listed in the table of contents.
TOC_LEVELS = (2, 3)

HTML_STYLE = """
body { font-family: -apple-system, "Segoe UI", Helvetica, Arial, sans-serif; max-width: 1100px;
       margin: 2em auto; padding: 0 1em; line-height: 1.45; color: #1f2328; }
h1, h2, h3 { border-bottom: 1px solid #d0d7de; padding-bottom: .2em; }
nav.toc { background: #f6f8fa; border: 1px solid #d0d7de; border-radius: 6px; padding: .4em 1.2em; margin: 1em 0; }
nav.toc ol { margin: .2em 0; padding-left: 1.4em; }
nav.toc > ol { columns: 2; column-gap: 2em; }
nav.toc li { break-inside: avoid; }
.table-wrap { overflow-x: auto; margin: 1em 0; max-width: 100%; }
table { border-collapse: separate; border-spacing: 0; font-size: 0.85em; }
th, td { border: 1px solid #d0d7de; border-width: 0 1px 1px 0; padding: 3px 7px; vertical-align: top; background: #fff; }
tr > :first-child { border-left-width: 1px; position: sticky; left: 0; z-index: 1; }
thead th { border-top-width: 1px; background: #f6f8fa; }
tr:nth-child(even) td { background: #fbfbfc; }
td.prose { min-width: 24em; }
code { background: #f3f4f6; padding: 0 3px; border-radius: 3px; font-size: 0.92em; overflow-wrap: anywhere; }
math { font-size: 1.05em; font-family: "Latin Modern Math", "STIX Two Math", "Cambria Math", "DejaVu Math TeX Gyre", math; }
math [mathcolor] { background: #ffe7a3; border-radius: 2px; }
.math-error { color: #b00020; }
figure { margin: 1.2em 0; }
figure img { max-width: 100%; height: auto; border: 1px solid #eee; }
figcaption { font-size: 0.9em; color: #555; }
""".strip()


# --- Markdown writing --------------------------------------------------------------------------
def md_cell(text: object) -> str:
    """One table cell: bars escaped, newlines flattened."""
    return str(text).replace("|", "\\|").replace("\n", " ")


def md_escape(text: object) -> str:
    """Plain text shown literally: Markdown's emphasis, code, link, HTML and math characters escaped."""
    return _MARKDOWN_SPECIAL.sub(r"\\\1", str(text))


def md_math(latex: str) -> str:
    """Inline math ``$...$`` for a LaTeX formula, safe inside a table cell.

    Bars become ``\\vert`` (a ``|`` would end the cell), newlines spaces; the formula is stripped so
    that code hosts (which require no space inside the dollars) render it too.
    """
    text = re.sub(r"\\?\|", lambda m: r"\Vert " if m.group(0) == "\\|" else r"\vert ", str(latex))
    text = " ".join(text.split())
    if not text:
        raise ValueError("md_math: empty formula")
    return f"${text}$"


def number_figures(markdown: str) -> str:
    """Give every image that stands alone on its line a numbered caption paragraph below it.

    ``![alt](src)`` becomes ``![alt](src)``, a blank line and ``*Figure N.* alt``, numbered in
    order; :func:`markdown_to_html` turns the pair into one ``<figure>`` with that caption.
    """
    out, n = [], 0
    for line in markdown.splitlines():
        out.append(line)
        m = _IMAGE_LINE.match(line)
        if m:
            n += 1
            out += ["", f"*Figure {n}.* {m.group(1)}"]
    return "\n".join(out) + ("\n" if markdown.endswith("\n") else "")


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
    """A count as an integer; '–' for NaN/inf (as :func:`fmt_number`); non-numbers as they are."""
    try:
        x = float(x)
        return "–" if not np.isfinite(x) else f"{int(round(x))}"
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
def png_data_uri(path: Path) -> str:
    """``data:image/png;base64,...`` for a PNG file."""
    return "data:image/png;base64," + base64.b64encode(Path(path).read_bytes()).decode("ascii")


def math_html(latex: str, display: bool = False) -> str:
    """MathML for a LaTeX formula; a formula latex2mathml cannot read is shown as code, marked."""
    try:
        return latex_to_mathml(latex, display="block" if display else "inline")
    except Exception as exc:  # latex2mathml raises many types (its own, IndexError, KeyError) on bad input
        return (f'<code class="math-error" title="not typeset: {html.escape(type(exc).__name__)}">'
                f"{html.escape(latex)}</code>")


def _is_image_paragraph(tokens: list[Token], i: int) -> bool:
    if tokens[i].type != "paragraph_open" or i + 2 >= len(tokens):
        return False
    children = [c for c in tokens[i + 1].children or [] if not (c.type == "text" and not c.content.strip())]
    return len(children) == 1 and children[0].type == "image"


def _is_caption_paragraph(tokens: list[Token], i: int) -> bool:
    return (i + 2 < len(tokens) and tokens[i].type == "paragraph_open"
            and bool(_CAPTION.match(tokens[i + 1].content)))


def _figures(image_source: Callable[[str], str]) -> Callable[[StateCore], None]:
    """Core rule: image-only paragraphs -> numbered <figure>s (with their caption paragraph)."""
    def rule(state: StateCore) -> None:
        tokens, out, i, n = state.tokens, [], 0, 0
        while i < len(tokens):
            if not _is_image_paragraph(tokens, i):
                out.append(tokens[i])
                i += 1
                continue
            n += 1
            image = next(c for c in tokens[i + 1].children if c.type == "image")
            image.attrSet("src", image_source(image.attrGet("src")))
            figure = Token("figure_open", "figure", 1, block=True)
            figure.attrSet("id", f"figure-{n}")
            out += [figure, tokens[i + 1]]
            i += 3
            if _is_caption_paragraph(tokens, i):
                caption = tokens[i + 1]
                i += 3
            else:  # no caption paragraph: number the image's own text
                caption = Token("inline", "", 0, content=f"*Figure {n}.* {image.content}")
                caption.children = state.md.parseInline(caption.content, state.env)[0].children
            out += [Token("figcaption_open", "figcaption", 1, block=True), caption,
                    Token("figcaption_close", "figcaption", -1, block=True),
                    Token("figure_close", "figure", -1, block=True)]
        state.tokens = out
    return rule


def _toc(tokens: list[Token], renderer, options, env) -> str:
    """A nested ordered list of links to the headings of TOC_LEVELS."""
    items = []
    for i, tok in enumerate(tokens):
        level = int(tok.tag[1]) if tok.type == "heading_open" else 0
        if level in TOC_LEVELS and tok.attrGet("id"):
            text = renderer.renderInline(tokens[i + 1].children, options, env)
            items.append((level, f'<a href="#{html.escape(str(tok.attrGet("id")))}">{text}</a>'))
    if not items:
        return ""
    out, top = ['<nav class="toc" aria-label="Contents">', "<strong>Contents</strong>", "<ol>"], TOC_LEVELS[0]
    for k, (level, link) in enumerate(items):
        out.append(f"<li>{link}")
        deeper = k + 1 < len(items) and items[k + 1][0] > level
        if deeper:
            out.append("<ol>")
            continue
        out.append("</li>")
        nxt = items[k + 1][0] if k + 1 < len(items) else top
        for _ in range(level - max(nxt, top)):
            out.append("</ol></li>")
    out += ["</ol>", "</nav>"]
    return "\n".join(out)


def _td_open(self, tokens: list[Token], idx: int, options, env) -> str:
    content = tokens[idx + 1].content if idx + 1 < len(tokens) else ""
    if len(content) > PROSE_CELL_CHARS and "$" not in content:
        tokens[idx].attrJoin("class", "prose")
    return self.renderToken(tokens, idx, options, env)


def markdown_parser(image_source: Callable[[str], str] = lambda src: src) -> MarkdownIt:
    """The report's Markdown parser: CommonMark, GFM tables, footnotes, heading ids, $math$, figures.

    ``image_source`` maps an image path as written in the Markdown to the ``src`` to use.
    """
    md = MarkdownIt("commonmark", {"html": False, "typographer": False}).enable("table")
    md.use(footnote_plugin)
    md.use(anchors_plugin, min_level=1, max_level=6)
    md.use(dollarmath_plugin, allow_space=False, allow_digits=False, double_inline=True,
           renderer=lambda content, options: math_html(content, options.get("display_mode", False)))
    md.core.ruler.push("figures", _figures(image_source))
    md.add_render_rule("td_open", _td_open)
    md.add_render_rule("table_open", lambda self, tokens, idx, options, env:
                       '<div class="table-wrap">\n' + self.renderToken(tokens, idx, options, env))
    md.add_render_rule("table_close", lambda self, tokens, idx, options, env:
                       self.renderToken(tokens, idx, options, env) + "</div>\n")
    return md


def markdown_to_html(markdown: str, image_source: Callable[[str], str], title: str, toc_after: str = "") -> str:
    """Render the report's Markdown as one self-contained HTML page (see the module docstring).

    Parameters
    ----------
    markdown : the document
    image_source : maps an image path as written in the Markdown to the ``src`` to use (a data URI)
    title : the page title

    The table of contents goes before the first heading of level TOC_LEVELS[0], or, with ``toc_after`` (a heading
    id), before the first such heading after that heading's section (the findings come before the contents).
    """
    md = markdown_parser(image_source)
    env: dict = {}
    tokens = md.parse(markdown, env)
    toc = _toc(tokens, md.renderer, md.options, env)
    tops = [i for i, t in enumerate(tokens) if t.type == "heading_open" and t.tag == f"h{TOC_LEVELS[0]}"]
    after = [k for k, i in enumerate(tops) if toc_after and tokens[i].attrGet("id") == toc_after]
    rest = tops[after[0] + 1:] if after else tops
    first = rest[0] if rest else len(tokens)
    if toc:
        block = Token("html_block", "", 0, content=toc + "\n", block=True)
        tokens = tokens[:first] + [block] + tokens[first:]
    body = md.renderer.render(tokens, md.options, env)
    return ("<!DOCTYPE html>\n<html lang=\"en\">\n<head>\n<meta charset=\"utf-8\">\n"
            '<meta name="viewport" content="width=device-width, initial-scale=1">\n'
            f"<title>{html.escape(title)}</title>\n<style>\n{HTML_STYLE}\n</style>\n</head>\n<body>\n"
            + body + "</body>\n</html>\n")
