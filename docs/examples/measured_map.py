"""A measured surface

A height map's roughness, then its resistance: from its summits, and from the map itself.

A profilometer's map is stood in for by a synthetic one: a 256 x 256 Gaussian random surface with
a self-affine spectrum (Hurst exponent 0.8) rolled off below 50 um, 1 um pixels, heights in m,
saved as ``.npy``. ``g2tom roughness`` reduces it to the summit parameters of the model (sigma,
eta, beta); ``g2tom.predict_resistance`` with the map as the surface answers its resistance,
as ``g2tom predict --roughness map.npy --pixel-size 1e-6`` would. ``g2tom.surface_resistance``
presses a 1 mm gold sphere on the map itself and solves the full field, as ``g2tom surface map.npy
--pixel-size 1e-6 --force 0.05,0.2 --set 'material.bodies=["hard_gold"]' --set indenter.radius=1e-3``
would.
"""

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt
import numpy as np

import g2tom
from g2tom.cli.main import main

# --- a synthetic height map: filtered white noise, rms 2 um -----------------------------------
n, pixel = 256, 1e-6  # pixels per side, pixel size in m
rng = np.random.default_rng(7)
q = np.hypot(*np.meshgrid(np.fft.fftfreq(n, pixel), np.fft.fftfreq(n, pixel)))
q_roll = 1 / 50e-6
spectrum = (np.fmax(q, q_roll) / q_roll) ** -(1 + 0.8)
spectrum[0, 0] = 0.0
heights = np.fft.ifft2(np.fft.fft2(rng.standard_normal((n, n))) * spectrum).real
heights *= 2e-6 / heights.std()
np.save("map.npy", heights)

# --- the roughness reduction, as on the command line ---------------------------------------------
command = ["roughness", "map.npy", "--pixel-size", str(pixel), "--periodic"]
print("$ g2tom", " ".join(command))
main(command)  # the command line's entry point, run in this process
print()

# --- the resistance of that surface ------------------------------------------------------------------
force = np.array([20.0, 60.0, 200.0])  # N
for xi in (0.2, 0.5):
    answer = g2tom.predict_resistance("map.npy", force=force, xi=xi, lam=5.0, pixel_size=pixel)
    cells = ", ".join(f"F = {f:g} N: {1e3 * r:.3f} mOhm" for f, r in zip(force, answer["resistance"].values))
    print(f"xi = {xi}, lambda = 5: {cells}")

# --- the full field on the map itself: a 1 mm hard-gold sphere, clean and with 30 % oxide --------------
full = g2tom.surface_resistance("map.npy", force=[0.05, 0.2], pixel_size=pixel, xi=[0.3], correlation_length=[10e-6],
                                fields=2, overrides={"material.bodies": ["hard_gold"], "indenter.radius": 1e-3})
print(f"\nfull field: window {full.attrs['window_pixels']} pixels, {full.sizes['position']} position(s); "
      f"plasticity index of the map's summits {full.attrs['plasticity_index']:.3g}")
for f, force_n in enumerate(full["force"].values):
    print(f"F = {force_n:g} N: clean {1e3 * float(full['resistance_clean_typical'][f]):.3f} mOhm, "
          f"xi = 0.3: {1e3 * float(full['resistance_typical'][0, 0, f]):.3f} mOhm")

fig, ax = plt.subplots(figsize=(4.2, 3.6), layout="constrained")
image = ax.imshow(1e6 * heights, extent=(0, 1e3 * n * pixel, 0, 1e3 * n * pixel), cmap="viridis")
fig.colorbar(image, label="height (um)")
ax.set(xlabel="x (mm)", ylabel="y (mm)", title="the synthetic height map")
fig.savefig("map.png", dpi=100)
