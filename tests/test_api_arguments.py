"""Arguments at the edges: ``g2tom.predict_resistance``'s checked at its entry, each refusal naming the
argument and its value; ``model`` honoured by the surrogate that can and refused by the one that cannot
(the atlas); extreme but allowed-looking counts given a range; refusals that name what is refused;
a benchmark that cannot run saying so; a scheduler address where no dask scheduler answers."""

from __future__ import annotations

import pytest

import g2tom
from g2tom.cli.main import main
from g2tom.config import ConfigError

#: A query the shipped atlas answers (the paper's surface).
QUERY = {"force": 100.0, "xi": 0.5, "lam": 5.0}


@pytest.mark.parametrize("change, named", [
    ({"model": "bogus"}, "model = 'bogus' is not allowed: must be one of 'curve', 'power_law'"),
    ({"force": "5N"}, "force = '5N' is not allowed: must be a number (N, > 0)"),
    ({"xi": [0.5, "a lot"]}, "xi = [0.5, 'a lot'] is not allowed: must be a number (in (0, 1))"),
    ({"data_dir": None}, "data_dir = None is not allowed: must be a folder"),
    ({"pixel_size": "1e-6"}, "pixel_size = '1e-6' is not allowed: must be None or a number > 0 (m)"),
    ({"surrogate": 3}, "surrogate = 3 is not allowed"),
    ({"extrapolate": "no"}, "extrapolate = 'no' is not allowed: must be True or False"),
    ({"overrides": ["roughness.sigma=1e-6"]}, "overrides = ['roughness.sigma=1e-6'] is not allowed"),
])
def test_a_wrong_argument_is_refused_by_name(tmp_path, change, named) -> None:
    given = {**QUERY, "data_dir": tmp_path, **change}
    with pytest.raises(ConfigError) as caught:
        g2tom.predict_resistance("paper", **given)
    assert str(caught.value).startswith(named)


def test_a_surface_of_the_wrong_kind_is_refused_by_name(tmp_path) -> None:
    with pytest.raises(ConfigError, match=r"^surface = 42 is not allowed: must be a Scenario, a bundled scenario's "
                                          r"name \(.*paper.*\), a TOML file or a height map file"):
        g2tom.predict_resistance(42, **QUERY, data_dir=tmp_path)


def test_the_atlas_refuses_the_power_law_it_cannot_answer(tmp_path, capsys) -> None:
    assert g2tom.predict_resistance("paper", **QUERY, data_dir=tmp_path).attrs["model"] == "curve"
    with pytest.raises(ConfigError, match="model = 'power_law' cannot be answered by the atlas surrogate"):
        g2tom.predict_resistance("paper", **QUERY, data_dir=tmp_path, model="power_law")
    rc = main(["predict", "--force", "100", "--xi", "0.5", "--lambda", "5", "--model", "power_law",
               "--data-dir", str(tmp_path)])
    err = capsys.readouterr().err
    assert rc == 2 and err.count("\n") == 1 and err.startswith(
        "g2tom: error: model = 'power_law' cannot be answered by the atlas surrogate"), err


@pytest.mark.parametrize("argv, refusal", [
    (["--standard-error", "1e-300"], "--standard-error = 1e-300 is out of range: must be in [0.0001, 0.5]"),
    (["--max-realizations", "100000000"], "--max-realizations = 100000000 is out of range: must be 2 .. 10000"),
    (["--loads", "1000000"], "--loads = 1000000 is out of range: must be 2 .. 100"),
    (["--realizations", "100000"], "--realizations = 100000 is out of range: must be 2 .. 1000"),
])
def test_extreme_validate_counts_are_refused_with_their_range(tmp_path, capsys, argv, refusal) -> None:
    assert main(["validate", "--plan", "--data-dir", str(tmp_path), *argv]) == 2
    err = capsys.readouterr().err
    assert err.startswith(f"g2tom: error: {refusal}") and err.count("\n") == 1, err


def test_a_refused_validated_scenario_is_named(tmp_path, capsys) -> None:
    assert main(["validate", "--plan", "--config", "published", "--data-dir", str(tmp_path)]) == 2
    err = capsys.readouterr().err
    assert err.startswith("g2tom: error: --config 'published' (the scenario part 2 validates) cannot run on the "
                          "validation scene: contact.window") and err.count("\n") == 1, err


def test_a_benchmark_that_cannot_run_says_it_skipped(tmp_path, capsys) -> None:
    from g2tom.reference.devices import gpu_missing

    if gpu_missing() is None:
        pytest.skip("CuPy sees a GPU here")
    assert main(["bench", "--only", "gpu", "--data-dir", str(tmp_path)]) == 0
    out = capsys.readouterr().out
    assert out.startswith("bench gpu: skipped (no GPU: ") and "figures" not in out, out


def test_a_scheduler_address_where_http_answers_is_refused_quickly() -> None:
    import socket
    import subprocess
    import sys
    import time

    from g2tom.before_work.preflight import check_scheduler

    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        port = s.getsockname()[1]
    http = subprocess.Popen([sys.executable, "-m", "http.server", str(port), "--bind", "127.0.0.1"],
                            stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    try:
        for _ in range(100):  # until it listens
            with socket.socket() as probe:
                if probe.connect_ex(("127.0.0.1", port)) == 0:
                    break
            time.sleep(0.05)
        start = time.perf_counter()
        with pytest.raises(ConfigError, match=f"--scheduler 'tcp://127.0.0.1:{port}': no dask scheduler reachable "
                                              r"at .* \(something accepts connections there but"):
            check_scheduler(f"tcp://127.0.0.1:{port}")
        assert time.perf_counter() - start < 10
    finally:
        http.kill()
        http.wait()


def test_help_texts_describe_what_users_have(tmp_path, capsys) -> None:
    import re

    from g2tom.cli.arguments import build_parser

    parser = build_parser()
    top = parser.format_help()
    assert "stamp" not in top and "with the surrogate (Eq. 27)" not in top
    assert re.search(r"predict\s+predict R_el .* each cell's ln R'\(ln F'\) curve", top, re.S)
    texts = [top, *(p.format_help() for p in parser._subparsers._group_actions[0].choices.values())]
    assert main(["params", "--data-dir", str(tmp_path)]) == 0
    texts.append(capsys.readouterr().out)
    for text in texts:
        assert not re.search(r"design note|issue \d|session|shared/", text, re.I), text
    assert main(["stamp", "--data-dir", str(tmp_path)]) == 0  # make's own command still runs
    assert (tmp_path / ".stamps" / "cube.json").is_file()
