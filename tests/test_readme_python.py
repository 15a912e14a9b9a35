"""The README's Python examples, run in order as a reader would after ``make run`` (issue 32).

The ``data/`` they read is a small run in a temporary working directory: the paper scenario with
:data:`tests.conftest.SMALL_OVERRIDES`, its fits from a synthetic cube (as tests/test_predict.py).
"""

from __future__ import annotations

import re
import warnings
from pathlib import Path

import pytest

from g2tom.before_work import load_scenario
from g2tom.stages import fits, surrogate
from g2tom.store import write_dataset
from tests.conftest import SMALL_OVERRIDES
from tests.test_fits_stage import synthetic_cube

README = Path(__file__).resolve().parents[1] / "README.md"


def python_blocks(text: str) -> list[str]:
    """The ```python blocks of a Markdown text, in order."""
    return re.findall(r"^```python\n(.*?)^```$", text, flags=re.M | re.S)


def test_blocks_are_found() -> None:
    blocks = python_blocks(README.read_text())
    assert len(blocks) >= 2 and any("predict_resistance" in b for b in blocks)
    assert python_blocks("x\n```python\na = 1\n```\n```sh\nb\n```\n```python\nc = 2\n```\n") == ["a = 1\n", "c = 2\n"]


def test_readme_python_examples_run_in_order(tmp_path, monkeypatch, capsys) -> None:
    from g2tom.before_work.domains import resolve

    small = resolve(load_scenario("paper_gt", SMALL_OVERRIDES))
    data = tmp_path / "data"
    write_dataset(fits.build(small, synthetic_cube(small, noise=0.2)), data, "fits", small)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", UserWarning)
        surrogate.run(small, data, None)
    monkeypatch.chdir(tmp_path)
    namespace: dict = {"__name__": "readme"}
    for k, block in enumerate(python_blocks(README.read_text())):
        try:
            exec(compile(block, f"README.md python block {k + 1}", "exec"), namespace)  # noqa: S102
        except Exception as exc:  # noqa: BLE001
            pytest.fail(f"README.md python block {k + 1} fails: {type(exc).__name__}: {exc}\n{block}")
    out = capsys.readouterr().out
    assert "the atlas surrogate" in out and "the run's own single-scene surrogate" in out
    assert namespace["p"].attrs["answered_by"].startswith("the atlas surrogate")
    assert namespace["own"].attrs["answered_by"].startswith("the run's own")
