"""Every answer says whether the caps yield: the plasticity index in plan, the contact stage and its
file, one warning where caps that yield are held elastic, and refusals where a model or a surrogate
cannot answer capped caps."""

from __future__ import annotations

import warnings

import numpy as np
import pytest

from g2tom import predict_resistance
from g2tom.before_work import load_scenario
from g2tom.cli.main import main
from g2tom.config import ConfigError
from g2tom.predict.queries import OutsideDomainError
from g2tom.scene import scene_plasticity


def test_plan_prints_psi_and_first_yield_of_capped_caps(capsys) -> None:
    assert main(["plan", "--set", "material.hardness=2e9"]) == 0
    out = capsys.readouterr().out
    # the paper's steel: E* = 2.1e11 / (2 (1 - 0.09)) = 115.4 GPa, sigma 20 um, beta 30 um
    assert "caps: capped at H = 2 GPa (perfectly plastic surface); plasticity index psi = 47.1" in out
    assert "first yield at omega_c = 22.2 nm = 0.00111 sigma" in out
    assert "capped caps: the times below are the elastic caps' cost models" in out


def test_plan_of_an_elastic_scene_says_its_index_is_unknown(capsys) -> None:
    assert main(["plan"]) == 0
    out = capsys.readouterr().out
    assert "caps: elastic (Hertz); plasticity index unknown" in out and "capped caps:" not in out


def test_caps_that_yield_held_elastic_warn_once_naming_the_hardness() -> None:
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        s = load_scenario("paper", {"material.bodies": ["hard_gold"], "material.hardness": "none",
                                    "roughness.sigma": 0.2e-6, "roughness.beta": 10e-6, "roughness.eta": 2e10})
    texts = [str(w.message) for w in caught if "plasticity index" in str(w.message)]
    assert len(texts) == 1
    assert texts[0].startswith("plasticity index psi = 4.52 > 0.6: most touching asperities yield")
    assert "set material.hardness" in texts[0]
    assert scene_plasticity(s).hardness is None and scene_plasticity(s).index == pytest.approx(4.52, abs=0.005)


def test_capped_caps_do_not_warn() -> None:
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        load_scenario("gold_connector")
    assert not [w for w in caught if "plasticity index" in str(w.message)]


def test_greenwood_tripp_refuses_a_hardness() -> None:
    with pytest.raises(ConfigError, match=r"material.hardness = 2e\+09 Pa needs contact.model = 'discrete': "
                                          r"greenwood_tripp's caps are elastic only"):
        load_scenario("paper_gt", {"material.hardness": 2e9})


def test_the_atlas_refuses_capped_caps_in_one_line() -> None:
    with pytest.raises(OutsideDomainError, match=r"material.hardness = 1.5e\+09 Pa \(plasticity index psi = 4.52\) is "
                                                 r"outside what the surrogate answers: the atlas surrogate covers elastic caps only"):
        predict_resistance("gold_connector", force=1.0, xi=0.3, lam=5)


def test_predict_command_refuses_capped_caps_with_exit_2_and_the_run_that_answers(capsys, tmp_path) -> None:
    assert main(["predict", "--config", "gold_connector", "--force", "1", "--xi", "0.3", "--lambda", "5",
                 "--data-dir", str(tmp_path)]) == 2
    err = capsys.readouterr().err
    assert "the atlas surrogate covers elastic caps only" in err and "g2tom run --config gold_connector" in err
    assert "Traceback" not in err


def test_a_hardness_no_cap_reaches_warns_that_the_answer_is_elastic() -> None:
    from g2tom.models.discrete_pool import _warn_no_yield
    from g2tom.physics.cap_law import CappedCap, HertzCap

    cap = CappedCap(1.154e11, 3e-5, 2e9)
    below = [{"radius": np.full((3, 4), 0.9 * cap.a_c)}]
    with pytest.warns(UserWarning, match=r"material.hardness = 2e\+09 Pa: no cap of the pool reaches first yield"):
        _warn_no_yield(cap, below)
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        _warn_no_yield(cap, [{"radius": np.full((3, 4), 1.1 * cap.a_c)}])
        _warn_no_yield(HertzCap(1.154e11, 3e-5), below)


def test_a_pool_solve_that_fails_is_one_line_and_exit_1(tmp_path, capsys, monkeypatch) -> None:
    """A discrete solve that does not converge (here made to fail) ends the contact stage with one line
    naming the surface, exit status 1, no traceback and no contact.nc."""
    from g2tom.physics import discrete_contact as dc

    def fails(*args, **kwargs):
        raise dc.NotConverged("force 1 N: relative residual 0.1 (stalled)")

    monkeypatch.setattr(dc, "solve_forces", fails)
    assert main(["contact", "--config", "gold_connector", "--data-dir", str(tmp_path), "--no-progress"]) == 1
    err = capsys.readouterr().err
    assert "g2tom: error: contact: the discrete solve of pool surface 0 did not converge (force 1 N" in err
    assert "Traceback" not in err and not (tmp_path / "contact.nc").exists()
