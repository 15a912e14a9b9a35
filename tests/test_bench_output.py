"""What `g2tom bench` prints: one line per benchmark naming its file, every figure with --verbose."""

from __future__ import annotations

from g2tom.before_work.domains import resolve
from g2tom.before_work import load_scenario
from tests.conftest import SMALL_OVERRIDES


def test_bench_prints_one_line_unless_verbose(tmp_path, capsys):
    from g2tom.bench import run_benchmarks

    scene = resolve(load_scenario("paper_gt", SMALL_OVERRIDES))
    paths = run_benchmarks(scene, tmp_path, only=["predict"])
    out = capsys.readouterr().out.strip().splitlines()
    assert len(out) == 1 and str(paths["predict"]) in out[0] and paths["predict"].is_file()
    run_benchmarks(scene, tmp_path, only=["predict"], verbose=True)
    assert len(capsys.readouterr().out.splitlines()) > 3
