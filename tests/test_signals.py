"""Ctrl-C and SIGTERM sent to a command's whole process group, as a terminal sends Ctrl-C.

The command is started in its own session, the signal sent to its group once it has started
work (a known line read), and then: one line, exit status 130 (143 for SIGTERM), no traceback
from any process (the local cluster's workers included), and no stray file.
"""

from __future__ import annotations

import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import pytest

from tests.conftest import SMALL_OVERRIDES

#: The small study of tests/conftest.py (Greenwood-Tripp's layer): a tiny cube, the fits the slowest stage.
_SMALL = [a for k, v in SMALL_OVERRIDES.items() for a in ("--set", f"{k}={v}")]
#: The tiny atlas of tests/test_atlas.py: five scenes.
_ATLAS = [*_SMALL, *(a for k, v in {"oxide.xi": [0.5], "oxide.lambda": [1.0, 5.0], "oxide.step_half_width": 0.0,
                                    "atlas.mu_min": 4.0, "atlas.mu_max": 16.0, "atlas.pi_min": 20.0,
                                    "atlas.pi_max": 40.0, "atlas.n_mu": 2, "atlas.n_pi": 2,
                                    "atlas.n_heldout": 1}.items() for a in ("--set", f"{k}={v}"))]


def _signalled(args: list[str], after: str, sig: int, data_dir: Path, delay: float = 1.0,
               again_after: float | None = None) -> tuple[int, str]:
    """Run ``g2tom args`` in a new session, send ``sig`` to its group ``delay`` s after a line holding
    ``after`` (and once more ``again_after`` s later, if given); its exit status and everything it
    wrote (stdout and stderr)."""
    proc = subprocess.Popen([sys.executable, "-m", "g2tom.cli.main", *args, "--data-dir", str(data_dir)],
                            stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True, start_new_session=True)
    lines = []
    try:
        for line in proc.stdout:
            lines.append(line)
            if after in line:
                time.sleep(delay)
                os.killpg(proc.pid, sig)
                if again_after is not None:
                    time.sleep(again_after)
                    os.killpg(proc.pid, sig)
                break
        lines.append(proc.stdout.read())
        return proc.wait(timeout=60), "".join(lines)
    finally:
        if proc.poll() is None:
            os.killpg(proc.pid, signal.SIGKILL)


def _after_signal(output: str, after: str) -> list[str]:
    """The lines written after the one holding ``after``."""
    return output.split(after, 1)[1].splitlines()[1:]


def _no_stray_files(data_dir: Path) -> None:
    assert not [p for p in data_dir.rglob(".*.tmp")], list(data_dir.rglob("*"))


@pytest.mark.parametrize("sig, status, word", [(signal.SIGINT, 130, "interrupted"), (signal.SIGTERM, 143, "terminated")])
def test_atlas_on_a_local_cluster_stops_with_one_line(tmp_path, sig, status, word) -> None:
    args = ["atlas", "--workers", "2", "--no-progress", *_ATLAS]
    rc, out = _signalled(args, "atlas: plan:", sig, tmp_path, delay=2.0)  # the first scene computing on the cluster
    assert rc == status, out
    assert "Traceback" not in out and "Error" not in out, out
    assert _after_signal(out, "atlas: plan:") == [f"g2tom: {word}: the scenes finished so far are kept in "
                                                  f"{tmp_path / 'atlas'}; run the same `g2tom atlas` command again to "
                                                  "continue from them"], out
    _no_stray_files(tmp_path)


def test_run_stops_with_one_line_and_resumes_to_the_same_numbers(tmp_path, capsys) -> None:
    import warnings

    from g2tom.cli.main import main

    args = ["run", "--no-bench", "--config", "paper_gt", *_SMALL]
    rc, out = _signalled(args, "cube: wrote", signal.SIGINT, tmp_path, delay=0.0)  # in the fits or the surrogate (the
    # rest takes ~3 s, less than a loaded machine can delay a signal sent later)
    assert rc == 130, out
    assert "Traceback" not in out and out.count("interrupted") == 1, out
    assert out.splitlines()[-1] == "g2tom: interrupted: stopped before the end; run the command again", out
    _no_stray_files(tmp_path)
    cube = (tmp_path / "cube.nc").read_bytes()
    capsys.readouterr()
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", UserWarning)  # surrogate orders reduced on a 3 x 3 grid
        status = main([*args, "--data-dir", str(tmp_path)])  # the same command again, in this process
    err = capsys.readouterr().err
    assert status == 0, err
    assert "cube: up to date" in err and (tmp_path / "cube.nc").read_bytes() == cube


@pytest.mark.parametrize("signal_exc, status, word", [(KeyboardInterrupt, 130, "interrupted"),
                                                      (None, 143, "terminated")])
def test_a_signal_wrapped_by_a_compiled_extension_is_still_one_line(monkeypatch, capsys, signal_exc, status,
                                                                      word) -> None:
    """A signal that comes while numba calls back into Python reaches us as SystemError("... returned a
    result with an exception set") caused by the signal's exception; other SystemErrors still raise."""
    from g2tom.cli import commands, main as cli

    cause = signal_exc() if signal_exc else cli.Terminated()

    def wrapped(args, scenario) -> None:
        try:
            raise cause
        except BaseException as inner:
            raise SystemError("CPUDispatcher(<function f>) returned a result with an exception set") from inner

    monkeypatch.setattr(commands, "params", wrapped)
    assert cli.main(["params"]) == status
    assert capsys.readouterr().err == f"g2tom: {word}: stopped before the end; run the command again\n"

    def broken(args, scenario) -> None:
        raise SystemError("a bug")

    monkeypatch.setattr(commands, "params", broken)
    with pytest.raises(SystemError, match="a bug"):
        cli.main(["params"])



@pytest.mark.parametrize("sig, status, word, gap", [(signal.SIGINT, 130, "interrupted", 0.02),
                                                     (signal.SIGTERM, 143, "terminated", 0.2)])
def test_a_second_signal_while_the_first_unwinds_adds_nothing(tmp_path, sig, status, word, gap) -> None:
    """Ctrl-C pressed twice, or `timeout`, which signals the command and then its whole group, while
    `g2tom surface` computes its positions and their oxide fields: one line, the first signal's status,
    no traceback, nothing written."""
    import numpy as np

    np.save(tmp_path / "map.npy", np.random.default_rng(1).normal(size=(256, 256)) * 2e-7)
    args = ["surface", str(tmp_path / "map.npy"), "--pixel-size", "5e-7", "--force", "0.01", "--positions", "400",
            "--xi", "0.3", "--correlation-length", "4e-6", "--fields", "2",
            "--set", "indenter.radius=1e-3", "--set", "material.modulus=5e10"]
    rc, out = _signalled(args, "MiB a task", sig, tmp_path, delay=0.5, again_after=gap)
    assert rc == status and "Traceback" not in out and "Error" not in out, out
    assert _after_signal(out, "MiB a task")[-1] == f"g2tom: {word}: stopped before the end; run the command again", out
    assert [p.name for p in tmp_path.rglob("*") if p.is_file()] == ["map.npy"], list(tmp_path.rglob("*"))
