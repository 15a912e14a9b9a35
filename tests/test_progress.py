"""The progress line: its time-left text, when it draws, and that it never changes a result."""

from __future__ import annotations

import io
import re

import dask
import dask.array as da
import numpy as np
import pytest

from g2tom import compute as compute_module
from g2tom import progress
from g2tom.compute import ComputeOptions, compute
from g2tom.progress import DaskProgress, ProgressLine, describe, format_duration

PERCENT = re.compile(r"\]\s+(\d+) %")


class Terminal(io.StringIO):
    """A captured stream that says it is a terminal."""

    def isatty(self) -> bool:
        return True


class Clock:
    """A clock the test moves by hand (s)."""

    def __init__(self) -> None:
        self.now = 100.0

    def __call__(self) -> float:
        return self.now


def _frames(text: str) -> list[str]:
    """The successive drawings of the line (each starts with a carriage return)."""
    return [frame.rstrip(" \n") for frame in text.split("\r")[1:]]


# ------------------------------------------------------------------ the text
@pytest.mark.parametrize(
    ("seconds", "text"),
    [(0.0, "0 s"), (-3.0, "0 s"), (12.4, "12 s"), (59.6, "1 min 00 s"), (125.0, "2 min 05 s"),
     (3599.4, "59 min 59 s"), (3599.6, "1 h 00 min"), (5400.0, "1 h 30 min"), (90_000.0, "25 h 00 min")],
)
def test_durations_read_as_seconds_minutes_or_hours(seconds: float, text: str) -> None:
    assert format_duration(seconds) == text


def test_half_done_after_10_s_leaves_about_10_s() -> None:
    assert describe(0.5, 10.0) == "[##########          ]  50 %  10 s elapsed, ~10 s left"


def test_time_left_is_elapsed_times_the_remaining_fraction_over_the_done_one() -> None:
    assert describe(0.45, 12.0).endswith("45 %  12 s elapsed, ~15 s left")  # 12 x 0.55 / 0.45 = 14.7
    assert describe(0.25, 1800.0).endswith("30 min 00 s elapsed, ~1 h 30 min left")
    assert describe(0.001, 60.0).endswith("1 min 00 s elapsed, ~16 h 39 min left")  # 59,940 s


def test_nothing_done_or_too_few_tasks_is_estimating() -> None:
    assert describe(0.0, 5.0) == f"[{' ' * 20}]   0 %  5 s elapsed, estimating"
    assert describe(0.5, 10.0, settled=False).endswith("50 %  10 s elapsed, estimating")


def test_all_done_says_done_with_a_full_bar() -> None:
    assert describe(1.0, 42.0) == f"[{'#' * 20}] 100 %  42 s elapsed, done"
    assert describe(0.999, 42.0).startswith(f"[{'#' * 19} ]  99 %")  # 100 % only when all is done


def test_fraction_and_time_are_clamped() -> None:
    assert describe(1.7, 10.0) == describe(1.0, 10.0)
    assert describe(-0.2, 10.0) == describe(0.0, 10.0)
    assert describe(float("nan"), 10.0) == describe(0.0, 10.0)
    assert describe(0.5, -1.0) == describe(0.5, 0.0)


# ------------------------------------------------------------------ when the line draws
def test_line_appears_only_after_the_delay_and_redraws_at_most_every_half_second() -> None:
    out, clock = io.StringIO(), Clock()
    line = ProgressLine("job", stream=out, after=3.0, force=True, clock=clock)
    line.start(10)
    for done, t in [(1, 101.0), (2, 102.9)]:
        clock.now = t
        line.update(done)
    assert out.getvalue() == ""  # a short run stays silent
    clock.now = 103.0
    line.update(3)
    clock.now = 103.2
    line.update(4)  # too soon after the last drawing
    clock.now = 103.6
    line.update(5)
    clock.now = 104.0
    line.finish()
    assert _frames(out.getvalue()) == [
        f"job  {describe(0.3, 3.0)}",
        f"job  {describe(0.5, 3.6)}",
        f"job  {describe(1.0, 4.0)}",
    ]
    assert out.getvalue().endswith("\n") and out.getvalue().count("\n") == 1


def test_first_tasks_are_estimating_and_a_shorter_line_blanks_the_longer_one() -> None:
    out, clock = io.StringIO(), Clock()
    line = ProgressLine("job", stream=out, force=True, clock=clock)
    line.start(10)
    clock.now += 1.0
    line.update(2)
    clock.now += 1.0
    line.update(3)
    first, second = out.getvalue().split("\r")[1:]
    assert progress.SETTLE_TASKS == 3 and first.endswith("estimating")
    assert second.rstrip().endswith("2 s elapsed, ~5 s left")  # 2 s x 7 / 3
    assert len(second) == len(first)  # trailing blanks cover the end of "estimating"


def test_a_short_run_prints_nothing_even_at_the_end() -> None:
    out, clock = io.StringIO(), Clock()
    line = ProgressLine("job", stream=out, after=3.0, force=True, clock=clock)
    line.start(2)
    clock.now += 2.0
    line.update(2)
    line.finish()
    assert out.getvalue() == ""


def test_a_long_run_whose_tasks_all_ended_early_still_gets_its_final_line() -> None:
    out, clock = io.StringIO(), Clock()
    line = ProgressLine("job", stream=out, after=3.0, force=True, clock=clock)
    line.start(1)
    clock.now += 5.0
    line.finish()
    assert _frames(out.getvalue()) == [f"job  {describe(1.0, 5.0)}"]


def test_a_failed_run_keeps_its_last_fraction_and_ends_the_line() -> None:
    out, clock = io.StringIO(), Clock()
    line = ProgressLine("job", stream=out, force=True, clock=clock)
    line.start(4)
    clock.now += 1.0
    line.update(1)
    line.finish(failed=True)
    assert _frames(out.getvalue())[-1] == f"job  {describe(0.25, 1.0, settled=False)}"
    assert out.getvalue().endswith("\n")


def test_not_a_terminal_gets_nothing() -> None:
    out = io.StringIO()
    line = ProgressLine("job", stream=out)
    assert not line.enabled
    with DaskProgress(line):
        assert dask.compute(da.arange(40, chunks=4).sum(), scheduler="sync") == (780,)
    assert out.getvalue() == ""


# ------------------------------------------------------------------ on dask graphs
class CountingLine(ProgressLine):
    """A progress line that also records every count it is given."""

    def __init__(self, *args, **kwargs) -> None:
        super().__init__(*args, **kwargs)
        self.counts: list[int] = []
        self.total = 0

    def start(self, total: int) -> None:
        super().start(total)
        self.total = total

    def update(self, done: int) -> None:
        super().update(done)
        self.counts.append(done)


@pytest.mark.parametrize("scheduler", ["sync", "threads"])
def test_callback_counts_every_task_and_ends_at_100_percent(monkeypatch, scheduler: str) -> None:
    monkeypatch.setattr(progress, "REDRAW", 0.0)
    out = io.StringIO()
    line = CountingLine("sum", stream=out, force=True)
    x = da.arange(60, chunks=5)
    with DaskProgress(line):
        (total,) = dask.compute((x**2).sum(), scheduler=scheduler)
    assert total == sum(i * i for i in range(60))
    assert line.total > 12 and line.counts == list(range(1, line.total + 1))
    percents = [int(m.group(1)) for m in map(PERCENT.search, _frames(out.getvalue()))]
    assert len(percents) == line.total + 1  # every task, then the final line
    assert percents == sorted(percents) and percents[-2:] == [100, 100]
    assert out.getvalue().endswith("\n") and out.getvalue().count("\n") == 1


def test_compute_draws_the_callers_label_on_a_terminal_with_the_same_result(monkeypatch) -> None:
    x = da.random.default_rng(7).standard_normal((300, 300), chunks=(50, 50))
    y = (x @ x.T).sum(axis=0)
    (quiet,) = compute(y, options=ComputeOptions(progress=False))
    monkeypatch.setattr(compute_module, "PROGRESS_AFTER", 0.0)
    monkeypatch.setattr(progress, "REDRAW", 0.0)
    terminal = Terminal()
    monkeypatch.setattr("sys.stderr", terminal)
    (shown,) = compute(y, options=ComputeOptions(progress=True), label="cube round 2 (test)")
    np.testing.assert_array_equal(shown, quiet)
    frames = _frames(terminal.getvalue())
    assert len(frames) > 2 and all(f.startswith("cube round 2 (test)  [") for f in frames)
    assert PERCENT.search(frames[-1]).group(1) == "100" and frames[-1].endswith("elapsed, done")
    assert terminal.getvalue().endswith("\n")


def test_no_progress_option_draws_nothing_even_on_a_terminal(monkeypatch) -> None:
    monkeypatch.setattr(compute_module, "PROGRESS_AFTER", 0.0)
    terminal = Terminal()
    monkeypatch.setattr("sys.stderr", terminal)
    assert compute(da.ones(10, chunks=2).sum(), options=ComputeOptions(progress=False)) == (10.0,)
    assert terminal.getvalue() == ""


def test_distributed_futures_draw_the_same_line_with_the_same_result(monkeypatch) -> None:
    distributed = pytest.importorskip("distributed")
    x = da.random.default_rng(8).standard_normal((200, 200), chunks=(50, 50))
    y = np.exp(x).cumsum(axis=1)
    (quiet,) = compute(y, options=ComputeOptions(progress=False))
    monkeypatch.setattr(compute_module, "PROGRESS_AFTER", 0.0)
    monkeypatch.setattr(progress, "REDRAW", 0.0)
    with distributed.LocalCluster(n_workers=1, threads_per_worker=2, processes=False,
                                  dashboard_address=None) as cluster:
        options = ComputeOptions(scheduler=cluster.scheduler_address, progress=True)
        terminal = Terminal()
        monkeypatch.setattr("sys.stderr", terminal)
        (shown,) = compute(y, options=options, label="remote")
        monkeypatch.undo()
        (remote_quiet,) = compute(y, options=ComputeOptions(scheduler=cluster.scheduler_address, progress=False))
    np.testing.assert_array_equal(shown, quiet)
    np.testing.assert_array_equal(remote_quiet, quiet)
    percents = [int(m.group(1)) for m in map(PERCENT.search, _frames(terminal.getvalue()))]
    # one count per output chunk (16), not one per collection
    assert len(percents) == 17 and percents == sorted(percents) and percents[-1] == 100
    assert all(f.startswith("remote  [") for f in _frames(terminal.getvalue()))
    assert terminal.getvalue().endswith("\n")


# ------------------------------------------------------------------ the cube's rounds
def test_cube_labels_each_round_with_the_cells_still_open(monkeypatch, small) -> None:
    from g2tom.stages import contact as contact_stage
    from g2tom.stages import cube, cube_rounds
    from g2tom.stages import oxide as oxide_stage
    from tests.test_ensemble import _adaptive

    scenario = _adaptive(small)
    contact, oxide = contact_stage.build(scenario), oxide_stage.build(scenario)
    labels: list[str] = []

    def spy(*collections, options, label):
        labels.append(label)
        return compute(*collections, options=options, label=label)

    monkeypatch.setattr(cube_rounds, "compute", spy)
    counts = cube.build(scenario, contact, oxide, ComputeOptions(progress=False))["n_realizations"].values
    ox, cells = scenario.oxide, counts.size
    assert labels[0] == f"cube round 1 ({cells} cells, {ox.min_realizations} realizations each)"
    assert len(labels) > 2  # the scenario really needs several rounds
    for r, label in enumerate(labels[1:], start=2):
        still_open = int(np.sum(counts > ox.min_realizations + (r - 2) * scenario.compute.oxide_batch))
        assert label == f"cube round {r} (adaptive: {still_open} of {cells} cells still open)"
