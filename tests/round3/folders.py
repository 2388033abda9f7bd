"""Round three, group 'folders and saves': see tests/round3/__init__.py.

A command writes only into a folder it made (marked ``.study-output``) or an empty or new one; a user's non-empty
folder is refused before any work, naming it. A saved result pair (CSV + JSON) is replaced only as a whole.
"""

from __future__ import annotations

import os
from pathlib import Path

from round3 import OK, add

G = "folders and saves"
REPO = Path(__file__).resolve().parents[2]
FIVE_BAR = str(REPO / "examples" / "five_bar" / "five_bar.py")
MARKER = ".study-output"


def user_folder(tmp: Path) -> Path:
    """A user's own folder with files in it, in the places a report or a validation writes."""
    mine = tmp / "mine"
    for rel in ("notes.txt", "runs/keep.csv", "tables/keep.csv", "figures/keep.png", "timing/keep.csv"):
        (mine / rel).parent.mkdir(parents=True, exist_ok=True)
        (mine / rel).write_text(f"the user's {rel}\n")
    return mine


def into_user_folder(*argv):
    return lambda tmp: [*argv, "--out", str(user_folder(tmp))]


add(G, "validate_out_user_folder", into_user_folder("validate", FIVE_BAR, "--t-end", "0.1"), 2,
    "mine", MARKER)
add(G, "run_out_user_folder", into_user_folder("run", "sliding_mode", "--workers", "1"), 2, "mine", MARKER)
add(G, "report_out_user_folder", into_user_folder("report"), 2, "mine", MARKER)
add(G, "verify_out_user_folder", into_user_folder("verify", "sliding_mode", "--workers", "1"), 2, "mine", MARKER)
add(G, "verify_perturb_out_user_folder", into_user_folder("verify", "sliding_mode", "--perturb", "--workers", "1"), 2,
    "mine", MARKER)
add(G, "initial_out_user_folder", into_user_folder("initial"), 2, "mine", MARKER)
add(G, "errata_out_user_folder", into_user_folder("errata"), 2, "mine", MARKER)
add(G, "reproduce_out_user_folder", into_user_folder("reproduce", "--workers", "1"), 2, "mine", MARKER)


def afile(tmp: Path) -> str:
    (tmp / "afile.txt").write_text("a user's file\n")
    return str(tmp / "afile.txt")


add(G, "report_out_is_a_file", lambda tmp: ["report", "--out", afile(tmp)], 2, "afile.txt", "not a folder")
add(G, "validate_out_is_a_file", lambda tmp: ["validate", FIVE_BAR, "--t-end", "0.1", "--out", afile(tmp)], 2,
    "afile.txt", "not a folder")


def simulate_into(out):
    return lambda tmp: ["simulate", "slider_crank", "--t-end", "0.05", "--out", out(tmp)]


def existing_folder(tmp: Path) -> str:
    (tmp / "results").mkdir()
    (tmp / "results" / "old.csv").write_text("a,b\n1,2\n")
    return str(tmp / "results")


def users_csv(tmp: Path) -> str:
    (tmp / "data.csv").write_text("t,x\n0,1\n")   # a user's own table, no JSON beside it: not a saved result
    return str(tmp / "data")


add(G, "simulate_out_is_a_folder", simulate_into(existing_folder), 2, "results", "folder")
add(G, "simulate_out_over_a_users_csv", simulate_into(users_csv), 2, "data.csv", "not a saved result")


# --- a saved pair is replaced only as a whole ------------------------------------------------------------------
def _pair(tmp: Path):
    from study.simulate import simulate

    base = tmp / "saved" / "run"
    simulate("slider_crank", t_end=0.05, output_step=0.01).save(base)
    return base


def _failing_replace(when):
    """os.replace that fails (``when(src, dst)`` -> an exception to raise, or None) and otherwise replaces."""
    real = os.replace

    def replace(src, dst, *args, **kwargs):
        exc = when(str(src), str(dst))
        if exc is not None:
            raise exc
        return real(src, dst, *args, **kwargs)
    return real, replace


def save_with(tmp: Path, when, catch=OSError):
    """Save a new (longer) result over a saved pair while os.replace fails as ``when`` says; re-raise the failure
    after checking that the previous pair is still whole: it loads, with its own 6 samples."""
    from study.results import SimulationResult
    from study.simulate import simulate

    base = _pair(tmp)
    new = simulate("slider_crank", t_end=0.1, output_step=0.01)
    real, failing = _failing_replace(when)
    os.replace = failing
    try:
        new.save(base)
    except catch as exc:
        failure = exc
    else:
        raise AssertionError("the failing save did not report its failure")
    finally:
        os.replace = real
    assert len(SimulationResult.load(base).t) == 6, "the previous result is not whole"
    if isinstance(failure, Exception):
        raise failure


def json_immutable(src, dst):   # the JSON cannot be replaced (an immutable file): after the CSV was
    return PermissionError(1, "Operation not permitted", dst) if dst.endswith("/saved/run.json") else None


def csv_immutable(src, dst):
    return PermissionError(1, "Operation not permitted", dst) if dst.endswith("/saved/run.csv") else None


def interrupted_between(src, dst):   # Ctrl-C after the first file was renamed
    return KeyboardInterrupt() if dst.endswith("/saved/run.json") else None


add(G, "save_json_cannot_be_replaced", lambda tmp: save_with(tmp, json_immutable), OSError,
    "run.json", "previous result intact")
add(G, "save_csv_cannot_be_replaced", lambda tmp: save_with(tmp, csv_immutable), OSError,
    "run.csv", "previous result intact")
add(G, "save_interrupted_between_files", lambda tmp: save_with(tmp, interrupted_between, catch=KeyboardInterrupt),
    OK)


def rollback_fails(tmp):
    """The JSON cannot be replaced, nor the CSV put back: the pair does not match, so it is refused when read."""
    from study.errors import ResultIntegrityError
    from study.results import SimulationResult
    from study.simulate import simulate

    base = _pair(tmp)
    into_csv = []

    def when(src, dst):   # the first rename into run.csv (the new CSV) works, the one putting the old back fails
        if dst.endswith("/saved/run.csv"):
            into_csv.append(src)
        if dst.endswith("/saved/run.json") or (dst.endswith("/saved/run.csv") and len(into_csv) > 1):
            return PermissionError(1, "Operation not permitted", dst)
        return None
    real, failing = _failing_replace(when)
    os.replace = failing
    try:
        simulate("slider_crank", t_end=0.1, output_step=0.01).save(base)
    except OSError as exc:
        failure = exc
    finally:
        os.replace = real
    try:
        SimulationResult.load(base)
    except ResultIntegrityError:
        raise failure from None
    raise AssertionError("a pair left half-replaced was read as a result")


add(G, "save_rollback_also_fails", rollback_fails, OSError, "run.json", "refused when read")


# --- a folder the command made is used again; a user's file in it survives --------------------------------------
def initial_twice(tmp):
    return ["initial", "--out", str(tmp / "new")]


def marked_and_kept(tmp):
    from study.cli import main

    out = tmp / "new"
    assert (out / MARKER).is_file(), f"{out} has no {MARKER} marker"
    (out / "notes.txt").write_text("mine\n")
    assert main(["initial", "--out", str(out)]) == 0, "the folder initial made was refused the second time"
    assert (out / "notes.txt").read_text() == "mine\n", "a user's file in the output folder was touched"


add(G, "initial_new_folder_marked_and_reused", initial_twice, OK, then=marked_and_kept, cli=True)


def empty_folder(tmp):
    (tmp / "empty").mkdir()
    return ["initial", "--out", str(tmp / "empty")]


def has_marker(tmp):
    assert (tmp / "empty" / MARKER).is_file(), "an empty folder used for output did not get its marker"
    assert (tmp / "empty" / "tables" / "initial_conditions.csv").is_file()


add(G, "initial_empty_folder_accepted", empty_folder, OK, then=has_marker, cli=True)


def validate_twice(tmp):
    out = tmp / "v"
    return ["validate", FIVE_BAR, "--t-end", "0.1", "--out", str(out)]


def second_validate_keeps_users_files(tmp):
    from study.cli import main

    out = tmp / "v"
    (out / "runs" / "my_notes.txt").write_text("mine\n")
    (out / "mine.txt").write_text("mine\n")
    assert main(["validate", FIVE_BAR, "--t-end", "0.1", "--out", str(out)]) in (0, 1)
    assert (out / "runs" / "my_notes.txt").read_text() == "mine\n", "a user's file in runs/ was deleted"
    assert (out / "mine.txt").read_text() == "mine\n"
    assert (out / "report.md").is_file()


add(G, "validate_same_folder_twice_keeps_users_files", validate_twice, OK, then=second_validate_keeps_users_files,
    cli=True, slow=True)


def committed_reports_marked(tmp):
    assert (REPO / "reports" / MARKER).is_file(), "the repository's reports/ carries no marker: make reproduce " \
                                                  "would be refused"


add(G, "repository_reports_folder_is_marked", committed_reports_marked, OK)
