"""The report is built from saved results only: figures, index.md, report.html and manifest.json
from a tiny pipeline run, with every quoted number equal to the saved table's."""

import hashlib
import json
import os
import re
from pathlib import Path

import pandas as pd
import pytest

from study import pipeline as pl
from study.report import build_report
from study import errata
from study.errata.table import errata_markdown
from study.report.render import markdown_to_html, md_math, md_table, number_figures
from tiny_cases import TINY


@pytest.fixture(scope="module")
def saved(tmp_path_factory):
    """The tiny sliding-mode study run by the pipeline, and a minimal initial-conditions table."""
    root = tmp_path_factory.mktemp("report")
    cases = root / "cases"
    cases.mkdir()
    (cases / "sliding_mode.toml").write_text(TINY)
    reports, cache = root / "reports", root / "cache"
    pl.run_pipeline(reports, cache, workers=1, folder=cases, stream=open(os.devnull, "w"))
    pd.DataFrame({"mechanism": ["quick_return"], "max_abs_phi_printed": [0.000149101776],
                  "max_abs_phi_consistent": [1e-16], "max_abs_phidot_printed": [2e-5],
                  "max_abs_phidot_consistent": [3e-16]}).to_csv(reports / "tables" / "initial_conditions.csv",
                                                                 index=False)
    return reports, cache, cases


def _row(markdown, first_cells):
    """Cells of the table row of ``markdown`` that starts with ``first_cells``."""
    start = "| " + " | ".join(first_cells) + " |"
    line = next(line for line in markdown.splitlines() if line.startswith(start))
    return [c.strip() for c in line.strip().strip("|").split(" | ")]


def test_report_from_saved_runs(saved):
    reports, cache, cases = saved
    index = build_report(reports, cache, cases)
    assert index == reports / "index.md"
    text = index.read_text()
    for section in ("## Initial conditions", "## Errata", "## Constraint drift: the sliding-mode claims of paper 001",
                    "## All tables", "## Provenance"):
        assert section in text
    assert "errata table is missing" in text and "## Failed cases" not in text
    assert "max|Φ| = 0.000149101776" in text  # quoted with the saved digits

    # numbers quoted in the text are the saved table's, digit for digit
    runs_csv = pd.read_csv(reports / "tables" / "sliding_mode_runs.csv", dtype=str)
    at = runs_csv[runs_csv["integrator_setting"] == "RK45 rtol=1e-6"].set_index("method")
    row = _row(text, ["RK45 rtol=1e-6", "10"])  # key-finding table: setting, omega, Baumgarte max|Phi|, ...
    assert row[2] == at.loc["baumgarte", "max_abs_phi"]
    assert "max|Φ| agrees for every run" in text  # the table matches the saved runs

    figures = reports / "figures"
    for stem in ("quick_return_constraint_violation_RK45_rtol1e-6", "quick_return_velocity_constraint_violation_RK4_h1e-3",
                 "quick_return_trajectories", "sliding_mode_max_abs_phi_heatmap"):
        png = figures / f"{stem}.png"
        assert png.exists() and (figures / f"{stem}.svg").exists()
        assert png.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n" and png.stat().st_size < 150_000
        assert f"](figures/{stem}.png)" in text

    html = (reports / "report.html").read_text()
    assert '<img src="data:image/png;base64,' in html
    assert html.count("<img ") == text.count("![")

    manifest = json.loads((reports / "manifest.json").read_text())
    assert {"package_versions", "python", "git_commit", "platform", "inputs", "outputs", "cases",
            "stage_wall_seconds"} <= set(manifest)
    keys = manifest["cases"]["sliding_mode"]
    assert len(keys) == 7 and all(v["saved"] for v in keys.values())
    assert "cases:sliding_mode" in manifest["stage_wall_seconds"] and "run" in manifest["stage_wall_seconds"]
    inputs = {e["path"]: e["sha256"] for e in manifest["inputs"]}
    runs_path = next(p for p in inputs if p.endswith("tables/sliding_mode_runs.csv"))
    assert inputs[runs_path] == hashlib.sha256((reports / "tables" / "sliding_mode_runs.csv").read_bytes()).hexdigest()
    assert sum(p.endswith(".json") for p in inputs) == 7  # every saved run used

    # deterministic: building again gives the same files
    before = {p: (reports / p).read_bytes() for p in ("index.md", "report.html", "manifest.json")}
    build_report(reports, cache, cases)
    assert before == {p: (reports / p).read_bytes() for p in before}


def test_report_embeds_errata_and_lists_failed_cases(saved, tmp_path):
    reports, cache, cases = saved
    (reports / "tables" / "errata.md").write_text("# Errata\n\n| formula | verdict |\n|---|---|\n"
                                                   "| `a\\|b` | wrong |\n")
    pd.DataFrame([{"study": "sliding_mode", "case": "sliding_mode/runs [x]", "key": "k",
                   "error": "ValueError: boom"}]).to_csv(reports / "tables" / "failed_cases.csv", index=False)
    text = build_report(reports, cache, cases).read_text()
    assert "### Errata" in text and "| `a\\|b` | wrong |" in text
    assert "<code>a|b</code>" in (reports / "report.html").read_text()
    assert "## Failed cases" in text and "ValueError: boom" in text


def test_report_without_saved_runs(tmp_path, saved):
    cases = saved[2]
    text = build_report(tmp_path / "reports", tmp_path / "empty_cache", cases).read_text()
    assert "No saved runs found" in text and "initial_conditions.csv` is missing" in text
    assert (tmp_path / "reports" / "manifest.json").exists()


def test_report_outputs_are_written_atomically(tmp_path, saved, monkeypatch):
    """index.md, report.html and manifest.json go through the one atomic writer (temporary file, rename):
    each is written by it, none is left as a temporary file, and each gets open()'s usual mode."""
    import stat

    import study.report as report
    from study.integrity import atomic_write

    written = []
    monkeypatch.setattr(report, "atomic_write",
                        lambda path, text: written.append(Path(path).name) or atomic_write(path, text))
    out = tmp_path / "reports"
    build_report(out, tmp_path / "empty_cache", saved[2])
    assert {"index.md", "report.html", "manifest.json", "report_timing.csv"} <= set(written)
    assert not list(out.rglob("*.tmp"))
    mask = os.umask(0o022)
    os.umask(mask)
    for name in ("index.md", "report.html", "manifest.json"):
        assert stat.S_IMODE((out / name).stat().st_mode) == 0o666 & ~mask, name


def test_markdown_to_html_subset():
    md = "# T\n\nSome `x*y` and **bold** [link](a.csv).\n\n" + md_table(["a", "b"], [["1|2", "3"]], [False, True])
    html = markdown_to_html(md + "\n\n- one\n- two\n", lambda src: src, "t")
    assert '<h1 id="t">T</h1>' in html and "<code>x*y</code>" in html and "<strong>bold</strong>" in html
    assert '<a href="a.csv">link</a>' in html and "<td>1|2</td>" in html and '<td style="text-align:right">3</td>' in html
    assert "<li>one</li>" in html
    assert '<div class="table-wrap">\n<table>' in html  # wide tables scroll in their container
    with pytest.raises(ValueError, match="expected 2"):
        md_table(["a", "b"], [["1"]])


def test_markdown_to_html_links_math_toc_figures_footnotes():
    md = number_figures("# Report\n\nSee [`manifest.json`](manifest.json) and <b>raw</b>.[^n]\n\n"
                        "## First part\n\n### Detail\n\n![max |Φ| of *every* run](figures/a.png)\n\n"
                        "## Second part\n\n" + md_table(["f", "math"], [["x", md_math(r"\frac{a}{b} + |q_1|")]])
                        + "\n\n$$E = m c^2$$\n\n[^n]: a footnote\n")
    assert "*Figure 1.* max |Φ| of *every* run" in md  # numbered caption, readable in index.md too
    html = markdown_to_html(md, lambda src: "data:image/png;base64,AAAA", "t")
    body = html[html.index("<body>"):]
    assert '<a href="manifest.json"><code>manifest.json</code></a>' in body and "](" not in body
    assert "&lt;b&gt;raw&lt;/b&gt;" in body  # raw HTML is escaped, never passed through
    toc = body[body.index('<nav class="toc"'):body.index("</nav>")]
    assert [href for href in re.findall(r'href="#([^"]+)"', toc)] == ["first-part", "detail", "second-part"]
    assert body.index("</nav>") < body.index('<h2 id="first-part">')
    assert re.search(r'<figure id="figure-1"><img src="data:image/png;base64,AAAA" alt="max \|Φ\| of every run" />'
                     r"<figcaption><em>Figure 1\.</em> max \|Φ\| of <em>every</em> run</figcaption>", body)
    assert body.count("<math ") == 2 and 'display="block"' in body and "<mfrac>" in body
    assert "$" not in re.sub(r"<math.*?</math>", "", body, flags=re.S)
    assert 'class="footnote-ref"' in body and "a footnote" in body


def test_markdown_to_html_marks_unreadable_math():
    html = markdown_to_html("a $x^$ b and $\\left( y$\n", lambda src: src, "t")
    assert html.count('class="math-error"') == 2 and "<code" in html and "x^" in html and "<math" not in html


def test_report_html_typesets_the_errata(saved, tmp_path):
    """The errata table's printed and derived formulas (and their difference) become MathML."""
    reports, cache, cases = saved
    frame = pd.DataFrame([{"formula": "000.a22", "paper": "000", "equation": "000 eq. (14)", "verdict": "wrong",
                           "printed": r"a_{22} = m_2 c_2 l_1 + m_3 l_2^2 + J_2", "derived": "J2 + c2**2*m2 + l2**2*m3",
                           "derived_latex": r"J_{2} + {\color{crimson}c_{2}^{2} m_{2}} + l_{2}^{2} m_{3}",
                           "difference_latex": r"c_{2} m_{2} \left(- c_{2} + l_{1}\right)", "note": "m2*c2 |x|"}])
    (reports / "tables" / "errata.md").write_text(errata_markdown(frame))
    build_report(reports, cache, cases)
    html = (reports / "report.html").read_text()
    section = html[html.index('<h2 id="errata">'):html.index("<h2", html.index('<h2 id="errata">') + 5)]
    assert section.count("<math ") == 3 and 'mathcolor="crimson"' in section
    assert "<msub><mi>a</mi><mrow><mn>22</mn></mrow></msub>" in section
    assert "m2*c2 |x|" in section and "](" not in section
    assert '<nav class="toc"' in html and 'href="#errata"' in html


def test_claims_verdicts_follow_the_tables(tmp_path, saved):
    """Each claim's verdict is computed from its table: change the table, the verdict changes."""
    reports = tmp_path / "reports"
    (reports / "tables").mkdir(parents=True)
    pd.DataFrame({"mechanism": ["slider_crank", "quick_return"], "max_abs_phi_printed": [5.204, 1.5e-4]}).to_csv(
        reports / "tables" / "initial_conditions.csv", index=False)
    pd.DataFrame({"paper": [0, 0, 1], "verdict": ["exact", "wrong", "exact"]}).to_csv(
        reports / "tables" / "errata.csv", index=False)
    text = build_report(reports, tmp_path / "no_cache", saved[2]).read_text()
    claims = text[text.index("## Claims of the papers"):text.index("## Initial conditions")]
    assert "| 000 | the printed equations of motion are correct | fails (1 wrong) |" in claims
    assert "| 001 | the printed equations of motion are correct | holds |" in claims
    assert "| 000 | the printed initial state satisfies the constraints | fails | max\\|Φ\\| at the printed q(0) = 5.204 m" in claims
    assert "| 001 | the printed initial state satisfies the constraints | holds |" in claims
    assert claims.count("not checked") == 5  # friction and the four sliding-mode claims have no table


def test_case_lists_name_their_report_sections(tmp_path):
    """The report's sections come from the case lists ([study] section, section_order) and FIXED_SECTIONS;
    the study's own case lists give the order below."""
    from study.report import report_sections

    assert report_sections(pl.load_case_lists()) == (
        "claims", "initial", "errata", "sliding_mode", "sensitivity", "slider_crank", "cross_validation",
        "work_precision", "benchmarks", "beyond_papers", "backends", "reproducibility")
    folder = tmp_path / "cases"
    folder.mkdir()
    (folder / "a.toml").write_text(TINY)
    (folder / "b.toml").write_text(TINY.replace("section_order = 40", "section_order = 45"))
    with pytest.raises(pl.CaseListError, match="section_order = 45"):
        report_sections(pl.load_case_lists(folder))
    (folder / "b.toml").write_text(TINY.replace('section = "sliding_mode"', 'section = "no_such_section"'))
    with pytest.raises(pl.CaseListError, match="no module"):
        report_sections(pl.load_case_lists(folder))
    (folder / "b.toml").write_text(TINY.replace("section_order = 40\n", ""))
    with pytest.raises(pl.CaseListError, match="go together"):
        pl.load_case_lists(folder)


def test_a_section_of_your_own_outside_the_package(tmp_path, monkeypatch):
    """A case list may name a report section by the dotted name of any importable module."""
    import importlib

    from study.report import report_sections, section_module

    package = tmp_path / "mine"
    package.mkdir()
    (package / "__init__.py").write_text("")
    (package / "yoke_section.py").write_text("def section(ctx):\n    return ['## My yoke', '']\n")
    monkeypatch.syspath_prepend(str(tmp_path))
    folder = tmp_path / "cases"
    folder.mkdir()
    (folder / "b.toml").write_text(TINY.replace('section = "sliding_mode"', 'section = "mine.yoke_section"'))
    sections = report_sections(pl.load_case_lists(folder))
    assert "mine.yoke_section" in sections and "sliding_mode" not in sections
    assert importlib.import_module(section_module("mine.yoke_section")).section(None) == ["## My yoke", ""]
    (folder / "b.toml").write_text(TINY.replace('section = "sliding_mode"', 'section = "theirs.yoke_section"'))
    with pytest.raises(pl.CaseListError, match="no module theirs.yoke_section can be imported"):
        report_sections(pl.load_case_lists(folder))


def test_backends_section_lists_every_pair_that_does_not_agree(tmp_path):
    """A sampled compiled/reference pair beyond its bound is named with its numbers in the report."""
    from study.report.context import ReportContext
    from study.report.sections import backends

    tables = tmp_path / "tables"
    tables.mkdir()
    rule = "adaptive_global_error_factor * rtol * max|q|"
    pd.DataFrame({"study": ["slider_crank", "slider_crank", "work_precision"],
                  "case": ["slider_crank/eps_sweep [eps=1e-2]", "slider_crank/treatments [exact]", "work_precision/rk4 [h=2e-3]"],
                  "t_end": [20.0, 20.0, 5.0], "max_abs_dq": [5.77e-5, 1e-9, 2e-13], "bound": [4.44e-5, 4.4e-6, 5e-8],
                  "rule": [rule, rule, "fast_fixed_step_agreement * max|q|"], "agree": [False, True, True]}
                 ).to_csv(tables / "backend_agreement.csv", index=False)
    text = "\n".join(backends.section(ReportContext(reports_dir=tmp_path, store=None, case_lists={})))
    assert "**2 of 3 sampled pairs agree**" in text and "slider_crank 1 of 2, work_precision 1 of 1" in text
    assert "| slider_crank | slider_crank/eps_sweep [eps=1e-2] | 5.77e-05 | 4.44e-05 | 1.3 |" in text
    assert "treatments [exact]" not in text
