"""The report opens with its findings: one answer per question, each with a number and a link to its section.

Checked on the committed report (reports/index.md, reports/report.html, rebuilt by ``make reproduce``) and on the
renderer's placement of the table of contents.
"""

from __future__ import annotations

import re
from pathlib import Path

from mdit_py_plugins.anchors.index import slugify

from study.report.render import markdown_to_html
from study.report.sections import findings

REPORTS = Path(__file__).resolve().parents[1] / "reports"


def test_findings_are_the_first_section_with_a_number_and_a_live_link_per_question():
    text = (REPORTS / "index.md").read_text()
    headings = re.findall(r"^(#{1,3}) (.+)$", text, flags=re.M)
    assert [h for h in headings if h[0] == "##"][0][1] == findings.TITLE
    slugs = {slugify(title) for _, title in headings}
    block = text.split(f"## {findings.TITLE}\n", 1)[1].split("\n## ", 1)[0]
    answers = [line for line in block.splitlines() if line.startswith("- **")]
    assert [a.split("**")[1] for a in answers] == [q for q, _ in findings.QUESTIONS]
    for answer in answers:
        assert "not computed" not in answer, answer
        assert re.search(r"\d", answer.split("**", 2)[2]), answer
        targets = re.findall(r"\]\(#([^)]+)\)", answer)
        assert targets and set(targets) <= slugs, (answer, set(targets) - slugs)


def test_the_html_page_shows_the_findings_before_its_contents():
    page = (REPORTS / "report.html").read_text()
    assert page.index(f'id="{findings.ANCHOR}"') < page.index('<nav class="toc"') < page.index('id="claims-of-the-papers"')


def test_contents_go_after_the_named_section_or_before_the_first_heading():
    md = "# T\n\n## A\n\ntext a\n\n## B\n\ntext b\n"
    after = markdown_to_html(md, lambda s: s, "T", toc_after="a")
    assert after.index('id="a"') < after.index("<nav") < after.index('id="b"')
    plain = markdown_to_html(md, lambda s: s, "T")
    assert plain.index("<nav") < plain.index('id="a"')


def test_the_spatial_answer_reads_bricard_and_the_joint_friction_from_their_tables():
    """Bricard's A04 energy ratios over the benchmark's horizon, in-house and in Exudyn (each against the in-house
    run's bound), and the carriage's stick times in the committed answer are the tables' values."""
    import pandas as pd

    text = (REPORTS / "index.md").read_text()
    answer = next(line for line in text.splitlines() if line.startswith("- **Spatial mechanisms"))
    runs = pd.read_csv(REPORTS / "tables" / "spatial_runs.csv")
    bench = runs[(runs["mechanism"] == "bricard") & runs["group"].isin(["benchmark", "exudyn_benchmark"])]
    assert sorted(bench["engine"]) == ["exudyn", "inhouse"]
    for _, r in bench.iterrows():
        engine = {"inhouse": "in-house", "exudyn": "Exudyn"}[r["engine"]]
        assert f"{engine} at {r['drift_over_bound']:.2g} of it ({r['setting']})" in answer
    exact = pd.read_csv(REPORTS / "tables" / "spatial_friction.csv").query("law == 'exact'")
    first, second = (float(t) for t in exact["stick_times"].iloc[0].split(";"))
    assert f"stick at {first:.7g} and {second:.7g} s" in answer
