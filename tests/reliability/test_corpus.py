"""Every case of the reliability corpus (``tests/reliability/corpus.py`` and ``corpus_*.py``): a clean
one-line error or a result, never a traceback, and nothing a user gave lost or clobbered.

Cases run in-process through ``vibkit.cli.main`` (fast); those that inject faults, send signals or
could hang on a regression (a FIFO) run in a subprocess.  ``benchmarks/reliability.py`` runs the
same corpus, all in subprocesses, and writes the table quoted in the docs.
"""

import importlib.util
import sys
from pathlib import Path

import pytest

_spec = importlib.util.spec_from_file_location("vibkit_reliability_corpus", Path(__file__).with_name("corpus.py"))
corpus = importlib.util.module_from_spec(_spec)
sys.modules[_spec.name] = corpus
_spec.loader.exec_module(corpus)
all_cases, run_case = corpus.all_cases, corpus.run_case

CASES = [c for c in all_cases() if not c.heavy]  # heavy ones: see their notes; the table runs them


# the cases that need a subprocess of their own (fault injection, signals, FIFOs) take a second or two each
PARAMS = [pytest.param(c, marks=pytest.mark.slow) if c.needs_subprocess else c for c in CASES]


@pytest.mark.parametrize("case", PARAMS, ids=[c.name for c in CASES])
def test_case(case, tmp_path):
    res = run_case(case, tmp_path / "w", inprocess=True, timeout=240)
    assert res["passed"], f"{case.name}: {res['problems']} (message: {res['message']!r})"
