"""The report as a reader sees it: reports/report.html opened in headless Chromium.

Checks that every image loads, that no raw Markdown (links, emphasis, code spans, images, $math$)
is left in the rendered text, that every MathML formula has a non-zero size and that nothing but
the tables' scrolling containers is wider than the page. Saves screenshots of the first screen and
of the errata section to ``reports/screenshots/``. Skipped, with its reason, where no Chromium is
installed (``make browser`` installs the Debian package where the user may).
"""

from pathlib import Path

import pytest

from chromium import Chromium, find_chromium
from study.reference_data import tolerance
from study.report.sections import findings

ROOT = Path(__file__).resolve().parents[1]
REPORT = ROOT / "reports" / "report.html"
SCREENSHOTS = ROOT / "reports" / "screenshots"
VIEWPORT = (1280, 900)
ERRATA_SHOT_HEIGHT = 1400  # [px] of the errata section shown in its screenshot

# Runs in the page; returns what the checks need as plain JSON. In the text searched for raw
# Markdown, every <math> and <code> element stands as one placeholder character (formulas and code
# may hold brackets and stars; a link whose text is code must still be found).
CHECKS_JS = r"""
((slack) => {
  const width = document.documentElement.clientWidth;
  const images = [...document.images].map(img => ({alt: img.alt.slice(0, 80),
      loaded: img.complete && img.naturalWidth > 0 && img.getBoundingClientRect().width > 0}));
  const maths = [...document.querySelectorAll('math')].map(m => {
      const r = m.getBoundingClientRect();
      return {text: m.textContent.slice(0, 60), width: r.width, height: r.height};
  });
  const overflow = [];
  for (const el of document.body.querySelectorAll('*')) {
    if (el.closest('.table-wrap')) continue;  // a scrolling container's content may be wide
    const r = el.getBoundingClientRect();
    if (r.right > width + slack || r.left < -slack) overflow.push(el.tagName.toLowerCase() + (el.id ? '#' + el.id : '') + ' right=' + Math.round(r.right));
  }
  const clone = document.body.cloneNode(true);
  clone.querySelectorAll('math, code').forEach(e => e.replaceWith('\u25a2'));
  const text = clone.innerText;
  const errata = document.getElementById('errata');
  const next = errata && [...document.querySelectorAll('h2')].find(h => h.compareDocumentPosition(errata) & Node.DOCUMENT_POSITION_PRECEDING);
  const top = errata ? errata.getBoundingClientRect().top + window.scrollY : null;
  const bottom = next ? next.getBoundingClientRect().top + window.scrollY : document.documentElement.scrollHeight;
  return {width, scrollWidth: document.documentElement.scrollWidth, images, maths, overflow, text,
          errata: errata ? {top, bottom, maths: errata.parentElement.querySelectorAll('math').length} : null,
          tables: document.querySelectorAll('table').length,
          wrapped: document.querySelectorAll('.table-wrap > table').length,
          toc: document.querySelectorAll('nav.toc a').length,
          firstSection: (() => { const h = document.querySelector('h2');
                                 return h ? {id: h.id, top: h.getBoundingClientRect().top} : null; })()};
})(SLACK)
"""


def raw_markdown(text: str) -> dict[str, list[str]]:
    """Markdown syntax a renderer should have consumed, found in rendered text, by kind."""
    import re

    patterns = {
        "link": r"!?\[[^\]\n]+\]\([^)\s]+\)",
        "code span": r"`[^`\n]+`",
        "emphasis": r"(?:^|(?<=[\s(]))(\*\*|\*|__|_)(?=[^\s*_])[^\n]*?(?<=[^\s*_])\1(?=$|[\s).,;:!?])",
        "math": r"\$[^$\s][^$\n]*?\$",
    }
    return {kind: [m.group(0)[:80] for m in re.finditer(p, text, re.M)] for kind, p in patterns.items()}


def inspect(report: Path, screenshots: Path | None = None) -> dict:
    """Open ``report`` in Chromium, run the checks and (optionally) save the screenshots."""
    executable = find_chromium()
    with Chromium(executable, *VIEWPORT) as browser:
        browser.open(report.resolve().as_uri())
        found = browser.evaluate(CHECKS_JS.replace("SLACK", repr(tolerance("browser_overflow_px"))))
        if screenshots is not None:
            browser.screenshot(screenshots / "first_screen.png")
            errata = found["errata"]
            if errata:
                height = min(ERRATA_SHOT_HEIGHT, errata["bottom"] - errata["top"])
                browser.screenshot(screenshots / "errata.png",
                                   {"x": 0, "y": errata["top"], "width": VIEWPORT[0], "height": height})
    found["raw"] = raw_markdown(found.pop("text"))
    return found


def browser_test(test):
    """Slow (run by `make reproduce`), and skipped with its reason where no Chromium is installed."""
    skip = pytest.mark.skipif(find_chromium() is None, reason="no Chromium installed (Debian: apt-get install "
                              "chromium, or `make browser`; STUDY_CHROMIUM=/path/to/chrome to use another)")
    return pytest.mark.slow(skip(test))


@pytest.fixture(scope="module")
def page():
    if not REPORT.exists():
        pytest.fail(f"{REPORT} is missing: build it first (python -m study report)")
    return inspect(REPORT, SCREENSHOTS)


@browser_test
def test_browser_every_image_loads(page):
    assert page["images"], "the report shows no image"
    assert [i["alt"] for i in page["images"] if not i["loaded"]] == []


@browser_test
def test_browser_no_raw_markdown_left(page):
    assert page["raw"] == {"link": [], "code span": [], "emphasis": [], "math": []}


@browser_test
def test_browser_math_has_a_size(page):
    assert page["errata"] is not None and page["errata"]["maths"] > 0
    assert [m["text"] for m in page["maths"] if not (m["width"] > 0 and m["height"] > 0)] == []


@browser_test
def test_browser_no_horizontal_overflow_outside_tables(page):
    assert page["overflow"] == []
    assert page["scrollWidth"] <= page["width"]
    assert page["wrapped"] == page["tables"] > 0


@browser_test
def test_browser_screenshots_saved(page):
    for name in ("first_screen.png", "errata.png"):
        assert (SCREENSHOTS / name).read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"


@browser_test
def test_browser_first_screen_opens_with_the_findings(page):
    """The first section heading is the findings, in the upper half of the first screen (before the contents)."""
    first = page["firstSection"]
    assert first is not None and first["id"] == findings.ANCHOR, first
    assert first["top"] < VIEWPORT[1] / 2, first


def test_raw_markdown_detector_can_fail():
    """The detector finds what a broken renderer leaves, and passes literal stars in formulas."""
    found = raw_markdown("see [`manifest.json`](manifest.json), *em* and **bold**, `x`, $a_1$; m2*(-l1**2 + l2**2)")
    assert found == {"link": ["[`manifest.json`](manifest.json)"], "code span": ["`manifest.json`", "`x`"],
                     "emphasis": ["*em*", "**bold**"], "math": ["$a_1$"]}
