"""predict in the user's terms (issue 59): refusals name every group and the inputs that set it,
forces outside the atlas in newtons with the rest answered, and two bands with one meaning each."""

from __future__ import annotations

import csv
import io

import numpy as np
import pytest

import g2tom
from g2tom.cli.main import main
from g2tom.config import ConfigError
from g2tom.predict.atlas import shipped_path
from g2tom.predict.queries import PartlyAnsweredWarning

pytestmark = pytest.mark.skipif(shipped_path() is None, reason="this installation ships no atlas surrogate")

GOLD = ["--set", "indenter.radius=1e-3", "--set", "roughness.sigma=3e-7", "--set", "material.E=8e10"]
#: The gold contact with eta raised into the atlas's (mu, Pi).
INSIDE = {"indenter.radius": 1e-3, "roughness.sigma": 3e-7, "material.E": 8e10, "roughness.eta": 3e10}
QUERY = ["--force", "0.5,1,2,5", "--xi", "0.3", "--lambda", "5"]


def test_the_trial_refusal_names_every_group_and_the_inputs(tmp_path, capsys) -> None:
    assert main(["predict", *GOLD, *QUERY, "--data-dir", str(tmp_path)]) == 2
    err = capsys.readouterr().err
    assert "mu = 0.0391918 lies outside" in err and "Pi = 0.06 lies outside" in err and "F' = 43.78" in err
    assert "raise roughness.eta (2e+08 m^-2 now), roughness.sigma (3e-07 m now), indenter.radius" in err
    assert "g2tom run --config paper --set indenter.radius=1e-3" in err and "planned at" in err
    with pytest.raises(ConfigError, match=r"mu = .* raise roughness\.eta.*; Pi = .* raise roughness\.eta"):
        g2tom.predict_resistance("paper", force=1.0, xi=0.3, lam=5.0, data_dir=tmp_path,
                                 overrides={k: v for k, v in INSIDE.items() if k != "roughness.eta"})


def test_force_beyond_the_atlas_in_newtons_the_rest_answered(tmp_path, capsys) -> None:
    sets = [a for k, v in INSIDE.items() for a in ("--set", f"{k}={v}")]
    assert main(["predict", *sets, *QUERY, "--data-dir", str(tmp_path)]) == 0
    out = capsys.readouterr()
    assert "3 of 4 queries answered" in out.err and "answered from 0.0056 N to 2.33 N for this surface" in out.err
    rows = list(csv.DictReader(io.StringIO(out.out)))
    assert [r["outside_domain"] for r in rows[:3]] == ["", "", ""]
    assert rows[3]["outside_domain"] == "F' = 43.78 above 20.4 (F above 2.33 N)"
    assert rows[3]["resistance_ohm"] == "nan" and all(float(r["resistance_ohm"]) > 0 for r in rows[:3])
    with pytest.warns(PartlyAnsweredWarning):
        ds = g2tom.predict_resistance("paper", force=[1.0, 5.0], xi=0.3, lam=5.0, data_dir=tmp_path, overrides=INSIDE)
    assert np.isfinite(ds["resistance"][0]) and np.isnan(ds["resistance"][1]) and ds["outside_domain"][1] != ""


def test_both_bands_in_ohm_with_their_meaning_and_the_spread_unknown(tmp_path, capsys) -> None:
    ds = g2tom.predict_resistance("paper", force=[0.5, 1.0], xi=0.3, lam=5.0, data_dir=tmp_path, overrides=INSIDE)
    for name, words in (("resistance_mean_lower", "95 % interval of the predicted mean R"),
                        ("resistance_mean_upper", "95 % interval of the predicted mean R"),
                        ("resistance_spread_p16", "16 % of R over realizations"),
                        ("resistance_spread_p84", "84 % of R over realizations")):
        assert ds[name].attrs["units"] == "ohm" and words in ds[name].attrs["long_name"], name
    assert (ds["resistance_mean_lower"] < ds["resistance"]).all() and (ds["resistance"] < ds["resistance_mean_upper"]).all()
    assert np.isnan(ds["resistance_spread_p16"]).all() and "not known to the atlas surrogate" in ds.attrs["spread"]
    sets = [a for k, v in INSIDE.items() for a in ("--set", f"{k}={v}")]
    assert main(["predict", *sets, "--force", "1", "--xi", "0.3", "--lambda", "5", "--data-dir", str(tmp_path)]) == 0
    header = capsys.readouterr().out.splitlines()[0].split(",")
    assert {"resistance_mean_lower_ohm", "resistance_mean_upper_ohm", "resistance_spread_p16_ohm",
            "resistance_spread_p84_ohm"} <= set(header)
    assert not {"lower_ohm", "upper_ohm", "total_lower", "total_upper"} & set(header)
    assert main(["predict", *sets, "--force", "1", "--xi", "0.3", "--lambda", "5", "--data-dir", str(tmp_path),
                 "--json"]) == 0
    assert "spread over contacts: not known to the atlas surrogate" in capsys.readouterr().out
