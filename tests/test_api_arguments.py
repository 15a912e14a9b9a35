"""``g2tom.predict_resistance``'s arguments checked at its entry, each refusal naming the argument and its
value; ``model`` honoured by the surrogate that can and refused by the one that cannot (the atlas)."""

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
