"""The study's cases as data, run through an on-disk cache keyed by everything that affects them.

One module per concept:

* :mod:`.cases`: the case-list schema (``reference/cases/<study>.toml``) and its expansion into cases;
* :mod:`.keys`: a case's key, from its mechanism's fingerprint and the code version of its engine;
* :mod:`.store`: the saved results, one per key, checked on every read, and the recorded failures;
* :mod:`.executors`: where cases run (this process, a local process pool, a Dask cluster);
* :mod:`.execute`: running one case, and every case not stored yet, with progress;
* :mod:`.summaries`: each study's summary and the pipeline's own tables (failures, backend agreement);
* :mod:`.tables`: the one writer of tables (recording each in ``checksums.json`` beside it) and the one checked reader;
* :mod:`.orchestrate`: the whole run, :func:`run_pipeline`, and its record.

The names below are re-exported, so ``from study.pipeline import Case, Store, run_pipeline`` works.
"""

from study.pipeline.cases import (BACKENDS, CASES_DIR, ENGINES, SAMPLE_SUFFIX, Case, CaseList, CaseListError, find,
                                  find_one, load_case_list, load_case_lists)
from study.pipeline.execute import Progress, RunSummary, run_case, run_cases
from study.pipeline.executors import InlineExecutor, environment_workers, make_executor
from study.pipeline.keys import ENTRY_MODULES, NUMERIC_PACKAGES, code_version, mechanism_hash
from study.pipeline.orchestrate import PIPELINE_RECORD, run_pipeline, save_record
from study.pipeline.store import CorruptResult, MissingResult, Store
from study.pipeline.summaries import (backend_agreement, backend_cpu, failures_table, sample_agreement, summarize,
                                      summary_function)
from study.pipeline.tables import (CHECKSUMS, TABLE_FLOAT_FORMAT, check_tables, read_table, recorded, verified_text,
                                   write_table, write_tables)

__all__ = [
    "BACKENDS", "CASES_DIR", "CHECKSUMS", "ENGINES", "ENTRY_MODULES", "NUMERIC_PACKAGES", "PIPELINE_RECORD",
    "SAMPLE_SUFFIX", "TABLE_FLOAT_FORMAT", "Case", "CaseList", "CaseListError", "CorruptResult", "InlineExecutor",
    "MissingResult", "Progress", "RunSummary", "Store", "backend_agreement", "backend_cpu", "check_tables",
    "code_version", "environment_workers", "failures_table", "find", "find_one", "load_case_list",
    "load_case_lists", "make_executor", "mechanism_hash", "read_table", "recorded", "run_case", "run_cases",
    "run_pipeline", "sample_agreement", "save_record", "summarize", "summary_function", "verified_text",
    "write_table", "write_tables",
]
