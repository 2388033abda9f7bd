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
from study.errata.table import errata_markdown
from study.report.render import markdown_to_html, md_math, md_table, number_figures
from study.pipeline.tables import record_written
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
    write(reports / "tables" / "initial_conditions.csv",
          pd.DataFrame({"mechanism": ["quick_return"], "max_abs_phi_printed": [0.000149101776],
                        "max_abs_phi_consistent": [1e-16], "max_abs_phidot_printed": [2e-5],
                        "max_abs_phidot_consistent": [3e-16]}))
    return reports, cache, cases


def write(path, table):
    """A table made by a test, written by the one table writer (recorded beside it, as the report requires)."""
    from study.output_folder import claim_output_folder

    claim_output_folder(Path(path).parents[1])   # the report folder, as a command would have made it
    text = table if isinstance(table, str) else table.to_csv(index=False)
    pl.write_table(path, text, "written by the test")


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
    write(reports / "tables" / "errata.md", "# Errata\n\n| formula | verdict |\n|---|---|\n| `a\\|b` | wrong |\n")
    write(reports / "tables" / "failed_cases.csv",
          pd.DataFrame([{"study": "sliding_mode", "case": "sliding_mode/runs [x]", "key": "k", "error": "ValueError: boom"}]))
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

    import study.pipeline.tables as tables

    written = []
    for module in (report, tables):   # the report's own files, and its timing table through the table writer
        monkeypatch.setattr(module, "atomic_write",
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
    write(reports / "tables" / "errata.md", errata_markdown(frame))
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
    write(reports / "tables" / "initial_conditions.csv",
          pd.DataFrame({"mechanism": ["slider_crank", "quick_return"], "max_abs_phi_printed": [5.204, 1.5e-4]}))
    write(reports / "tables" / "errata.csv", pd.DataFrame({"paper": [0, 0, 1], "verdict": ["exact", "wrong", "exact"]}))
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
        "moving_friction", "work_precision", "benchmarks", "spatial", "beyond_papers", "backends", "energy_balance",
        "reproducibility")
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
    record_written(tables / "backend_agreement.csv", "written by the test")   # as the one table writer would
    text = "\n".join(backends.section(ReportContext(reports_dir=tmp_path, store=None, case_lists={})))
    assert "**2 of 3 sampled pairs agree**" in text and "slider_crank 1 of 2, work_precision 1 of 1" in text
    assert "| slider_crank | slider_crank/eps_sweep [eps=1e-2] | 5.77e-05 | 4.44e-05 | 1.3 |" in text
    assert "treatments [exact]" not in text


def test_benchmark_overview_judges_every_run_by_its_source_verdict(tmp_path):
    """The overview that opens "Benchmarks beyond the papers" has one row per run of A01 and A02, the in-house
    reference and each series' finest setting of Andrews, every run of Exudyn's slider-crank test model and every
    N = 2 run that reaches 10 s against fourBarMechanismIftomm's x_B0; its verdicts are the source tables' (A01 runs
    short of the horizon are not judged), Andrews has scd and no limit, and each CPU is its timing table's."""
    from study.report.context import ReportContext
    from study.report.sections import benchmark_overview as bo
    from study.studies import a01

    assert a01.verdict(1e-5, 20.0) == "not judged: 20 s of 2000 s" and a01.verdict(1e-5, 2000.0) == "high precision"
    assert bo.printed_digits(0.32846) == (5, 5e-6)
    tables, timing = tmp_path / "tables", tmp_path / "timing"
    tables.mkdir()
    timing.mkdir()

    def save(folder, name, frame):
        pd.DataFrame(frame).to_csv(folder / f"{name}.csv", index=False)
        record_written(folder / f"{name}.csv", "written by the test")   # as the one table writer would

    save(tables, "a01_runs", {"engine": ["inhouse", "inhouse", "exudyn"], "method": ["none", "none", "exudyn"],
                              "setting": ["DOP853 rtol=1e-08", "DOP853 rtol=1e-06", "index3 h=0.001"],
                              "t_end_s": [2000, 2000, 20], "output_steps": [4000, None, 40],
                              "x_max_error_m": [1.99, None, 2.4e-4], "y_max_error_m": [1.01, None, 1.3e-4],
                              "a01_verdict": ["fails", "stopped", "not judged: 20 s of 2000 s"],
                              "error": [None, "RunBoundError", None]})
    save(timing, "a01_timing", {"engine": ["inhouse", "exudyn"], "method": ["none", "exudyn"],
                                "setting": ["DOP853 rtol=1e-08", "index3 h=0.001"], "cpu_s": [0.48, 0.1]})
    runs = pd.DataFrame({"engine": ["inhouse", "inhouse", "inhouse", "exudyn", "exudyn"],
                         "method": ["multiplier + projection", "ALI3P", "ALI3P", "index3", "index3"],
                         "setting": ["RK45 rtol=1e-8", "h=2e-3", "h=2e-3", "h=0.001", "h=0.0005"],
                         "N": [2, 2, 40, 2, 2], "t_end_s": [10, 10, 20, 10, 10],
                         "stopped_at_s": [0.72, None, None, None, None],
                         "error": ["SingularConfigurationError", None, None, None, None],
                         "x_B0_max_error_m": [None, 2.4e-5, 4.3e-5, 1.9e-4, 4.8e-5],
                         "vx_B0_max_error_m_s": [None, 1.5e-4, 2.4e-4, 1.04e-3, 2.6e-4],
                         "a02_verdict": ["stopped", "high precision", "high precision", "low precision",
                                         "high precision"],
                         "x_B0_10s_minus_published_m": [None, 4.9e-6, None, -4.6e-5, 6e-6]})
    save(tables, "singular_four_bar_runs", runs)
    save(timing, "singular_four_bar_timing", {**{k: runs[k] for k in ("N", "engine", "method", "setting")},
                                              "cpu_s": [None, 1.2, 12.4, 0.5, 0.85]})
    save(tables, "andrews_reference", {"quantity": ["angle", "angle", "rate"], "coordinate": ["beta", "Theta", "beta"],
                                       "relative_difference": [-7e-11, 1e-10, 3e-7]})
    keys = {"group": ["reference", "compiled", "compiled", "exudyn", "exudyn"],
            "engine": ["inhouse", "inhouse", "inhouse", "exudyn", "exudyn"],
            "backend": ["reference", "compiled", "compiled", "exudyn", "exudyn"],
            "method": ["none", "none", "none", "exudyn", "exudyn"],
            "integrator": ["DOP853", "DOP853", "DOP853", "index3", "index3"],
            "rtol": [1e-13, 1e-8, 1e-12, None, None], "step": [None, None, None, 2e-4, 1.25e-5]}
    save(tables, "andrews_work_precision", {**keys, "relative_error_published": [1e-10, 1e-7, 1e-9, 1e-2, 1e-4]})
    save(timing, "andrews_work_precision_timing", {**keys, "cpu_seconds": [0.7, 0.01, 0.02, 0.03, 0.16]})
    sources = ["published (the test model: Exudyn index 2, h = 6e-05 s)",
               "in-house reference (DOP853, rtol 1e-12, projection)",
               "Exudyn from the descriptions, index 2, h = 6e-05 s",
               "Exudyn from the descriptions, index 2, h = 3e-05 s",
               "Richardson extrapolation of the two Exudyn runs"]
    save(tables, "exudyn_test_models", {"source": sources, "sum_abs_x_slider_m": [0.591649] * 5,
                                        "minus_published_m": [0.0, -5.9e-9, 5.4e-10, -2.5e-8, -5.9e-9]})
    save(tables, "exudyn_test_models_verdict", {"published_run_error_estimate_m": [6.5e-9], "bound_m": [1.95e-8],
                                                "agrees": [True]})
    save(timing, "exudyn_test_models_timing", {"source": sources[1:4], "cpu_s": [0.18, 0.28, 0.48]})

    ctx = ReportContext(reports_dir=tmp_path, store=None, case_lists={})
    table = bo.rows(ctx)
    by = {name: table[table["benchmark"] == name] for name in table["benchmark"].unique()}
    assert list(by[bo.A01]["verdict"]) == ["fails", "stopped (RunBoundError)", "not judged: 20 s of 2000 s"]
    assert list(by[bo.A01]["error"]) == ["1.99 m (x)", "–", "0.00024 m (x) over 20 s"]
    a02 = pd.concat([by[bo._a02(2)], by[bo._a02(40)]])
    assert len(a02) == len(runs)
    assert list(by[bo._a02(2)]["verdict"]) == ["stopped at t = 0.72 s (SingularConfigurationError)",
                                                "high precision", "low precision", "high precision"]
    assert list(by[bo._a02(40)]["verdict"]) == ["high precision"]
    assert list(by[bo.ANDREWS]["method"]) == ["reference: none, DOP853 rtol=1e-13", "none, DOP853 rtol=1e-12 (compiled)",
                                              "index3, h=1.25e-05"]   # the reference, then each series' finest
    assert list(by[bo.ANDREWS]["verdict"]) == [f"scd {s}; the Test Set sets no limit" for s in ("10", "9", "4")]
    assert list(by[bo.ANDREWS]["cpu_s"]) == [0.7, 0.02, 0.16]
    assert list(by[bo.SLIDER_CRANK]["verdict"]) == ["agrees: within 1.95e-08 m", "agrees: within 1.95e-08 m",
                                                    "does not agree: beyond 1.95e-08 m"]
    assert list(by[bo.SLIDER_CRANK]["cpu_s"]) == [0.18, 0.28, 0.48]
    assert list(by[bo.FOUR_BAR]["verdict"]) == ["matches the published 5 digits",
                                                "misses the published 5 digits by 4.6e-05 m",
                                                "misses the published 5 digits by 6e-06 m"]
    assert len(table) == 3 + len(runs) + 3 + 3 + 3
    text = "\n".join(bo.overview(ctx))
    assert text.count("\n| ") == len(table) + 1   # header and one line per row
    assert "| Exudyn | index3 h=0.001 | 0.00024 m (x) over 20 s | **not judged: 20 s of 2000 s** | 0.1 |" in text
