"""One surface, no run

The resistance of a rough, partly oxidized contact from the surrogate shipped with the package.

``g2tom.predict_resistance`` answers from the atlas surrogate that ships with the package when no
run of one's own covers the surface. Here: the default scenario's sphere and material with a
rougher surface (sigma = 15 um), at five forces, for 30 % oxide with patches 5 asperity spacings
long. The figure shows R_el with its band against the force.
"""

from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt
import numpy as np

import g2tom

force = np.geomspace(100.0, 2000.0, 5)  # N
answer = g2tom.predict_resistance("paper", force=force, xi=0.3, lam=5.0,
                                  overrides={"roughness.sigma": 15e-6})
package = str(Path(g2tom.__file__).parent)  # the install's folder, shortened in the print-out
print("answered by:", answer.attrs["answered_by"].replace(package, "<g2tom>"))
print(f"{'F (N)':>8}  {'R_el (mOhm)':>11}  {'95 % of the mean (mOhm)':>17}")
for f, r, lo, hi in zip(force, answer["resistance"].values, answer["resistance_mean_lower"].values,
                        answer["resistance_mean_upper"].values):
    print(f"{f:8.0f}  {1e3 * r:11.3f}  [{1e3 * lo:6.3f}, {1e3 * hi:6.3f}]")

fig, ax = plt.subplots(figsize=(5, 3.4), layout="constrained")
ax.fill_between(force, 1e3 * answer["resistance_mean_lower"], 1e3 * answer["resistance_mean_upper"], alpha=0.3,
                label="95 % of the mean")
ax.loglog(force, 1e3 * answer["resistance"], "o-", label="R_el")
ax.set(xlabel="force F (N)", ylabel="R_el (mOhm)", title="xi = 0.3, lambda = 5, sigma = 15 um")
ax.legend()
fig.savefig("resistance.png", dpi=110)
