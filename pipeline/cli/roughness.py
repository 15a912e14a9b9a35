"""``g2tom roughness FILE``: the moments and Greenwood–Williamson parameters of a measured surface
(:func:`g2tom.heightmap.measure`), printed as text or one JSON object.

The text says how many pixels of the map were measured and used, and how the moments were taken:
the spectrum of the whole map, or, when undefined pixels around the measured area lie outside it
(a round or irregular field of view), the masked, window-corrected spectrum of that area."""

from __future__ import annotations

import argparse
import json
import warnings
from typing import Any

from g2tom.heightmap import PLAUSIBLE_SIGMA, measure

__all__ = ["roughness_cli"]


def _report(r: dict[str, Any]) -> str:
    return "\n".join([
        f"file        {r['file']} ({r['reader']}, heights in {r['file_height_unit']}), {r['shape'][0]} x "
        f"{r['shape'][1]} pixels of {r['pixel_size'][0]:.4g} x {r['pixel_size'][1]:.4g} m",
        f"detrending  {r['detrending']} removed, window {r['window']}, wavelengths >= {r['cutoff_wavelength']:.4g} m",
        _filled_line(r),
        f"rms_height = {r['rms_height']:.6g} m   (std of surface heights)",
        f"m0    = {r['m0']:.6g} m^2",
        f"m2    = {r['m2']:.6g}",
        f"m4    = {r['m4']:.6g} m^-2",
        f"alpha = {r['bandwidth_alpha']:.6g}   (Nayak's bandwidth m0 m4/m2^2)",
        f"sigma = {r['sigma']:.6g} m   (std of summit heights, sqrt(1 - 0.8968/alpha) sqrt(m0))",
        f"eta   = {r['eta']:.6g} m^-2   (sqrt(3)/(18 pi) m4/m2)",
        f"beta  = {r['beta']:.6g} m   ({r['beta_rule']})",
        f"use: --set roughness.sigma={r['sigma']:.6g} --set roughness.eta={r['eta']:.6g} "
        f"--set roughness.beta={r['beta']:.6g}",
    ])


def _filled_line(r: dict[str, Any]) -> str:
    measured, total, used = r["measured_pixels"], r["map_pixels"], r["used_pixels"]
    share = "all of them" if used == measured else f"{used} ({r['used_share']:.1%})"
    line = f"measured    {measured} of {total} pixels ({measured / total:.1%}) used: {share} ({r['estimator']})\n"
    if not r["filled_pixels"]:
        where = "" if measured == total else " inside the measured area"
        return line + f"filled      none (no undefined pixels{where})"
    return line + _gap_line(r)


def _gap_line(r: dict[str, Any]) -> str:
    return (f"filled      {r['filled_pixels']} undefined pixels ({r['filled_share']:.2%}) by the fill of least curvature; "
            f"masked instead, rms_height {r['masked_rms_change']:+.2%}, m2 {r['masked_m2_change']:+.2%}, "
            f"m4 {r['masked_m4_change']:+.2%} (finite differences)")


def roughness_cli(args: argparse.Namespace) -> None:
    """Print the moments and GW parameters of ``args.heightmap`` (text, or one JSON object with --json).

    Raises
    ------
    ConfigError
        On a bad option, a missing or unreadable file, or an unusable map.
    """
    result = measure(args.heightmap, args.pixel_size, args.cutoff, True if args.periodic else None, args.beta_rule)
    low, high = PLAUSIBLE_SIGMA
    if not low <= result["rms_height"] <= high:
        warnings.warn(
            f"HEIGHTMAP {str(args.heightmap)!r}: rms height = {result['rms_height']:.3g} m is implausible for a "
            f"surface (expected {low:g}..{high:g} m): are the heights in m?", stacklevel=2)
    print(json.dumps(result) if args.json else _report(result))
