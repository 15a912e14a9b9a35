"""Sampling noise of the atlas's ensembles, drawn: the parametric bootstrap behind the held-out
verdict's noise ceiling (:func:`g2tom.atlas.fit.noise_ceiling`).

Every scene draws its own random streams (:func:`g2tom.atlas.design.scene_seed`), so the error of
one scene's ensemble is independent of another's; within a scene, the same fields serve every load
step, so the error of ln R' is correlated along the load: measured on held-out scene h02 (its first
100 fields against 3,000), 0.86 between neighbouring steps of 20, 0.65 five steps apart, 0.3 ten
apart. :func:`sampling_noise` draws the two ends of that range.
"""

from __future__ import annotations

import numpy as np

__all__ = ["sampling_noise"]


def sampling_noise(rng: np.random.Generator, sigma: np.ndarray, scene: np.ndarray, along_load: bool) -> np.ndarray:
    """One draw of the ensembles' error of ln R' at every point.

    Parameters
    ----------
    rng
        The random stream.
    sigma
        (n, ...) one standard deviation of ln R' at each point (a scene's load step) and node; 0 or
        not finite: no noise (the clean curve, an open circuit).
    scene
        (n,) the scene of each point.
    along_load
        False: independent from step to step; True: one draw per scene and node, fully correlated
        along the load.

    Returns
    -------
    numpy.ndarray
        Normal errors of the shape of ``sigma``, independent between scenes and nodes.
    """
    sigma = np.where(np.isfinite(sigma), sigma, 0.0)
    if along_load:
        labels, inverse = np.unique(scene, return_inverse=True)
        z = rng.standard_normal((labels.size,) + sigma.shape[1:])[inverse.ravel()]
    else:
        z = rng.standard_normal(sigma.shape)
    return z * sigma
