"""The report is built from saved results only: figures, index.md, report.html and manifest.json
from a tiny synthetic set of saved runs, with every quoted number equal to the saved table's."""

import hashlib
import json

import numpy as np
import pandas as pd
import pytest

from study.report import build_report, saved_run_stem
from study.report.render import markdown_to_html, md_table
from study.results import SimulationResult
from study.studies import sliding_mode as sm

SETTING = "RK45 rtol=1e-8"
METHODS = ("none", "baumgarte", "sliding_mode/tanh")


def _options(setting, method):
    if (setting, method) == ("reference", "reference"):
        return sm.reference_options()
    return next(o for s, m, o in sm.cases() if (s, m) == (setting, method))


def _result(method, options, scale):
    """A small run whose max|Phi| is known: Phi grows for 'none', stays ~scale otherwise."""
    t = np.linspace(0.0, 1.0, 21)
    q = np.column_stack([3.0 + 6.0 * t, 2.0 + 0.1 * np.sin(6 * t), 2.7 + 0.1 * np.cos(6 * t)])
    q = q + scale * np.outer(t, [1.0, -1.0, 0.5])
    growth = np.exp(4 * t) if method == "none" else 1.0 + 0.5 * np.sin(20 * t) ** 2
    phi = scale * np.column_stack([growth, 0.5 * growth])
    meta = {"mechanism": "quick_return", "variant": "seed", "coordinate_names": ["q1", "q2", "q3"],
            "stabilization": options["method"], "t_end": 1.0, "output_step": 0.05,
            **{k: v for k, v in options.items() if k != "method"}}
    if options["method"] == "sliding_mode":
        meta.update({"Lambda": 10.0, "K": 10.0, "k": 1e-6, "width": 1e-8})
    return SimulationResult(t, q, np.gradient(q, t, axis=0), np.zeros_like(q), np.zeros((21, 2)), phi, 0.1 * phi,
                            energies={"kinetic": 1.0 + t}, stats={"steps": 20, "nfev": 120, "projections": 0},
                            meta=meta)


@pytest.fixture
def saved(tmp_path):
    """A cache with three runs and the reference, and a reports folder with minimal tables."""
    folder = tmp_path / "cache" / "results" / "sliding_mode"
    scales = {"none": 1e-6, "baumgarte": 2.5e-8, "sliding_mode/tanh": 2.4e-8}
    rows = []
    for method in METHODS:
        options = _options(SETTING, method)
        result = _result(method, options, scales[method])
        result.save(folder / saved_run_stem(SETTING, method, options))
        phi = np.abs(result.phi).max(axis=1)
        rows.append({"integrator_setting": SETTING, "method": method, "max_abs_phi": phi.max(),
                     "phi_growth_last_vs_first_quarter": phi[-5:].max() / phi[:5].max()})
    ref_options = _options("reference", "reference")
    _result("projection", ref_options, 0.0).save(folder / saved_run_stem("reference", "reference", ref_options))

    tables = tmp_path / "reports" / "tables"
    tables.mkdir(parents=True)
    runs = pd.DataFrame(rows)
    runs.to_csv(tables / "sliding_mode_runs.csv", index=False, float_format="%.4g")
    by = runs.set_index("method")["max_abs_phi"]
    pd.DataFrame([{"integrator_setting": SETTING, "none_max_abs_phi": by["none"],
                   "baumgarte_max_abs_phi": by["baumgarte"],
                   "sliding_mode_max_abs_phi_min": by["sliding_mode/tanh"],
                   "sliding_mode_max_abs_phi_max": by["sliding_mode/tanh"],
                   "sliding_mode_about_1e-8": True}]).to_csv(tables / "sliding_mode_claims.csv", index=False,
                                                           float_format="%.4g")
    pd.DataFrame({"mechanism": ["quick_return", "quick_return"], "coordinate": ["q1", "q2"],
                  "max_abs_phi_printed": [0.000149101776, 0.000149101776]}).to_csv(
        tables / "initial_conditions.csv", index=False)
    return tmp_path / "reports", tmp_path / "cache"


def _row(markdown, first_cells):
    """Cells of the table row of ``markdown`` that starts with ``first_cells``."""
    start = "| " + " | ".join(first_cells) + " |"
    line = next(line for line in markdown.splitlines() if line.startswith(start))
    return [c.strip() for c in line.strip().strip("|").split(" | ")]


def test_report_from_saved_runs(saved):
    reports, cache = saved
    index = build_report(reports, cache)
    assert index == reports / "index.md"
    text = index.read_text()
    for section in ("## Initial conditions", "## Errata", "## Constraint drift: the sliding-mode claims of paper 001",
                    "## All tables", "## Provenance"):
        assert section in text
    assert "errata table is missing" in text

    # numbers quoted in the text are the saved table's, digit for digit
    runs_csv = pd.read_csv(reports / "tables" / "sliding_mode_runs.csv", dtype=str).set_index("method")
    baumgarte = runs_csv.loc["baumgarte", "max_abs_phi"]
    row = _row(text, [SETTING, "10"])  # key-finding table: setting, omega, Baumgarte max|Phi|, ...
    assert row[2] == baumgarte
    assert float(row[2]) == float(runs_csv.loc["baumgarte", "max_abs_phi"])
    ratio = float(runs_csv.loc["sliding_mode/tanh", "max_abs_phi"]) / float(baumgarte)
    assert row[6] == f"{ratio:.3g}" and row[7] == f"{ratio:.3g}"
    assert "max|Φ| agrees for every run" in text  # the table matches the saved runs

    figures = reports / "figures"
    slug = "RK45_rtol1e-8"
    for stem in (f"quick_return_constraint_violation_{slug}", f"quick_return_velocity_constraint_violation_{slug}",
                 "quick_return_trajectories", "sliding_mode_max_abs_phi_heatmap"):
        png = figures / f"{stem}.png"
        assert png.exists() and (figures / f"{stem}.svg").exists()
        assert png.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n" and png.stat().st_size < 150_000
        assert f"](figures/{stem}.png)" in text

    html = (reports / "report.html").read_text()
    assert '<img src="data:image/png;base64,' in html
    assert html.count("<img ") == text.count("![")
    assert f"<td style=\"text-align:right\">{baumgarte}</td>" in html

    manifest = json.loads((reports / "manifest.json").read_text())
    assert {"package_versions", "git_commit", "platform", "inputs", "outputs"} <= set(manifest)
    inputs = {e["path"]: e["sha256"] for e in manifest["inputs"]}
    runs_path = "reports/tables/sliding_mode_runs.csv"
    assert inputs[runs_path] == hashlib.sha256((reports / "tables" / "sliding_mode_runs.csv").read_bytes()).hexdigest()
    assert sum(p.endswith(".json") for p in inputs) == len(METHODS) + 1  # every saved run used

    # deterministic: building again gives the same files
    before = {p: (reports / p).read_bytes() for p in ("index.md", "report.html", "manifest.json")}
    build_report(reports, cache)
    assert before == {p: (reports / p).read_bytes() for p in before}


def test_report_derives_missing_tables_and_embeds_errata(saved):
    reports, cache = saved
    (reports / "tables" / "sliding_mode_runs.csv").unlink()
    (reports / "tables" / "sliding_mode_claims.csv").unlink()
    (reports / "tables" / "errata.md").write_text("# Errata\n\n| formula | verdict |\n|---|---|\n"
                                                   "| `a\\|b` | wrong |\n")
    text = build_report(reports, cache).read_text()
    assert "derived at report time" in text
    assert "### Errata" in text and "| `a\\|b` | wrong |" in text
    assert "<code>a|b</code>" in (reports / "report.html").read_text()


def test_report_without_saved_runs(tmp_path):
    text = build_report(tmp_path / "reports", tmp_path / "empty_cache").read_text()
    assert "No saved runs found" in text and "initial_conditions.csv` is missing" in text
    assert (tmp_path / "reports" / "manifest.json").exists()


def test_markdown_to_html_subset():
    md = "# T\n\nSome `x*y` and **bold** [link](a.csv).\n\n" + md_table(["a", "b"], [["1|2", "3"]], [False, True])
    html = markdown_to_html(md + "\n\n- one\n- two\n", lambda src: src, "t")
    assert "<h1>T</h1>" in html and "<code>x*y</code>" in html and "<strong>bold</strong>" in html
    assert '<a href="a.csv">link</a>' in html and "<td>1|2</td>" in html and '<td style="text-align:right">3</td>' in html
    assert "<li>one</li>" in html
    with pytest.raises(ValueError, match="expected 2"):
        md_table(["a", "b"], [["1"]])
