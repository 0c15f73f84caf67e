"""The docstring examples of the library run (on the installed package, editable or not)."""

import doctest
import importlib
import pkgutil

import pytest

import procam

MODULES = sorted(m.name for m in pkgutil.walk_packages(procam.__path__, "procam.")
                 if not m.name.startswith("procam.cli"))


@pytest.mark.parametrize("name", ["procam", *MODULES])
def test_docstring_examples(name):
    module = importlib.import_module(name)
    result = doctest.testmod(module, optionflags=doctest.ELLIPSIS | doctest.NORMALIZE_WHITESPACE, verbose=False)
    assert result.failed == 0, f"{result.failed} of {result.attempted} docstring examples failed in {name}"


def test_the_examples_are_there():
    """Guard against the test above passing vacuously: the library has docstring examples to run."""
    finder = doctest.DocTestFinder()
    n = sum(len(t.examples) for name in ["procam", *MODULES] for t in finder.find(importlib.import_module(name)))
    assert n >= 20, n
