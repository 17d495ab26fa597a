"""The examples in vibkit's docstrings run, and print what the docstrings say they print.

Every module of the package is imported and its docstrings' ``>>>`` examples run with :mod:`doctest`
(``ELLIPSIS`` and ``NORMALIZE_WHITESPACE``, as numpydoc examples are written). An example marked
``# doctest: +SKIP`` needs a file of the repository or a simulation and is left out, as it is by
``python -m doctest``. The harness itself is checked on a docstring whose printed value is wrong.
"""

import doctest
import importlib
import pkgutil

import pytest

import vibkit

FLAGS = doctest.ELLIPSIS | doctest.NORMALIZE_WHITESPACE


def _modules():
    names = []
    for info in pkgutil.walk_packages(vibkit.__path__, "vibkit."):
        if info.name.endswith("__main__"):  # running it parses sys.argv
            continue
        names.append(info.name)
    return ["vibkit", *names]


def _examples(name):
    module = importlib.import_module(name)
    return [t for t in doctest.DocTestFinder(exclude_empty=True).find(module, name) if t.examples]


MODULES = [name for name in _modules() if _examples(name)]


def _run(tests):
    runner = doctest.DocTestRunner(optionflags=FLAGS)
    for test in tests:
        runner.run(test)
    return runner.summarize(verbose=False)


@pytest.mark.parametrize("name", MODULES)
def test_docstring_examples_run(name):
    result = _run(_examples(name))
    assert result.failed == 0, f"{result.failed} docstring example(s) of {name} failed (the report is above)"


def test_the_signal_examples_are_among_them():
    # the issue named vibkit.signal's examples: each of its modules with examples is collected, and runs some
    signal = [n for n in MODULES if n.startswith("vibkit.signal.")]
    assert len(signal) >= 6
    assert all(_run(_examples(n)).attempted > 0 for n in signal)


def test_a_wrong_example_fails():
    def wrong():
        """
        >>> 1 + 1
        3
        """

    tests = doctest.DocTestFinder().find(wrong, "wrong")
    runner = doctest.DocTestRunner(optionflags=FLAGS)
    for test in tests:
        runner.run(test, out=lambda s: None)
    assert runner.failures == 1
