"""Faults of the machine, not of the input: a full disk, no permission, a read-only file system or
installation, an environment numba refuses.

Every writer goes through :func:`g2tom.store.atomic_path` (stage files, figures, ``predict
--output``): a failed write is one ``g2tom: error:`` line naming the file and what was kept, exit
status 1, the previous file untouched. As root, permissions do not stop a write: the faults are
raised by monkeypatching the call that meets them.
"""

from __future__ import annotations

import errno
import os
import signal
import subprocess
import sys
import tempfile
from pathlib import Path

import matplotlib.pyplot as plt
import pytest
import xarray as xr

from g2tom.analysis import style
from g2tom.analysis.figures import write_figures
from g2tom.before_work import load_scenario
from g2tom.cli.main import main, numba_cache_dir
from g2tom.errors import WriteError
from g2tom.store import atomic_path, signals_deferred, stage_path, write_dataset


def _fail(code: int):
    """A stand-in for a writing call that meets ``code`` (an errno)."""

    def fail(*args, **kwargs):
        raise OSError(code, os.strerror(code))

    return fail


@pytest.mark.parametrize("code", [errno.ENOSPC, errno.EACCES, errno.EROFS])
def test_a_failed_stage_write_names_the_file_and_keeps_the_previous_one(tmp_path, monkeypatch, code) -> None:
    scenario = load_scenario("paper")
    ds = xr.Dataset({"x": ("i", [1.0, 2.0])})
    target = write_dataset(ds, tmp_path, "fits", scenario)
    before = target.read_bytes()
    monkeypatch.setattr(xr.Dataset, "to_netcdf", _fail(code))
    with pytest.raises(WriteError) as caught:
        write_dataset(ds, tmp_path, "fits", scenario)
    text = str(caught.value)
    assert str(target) in text and os.strerror(code) in text and "free there" in text
    assert f"the previous {target} is kept unchanged" in text
    assert target.read_bytes() == before and sorted(p.name for p in tmp_path.iterdir()) == ["fits.nc"]


def test_netcdf_hdf_error_on_a_full_disk_is_a_write_error(tmp_path, monkeypatch) -> None:
    def hdf_error(*args, **kwargs):
        raise RuntimeError("NetCDF: HDF error")

    monkeypatch.setattr(xr.Dataset, "to_netcdf", hdf_error)
    with pytest.raises(WriteError, match=r"cannot write .*cube\.nc: NetCDF: HDF error .*; nothing was written there"):
        write_dataset(xr.Dataset(), tmp_path, "cube", load_scenario("paper"))
    assert not stage_path(tmp_path, "cube").exists() and not list(tmp_path.iterdir())


def test_a_figure_that_cannot_be_written_keeps_the_previous_one(tmp_path, monkeypatch) -> None:
    path = tmp_path / "fig1.png"
    path.write_bytes(b"previous")
    fig = plt.figure()
    monkeypatch.setattr(fig, "savefig", _fail(errno.ENOSPC))
    with pytest.raises(WriteError, match=f"cannot write {path}: No space left on device"):
        style.save(fig, path)
    assert path.read_bytes() == b"previous" and not plt.fignum_exists(fig.number)


def test_a_read_only_figures_folder_is_refused_before_any_figure(tmp_path, monkeypatch) -> None:
    (tmp_path / "figures").mkdir()
    monkeypatch.setattr(tempfile, "TemporaryFile", _fail(errno.EROFS))
    with pytest.raises(WriteError, match="figures: Read-only file system.*no figure was drawn; those already "
                                         "there are kept"):
        write_figures(load_scenario("paper"), tmp_path)


def test_predict_output_on_a_full_disk_is_one_line(tmp_path, monkeypatch, capsys) -> None:
    target = tmp_path / "out.csv"
    target.write_text("previous\n")
    monkeypatch.setattr(tempfile, "mkstemp", _fail(errno.ENOSPC))
    rc = main(["predict", "--force", "100", "--xi", "0.5", "--lambda", "5", "--data-dir", str(tmp_path / "d"),
               "--output", str(target)])
    err = capsys.readouterr().err
    assert rc == 1, err
    [line] = [line for line in err.splitlines() if line.startswith("g2tom: error:")]
    assert line.startswith(f"g2tom: error: cannot write {target}: No space left on device (")
    assert line.endswith(f"; the previous {target} is kept unchanged")
    assert "Traceback" not in err and target.read_text() == "previous\n"


def test_ctrl_c_waits_until_the_write_is_done(tmp_path) -> None:
    """SIGINT raised in this (the main) thread while the write runs: held, then raised after it.

    Python's own handler is put in place for the test: a suite started in the background by a
    non-interactive shell inherits SIGINT ignored (POSIX), and Python keeps it so."""
    found = signal.signal(signal.SIGINT, signal.default_int_handler)
    term = signal.getsignal(signal.SIGTERM)
    target = tmp_path / "a.txt"
    try:
        with pytest.raises(KeyboardInterrupt):
            with atomic_path(target) as tmp:
                signal.raise_signal(signal.SIGINT)
                tmp.write_text("whole")  # still reached: the signal is held
        assert target.read_text() == "whole" and signal.getsignal(signal.SIGINT) is signal.default_int_handler
    finally:
        signal.signal(signal.SIGINT, found)
    with signals_deferred():
        pass
    assert signal.getsignal(signal.SIGTERM) == term


def test_numba_cache_goes_where_it_can_be_written(tmp_path) -> None:
    home = tmp_path / "home"
    home.write_text("")  # a HOME under which nothing can be made
    installed = home / "physics"  # a read-only installation: nothing can be written beside the sources
    fallback = str(Path(tempfile.gettempdir()) / f"g2tom-numba-{os.getuid()}")
    assert numba_cache_dir({"HOME": str(home)}, installed) == fallback
    assert numba_cache_dir({"HOME": str(home), "XDG_CACHE_HOME": str(tmp_path / "xdg")}, installed) == str(
        tmp_path / "xdg" / "g2tom" / "numba")
    assert numba_cache_dir({"HOME": str(home), "NUMBA_CACHE_DIR": "/chosen"}, installed) is None  # the user's
    assert numba_cache_dir({"HOME": str(home)}, tmp_path) is None  # numba's own, beside the sources


@pytest.mark.parametrize("value", ["0", "-2", "two"])
def test_an_invalid_numba_thread_count_is_one_line(value) -> None:
    env = {**os.environ, "NUMBA_NUM_THREADS": value}
    done = subprocess.run([sys.executable, "-m", "g2tom.cli.main", "params"], capture_output=True, text=True,
                          env=env, timeout=60)
    assert done.returncode == 2 and done.stderr.count("\n") == 1, done.stderr
    assert done.stderr.startswith(f"g2tom: error: NUMBA_NUM_THREADS = {value!r} is not allowed: must be a whole "
                                  "number >= 1")
