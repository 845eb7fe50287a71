"""Runnable docstring examples are checked (every module of the package with a ``>>>`` example)."""
from __future__ import annotations

import doctest
import importlib
from pathlib import Path

import pytest

import waveoptics

PKG = Path(waveoptics.__file__).resolve().parent
WITH_EXAMPLES = sorted(".".join(("waveoptics",) + p.relative_to(PKG).with_suffix("").parts).removesuffix(".__init__")
                       for p in PKG.rglob("*.py") if ">>> " in p.read_text())


def test_there_are_examples():
    assert "waveoptics.request" in WITH_EXAMPLES


@pytest.mark.parametrize("name", WITH_EXAMPLES)
def test_docstring_examples_run(name):
    module = importlib.import_module(name)
    result = doctest.testmod(module, optionflags=doctest.ELLIPSIS | doctest.NORMALIZE_WHITESPACE)
    assert result.failed == 0, f"{name}: {result.failed} of {result.attempted} docstring examples failed"
