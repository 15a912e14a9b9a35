"""Examples executed at every build: ``docs/examples/*.py`` run, their output and figures in the pages.

When the builder starts, every script in ``docs/examples/`` runs in a subprocess (this Python, so
the installed g2tom) in a fresh temporary folder. Its standard output and every PNG it writes in
that folder are kept, and a MyST page per example is written to ``docs/_generated/examples/``:
the script's docstring as the introduction, the code (``literalinclude`` of the script itself),
the printed output and the figures. A script that fails stops the build with its error, so the
pages never show code that no longer runs. ``docs/examples/index.md`` lists the pages (a glob toctree).

Configuration values: ``g2tom_examples_timeout`` (s per script, default 300).
"""

from __future__ import annotations

import ast
import hashlib
import os
import shutil
import subprocess
import sys
import tempfile
import time
from pathlib import Path
from typing import Any

from sphinx.errors import ExtensionError
from sphinx.util import logging

logger = logging.getLogger(__name__)

#: Threads per script: one BLAS/OpenMP thread, as the command line sets, so that small solves
#: are not oversubscribed on a shared machine.
ENV = {"MPLBACKEND": "Agg", "OMP_NUM_THREADS": "1", "OPENBLAS_NUM_THREADS": "1", "MKL_NUM_THREADS": "1",
       "PYTHONHASHSEED": "0"}


def _docstring(script: Path) -> tuple[str, str]:
    """The script's title (the docstring's first line) and the rest of its docstring."""
    text = ast.get_docstring(ast.parse(script.read_text())) or script.stem.replace("_", " ").capitalize()
    title, _, rest = text.partition("\n")
    return title.strip().rstrip("."), rest.strip()


def run_example(script: Path, timeout: float = 300.0) -> tuple[str, dict[str, bytes], float]:
    """Run one script in a fresh temporary folder.

    Returns
    -------
    tuple
        Its standard output, ``{name: bytes}`` of the PNG files it wrote in its folder, and its wall
        time in s.

    Raises
    ------
    sphinx.errors.ExtensionError
        If the script exits with an error or runs past ``timeout``.
    """
    with tempfile.TemporaryDirectory(prefix=f"g2tom-example-{script.stem}-") as folder:
        started = time.perf_counter()
        try:
            done = subprocess.run([sys.executable, str(script.resolve())], cwd=folder, capture_output=True,
                                  text=True, timeout=timeout, env={**os.environ, **ENV})
        except subprocess.TimeoutExpired as exc:
            raise ExtensionError(f"example {script.name} ran past {timeout:g} s") from exc
        seconds = time.perf_counter() - started
        if done.returncode != 0:
            raise ExtensionError(f"example {script.name} failed (exit {done.returncode}):\n{done.stderr[-4000:]}")
        figures = {p.name: p.read_bytes() for p in sorted(Path(folder).glob("*.png"))}
    return done.stdout, figures, seconds


def page_markdown(script: Path, output: str, figures: list[str], seconds: float, source: str) -> str:
    """The MyST page of one example: introduction, code, output, figures.

    ``source`` is the script's path relative to the page, for ``literalinclude``.
    """
    title, intro = _docstring(script)
    fence = "`" * max(4, max((len(run) for run in output.split("\n") if set(run) == {"`"}), default=0) + 1)
    lines = [f"# {title}", "", intro, "",
             f"The script `docs/examples/{script.name}` ran in {seconds:.0f} s when this page was built; "
             "the output and figures below are its own.", "",
             "## Code", "",
             f"```{{literalinclude}} {source}", ":language: python", ":lines: " + _after_docstring(script), "```", "",
             "## Output", "", f"{fence}text", output.rstrip() or "(nothing printed)", fence, ""]
    if figures:
        lines += ["## Figure" + ("s" if len(figures) > 1 else ""), ""]
        for name in figures:
            lines += [f"```{{image}} {script.stem}/{name}", f":alt: {name}", "```", ""]
    return "\n".join(lines)


def _after_docstring(script: Path) -> str:
    """``literalinclude``'s ``:lines:`` that leave out the module docstring (it is the page's prose)."""
    tree = ast.parse(script.read_text())
    first = tree.body[0] if tree.body else None
    if isinstance(first, ast.Expr) and isinstance(getattr(first, "value", None), ast.Constant) \
            and isinstance(first.value.value, str):
        return f"{first.end_lineno + 2}-"
    return "1-"


def _write(path: Path, data: bytes) -> None:
    """Write ``data`` unless the file already holds it (an unchanged page is not read again)."""
    if not path.is_file() or hashlib.sha256(path.read_bytes()).digest() != hashlib.sha256(data).digest():
        path.parent.mkdir(parents=True, exist_ok=True)
        path.write_bytes(data)


def write_examples(examples: Path, out: Path, timeout: float = 300.0) -> dict[str, float]:
    """Run every ``examples/*.py`` and write its page and figures under ``out``; returns the times in s."""
    times = {}
    out.mkdir(parents=True, exist_ok=True)
    scripts = sorted(examples.glob("*.py"))
    for stale in out.glob("*.md"):
        if not (examples / f"{stale.stem}.py").is_file():
            stale.unlink()
            shutil.rmtree(out / stale.stem, ignore_errors=True)
    for script in scripts:
        output, figures, seconds = run_example(script, timeout)
        for old in (out / script.stem).glob("*.png"):
            if old.name not in figures:
                old.unlink()
        for name, data in figures.items():
            _write(out / script.stem / name, data)
        source = os.path.relpath(script, out)
        _write(out / f"{script.stem}.md", page_markdown(script, output, list(figures), seconds, source).encode())
        times[script.name] = seconds
        logger.info(f"example {script.name}: {seconds:.1f} s, {len(figures)} figure(s)")
    return times


def _on_builder_inited(app: Any) -> None:
    src = Path(app.srcdir)
    times = write_examples(src / "examples", src / "_generated" / "examples", app.config.g2tom_examples_timeout)
    logger.info(f"examples: {len(times)} run in {sum(times.values()):.1f} s")


def setup(app: Any) -> dict[str, Any]:
    app.add_config_value("g2tom_examples_timeout", 300.0, "env")
    app.connect("builder-inited", _on_builder_inited)
    return {"parallel_read_safe": True, "parallel_write_safe": True}
