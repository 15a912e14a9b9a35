"""The atlas ensembles' sampling noise as the noise ceiling draws it: one sigma as given, independent
between scenes and nodes, along the load independent or fully correlated."""

from __future__ import annotations

import numpy as np
import pytest

from g2tom.fitting.atlas_noise import sampling_noise


def _points(steps: int = 20, scenes: int = 400) -> tuple[np.ndarray, np.ndarray]:
    scene = np.repeat(np.arange(scenes), steps)
    sigma = np.broadcast_to(np.array([[0.0, 0.02], [0.05, np.inf]]), (scene.size, 2, 2)).copy()
    return sigma, scene


@pytest.mark.parametrize("along_load", [False, True])
def test_the_noise_has_the_given_sigma_and_none_where_there_is_none(along_load: bool) -> None:
    sigma, scene = _points()
    noise = sampling_noise(np.random.default_rng(3), sigma, scene, along_load)
    assert noise.shape == sigma.shape
    assert np.all(noise[:, 0, 0] == 0.0) and np.all(noise[:, 1, 1] == 0.0)  # the clean node; an open circuit
    per_scene = noise[::20] if along_load else noise  # fully correlated: one draw per scene
    # 400 or 8,000 normal draws: the sample sigma within 10 % (four standard errors at 400)
    assert np.std(per_scene[:, 0, 1]) == pytest.approx(0.02, rel=0.1)
    assert np.std(per_scene[:, 1, 0]) == pytest.approx(0.05, rel=0.1)


def test_along_the_load_a_scene_errs_alike_and_scenes_independently() -> None:
    sigma, scene = _points()
    along = sampling_noise(np.random.default_rng(4), sigma, scene, True)[:, 1, 0].reshape(400, 20)
    assert np.all(along == along[:, :1])  # one error per scene and node
    steps = sampling_noise(np.random.default_rng(4), sigma, scene, False)[:, 1, 0].reshape(400, 20)
    # neighbouring steps uncorrelated, and so are neighbouring scenes: |r| < 4 / sqrt(n)
    assert abs(np.corrcoef(steps[:, 0], steps[:, 1])[0, 1]) < 4 / np.sqrt(400)
    assert abs(np.corrcoef(along[:-1, 0], along[1:, 0])[0, 1]) < 4 / np.sqrt(399)
