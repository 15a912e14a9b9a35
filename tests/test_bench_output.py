"""What `g2tom bench` prints: one line per benchmark naming its file, every figure with --verbose."""

from __future__ import annotations

import json
import re

from g2tom.before_work.domains import resolve
from g2tom.before_work import load_scenario
from tests.conftest import SMALL_OVERRIDES


def test_bench_prints_one_line_unless_verbose(tmp_path, capsys, monkeypatch):
    import g2tom.bench.predict as predict_bench
    from g2tom.bench import run_benchmarks

    scene = resolve(load_scenario("paper_gt", SMALL_OVERRIDES))
    paths = run_benchmarks(scene, tmp_path, only=["predict"])
    out = capsys.readouterr().out.strip().splitlines()
    assert len(out) == 1 and str(paths["predict"]) in out[0] and paths["predict"].is_file()
    figures = int(re.search(r"bench predict: (\d+) figures in ", out[0]).group(1))
    # --verbose prints the same result's figures: the measured one, not measured again (3.5 s)
    stored = json.loads(paths["predict"].read_text())
    own = {k: v for k, v in stored.items() if k not in ("benchmark", "scenario", "config_hash", "machine")}
    monkeypatch.setattr(predict_bench, "run", lambda scenario: own)
    run_benchmarks(scene, tmp_path, only=["predict"], verbose=True)
    verbose = capsys.readouterr().out.splitlines()
    assert verbose[0] == "== bench predict ==" and len(verbose) == 1 + figures > 3
