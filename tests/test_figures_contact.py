"""Contact figures: raster spot maps, Hertz references for the sphere only."""

from __future__ import annotations

import matplotlib.figure
import numpy as np
import pytest

from g2tom.analysis import figures_contact
from g2tom import store
from g2tom.before_work import load_scenario
from g2tom.before_work.domains import resolve
from g2tom.stages import contact

FAST = {"loading.n_delta": 6, "contact.n_radial": 160}


@pytest.mark.parametrize("shape", ["sphere", "cone"])
def test_spot_maps_are_rasters_and_hertz_is_drawn_for_the_sphere_only(tmp_path, monkeypatch, shape):
    overrides = {**FAST, "indenter.shape": shape, "indenter.cone_angle": 0.1}
    scenario = resolve(load_scenario("paper_gt", overrides))
    store.write_dataset(contact.build(scenario), tmp_path, "contact", scenario)
    figures: list[matplotlib.figure.Figure] = []
    real = matplotlib.figure.Figure.savefig
    monkeypatch.setattr(matplotlib.figure.Figure, "savefig",
                        lambda self, *a, **k: (figures.append(self), real(self, *a, **k))[1])
    paths = figures_contact.write(scenario, tmp_path, tmp_path / "figures")
    assert [p.name for p in paths] == ["fig4_contact.png", "fig5_spots.png"]
    fig4, fig5 = figures
    labels = {t.get_label() for ax in fig4.axes for t in ax.get_lines()}
    assert any("Hertz" in label for label in labels) == (shape == "sphere")
    assert ("sphere only" in fig4._suptitle.get_text()) == (shape != "sphere")
    spot_axes = [ax for ax in fig5.axes if ax.get_images()]
    assert len(spot_axes) == 4
    for ax in spot_axes:
        assert not ax.collections  # no per-spot patches
        image = ax.get_images()[0].get_array()
        assert image.shape == (scenario.n_cells, scenario.n_cells)
        assert np.nanmax(image) > 0
