"""The memory probe works without os.sysconf, as on Windows (issue 32)."""

from __future__ import annotations

import os

import psutil

from g2tom.before_work.plan import available_memory
from g2tom.before_work.resources import check_resources
from g2tom.before_work import load_scenario


def test_memory_probe_without_sysconf(monkeypatch) -> None:
    monkeypatch.delattr(os, "sysconf", raising=False)
    total = psutil.virtual_memory().total
    have = available_memory()
    assert 0 < have <= total
    scenario = load_scenario("paper_gt")  # validation checks the ensemble against physical memory
    assert check_resources(scenario)  # the plan's estimates against the available memory
