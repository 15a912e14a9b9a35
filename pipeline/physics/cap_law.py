"""Single-asperity laws of the discrete contact: a cap's force, stiffness and radius against its interference.

Two laws share one interface, :class:`CapLaw` (all methods vectorised; an interference or load
<= 0 gives 0): ``load(w)`` (N), ``slope(w) = dP/dw`` (N/m), ``radius(w)`` (m) and
``interference(load)`` (m), the inverse of ``load``.

* :class:`HertzCap`: the elastic cap, ``P = (4/3) E* sqrt(beta) w^(3/2)``, ``a = sqrt(beta w)``,
  written with the floating-point expressions the elastic discrete solve has always used, so a
  solve through this law is bit for bit the elastic one.
* :class:`CappedCap`: the cap on the perfectly plastic surface (the elastic half-space with the
  pressure capped by the hardness H, :mod:`g2tom.physics.capped_sphere`). Exactly Hertz's law up
  to the onset ``omega_c``, where Hertz's peak pressure reaches H. Above it ``F / F_c`` and
  ``a / a_c`` against ``W = w / omega_c`` are universal and are read from the table
  (:data:`CAP_INTERFERENCE` and the four after it) by the cubic Hermite interpolant of ``ln F``
  and ``ln a`` in ``ln W`` on the tabulated values and log-log slopes: C1, with Hertz's value
  and slope at the onset (the table's first node is Hertz's, slopes 3/2 and 1/2; the capped law
  leaves Hertz's as about ``(W - 1)^(5/2)``), monotone (every interval meets the
  Fritsch-Carlson bound), and of fourth order between nodes. Beyond the table (``W > 40``) the
  law is the uniform disc of Holm's plastic spot, ``F = pi a^2 H`` at
  ``w = a^2 / (2 beta) + 4 H a / (pi E*)`` (:func:`g2tom.physics.capped_sphere.uniform_disc_law`),
  which the capped law meets exponentially fast (the radius within 5e-9 at ``W = 40``, the
  force within 1e-15), and which the table's last node is: the table need not reach the
  interferences of rough steel (``sigma / omega_c`` near 900), the closed form carries them.
  The stiffness there rises toward the plastic ``2 pi beta H``.

Accuracy of the capped law against the converged capped solve (Richardson from 128 and 256
annulus elements, measured on 240 interferences): within 5e-6 (force) and 1.5e-6 (radius) in
the table's first interval, where the law leaves Hertz's, 7e-7 and 2e-7 in the second, 3e-7
and 1e-7 beyond. Of the model, not the numbers: only the surface pressure is bounded, it is not
an elasto-plastic volume model.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Callable, Protocol

import numpy as np
from numpy.typing import ArrayLike

from g2tom.physics.capped_sphere import critical_scales, uniform_disc_law, uniform_disc_radius

__all__ = ["CapLaw", "HertzCap", "CappedCap", "CAP_INTERFERENCE", "CAP_FORCE", "CAP_RADIUS", "CAP_FORCE_SLOPE",
           "CAP_RADIUS_SLOPE"]

#: The capped law's table: ``W = w / omega_c`` (41 nodes, geometric from 1 to 40), ``F / F_c``,
#: ``a / a_c`` and the log-log slopes ``d ln F / d ln W``, ``d ln a / d ln W`` there, from the
#: converged capped solve (made by ``python -m g2tom.reference.cap_table``; tests/test_cap_law.py
#: recomputes the middle node and holds these to it). The last node is the uniform disc.
CAP_INTERFERENCE = (1.0, 1.0966082271243613, 1.202549603796835, 1.3187257890487505,
                    1.4461255495919247, 1.5858331751372434, 1.7390377067022493, 1.9070430564491687,
                    2.0912791051825463, 2.293313871956453, 2.5148668593658705, 2.757823688103018,
                    3.024252145332219, 3.3164197834698106, 3.6368132191509877, 3.9881592966356054,
                    4.373448295773112, 4.795959382047813, 5.259288515307898, 5.76737905470731,
                    6.324555320336758, 6.9355593971844405, 7.605591494662132, 8.340354205193565,
                    9.146101038546528, 10.029689644980788, 10.998640180189945, 12.061199308776862,
                    13.22641039099137, 14.504190450084279, 15.905414575341009, 17.442008479142682,
                    19.12704999580074, 20.974880386014075, 23.001226394252438, 25.22333409788722,
                    27.66011568724956, 30.33231042584948, 33.262661160676586, 36.47610788484789,
                    40.0)
CAP_FORCE = (1.0, 1.1479439661634157, 1.3161997181283571, 1.5068455507537832, 1.7223193224459854,
             1.9653784652274389, 2.239108231542421, 2.5469427102634863, 2.8926922513028535,
             3.2805754579092397, 3.7152552287466545, 4.201878863987911, 4.74612251889146,
             5.354240445057092, 6.033119552875724, 6.79033987819686, 7.6342415553862,
             8.573998902590441, 9.619702229688546, 10.782448000043626, 12.074438023428876,
             13.50908843189499, 15.1011492890988, 16.86683579957758, 18.823972210404794,
             20.992149628700243, 23.392899112848475, 26.049881534041866, 28.989095850652,
             32.239107594333575, 35.83129953691074, 39.80014669378725, 44.183518025126666,
             49.02300742237049, 54.364296816656285, 60.25755451935019, 66.75787220538572,
             73.92574427977105, 81.82759372943195, 90.53634895901992, 100.13207654441493)
CAP_RADIUS = (1.0, 1.0473215284699158, 1.097365801689576, 1.1504963489847373, 1.2070493708734735,
              1.2673584068392392, 1.3317605136747472, 1.4005971751580215, 1.4742125285340395,
              1.5529498799096169, 1.637147136200348, 1.727131773663449, 1.8232160442721435,
              1.925693174840465, 2.034835265523398, 2.150893407540893, 2.2741002264600976,
              2.4046746792087466, 2.542828582382959, 2.688774114387868, 2.842731464285375,
              3.0049358924170746, 3.1756436738628953, 3.355136648165949, 3.5437253359691647,
              3.741750765068656, 3.949585260795683, 4.167632501610679, 4.396327135962082,
              4.63613421788783, 4.887548662901138, 5.151094865667248, 5.427326564320924,
              5.716826990149035, 6.020209306246657, 6.338117316044431, 6.671226410586668,
              7.0202447197366995, 7.385914434179169, 7.769013271264699, 8.170356032406215)
CAP_FORCE_SLOPE = (1.5, 1.490473779553942, 1.4752655144336502, 1.4581214085079346,
                   1.4403570223439413, 1.4226230666524646, 1.405261162627341, 1.3884466576000771,
                   1.3722598351993778, 1.3567256261262992, 1.3418372557748224, 1.3275708796789936,
                   1.3138947918357993, 1.3007751686716984, 1.2881794936256865, 1.27607838071202,
                   1.2644462904073535, 1.2532615084917411, 1.2425056816056124, 1.2321631412315557,
                   1.222220187495211, 1.212664444584407, 1.2034843457522006, 1.194668763445583,
                   1.1862067720623746, 1.178087516622739, 1.1703001571183518, 1.1628338614251597,
                   1.1556778257462021, 1.1488213080286336, 1.1422536652732764, 1.135964389646211,
                   1.1299431409237104, 1.1241797743276274, 1.1186643636475684, 1.1133872198981851,
                   1.1083389059628908, 1.1035102476975656, 1.098892341885062, 1.0944765615216503,
                   1.090254558842434)
CAP_RADIUS_SLOPE = (0.5, 0.5033552707155753, 0.5091886422343681, 0.5163597157765654,
                    0.5244077908035129, 0.5330245000432313, 0.5419594309366371, 0.5509860392962221,
                    0.5598876658507872, 0.5684533602968378, 0.5764798887150442, 0.5837780826224817,
                    0.5901819733872861, 0.5955589347519543, 0.5998188257370023, 0.6029201735098977,
                    0.6048719426403308, 0.6057303204486775, 0.6055909968337571, 0.6045782945417653,
                    0.6028329709486696, 0.6005004854282401, 0.5977211102573474, 0.5946226586747564,
                    0.591316010077784, 0.5878931684336717, 0.5844273271071099, 0.5809743297009966,
                    0.5775749490899971, 0.5742575096992573, 0.571040502234451, 0.567934968894546,
                    0.5649465343054677, 0.5620770433466269, 0.5593258149897141, 0.5566905650629739,
                    0.5541680505986559, 0.5517545028644404, 0.5494459069608458, 0.5472381732205238,
                    0.545127279421217)

_LOG_W = np.log(CAP_INTERFERENCE)
_LOG_F = np.log(CAP_FORCE)
_LOG_A = np.log(CAP_RADIUS)
_SLOPE_F = np.array(CAP_FORCE_SLOPE)
_SLOPE_A = np.array(CAP_RADIUS_SLOPE)
#: Newton iterations at most when the table is inverted (it takes 3 from the chord).
_INVERSE_ITERATIONS = 50


def _interval(x: np.ndarray, knots: np.ndarray) -> np.ndarray:
    """Index ``k`` of the interval ``[knots[k], knots[k + 1]]`` holding each ``x`` (the end ones beyond)."""
    return np.clip(np.searchsorted(knots, x, side="right") - 1, 0, knots.size - 2)


def _coefficients(k: np.ndarray, knots: np.ndarray, values: np.ndarray,
                  slopes: np.ndarray) -> tuple[np.ndarray, ...]:
    """Interval widths ``h`` and the cubic ``c0 + c1 s + c2 s^2 + c3 s^3`` in ``s = (x - knots[k]) / h``
    that takes the values and slopes at both ends of interval ``k``."""
    h = knots[k + 1] - knots[k]
    rise = values[k + 1] - values[k]
    m0, m1 = slopes[k] * h, slopes[k + 1] * h
    return h, values[k], m0, 3.0 * rise - 2.0 * m0 - m1, m0 + m1 - 2.0 * rise


def _hermite(x: np.ndarray, knots: np.ndarray, values: np.ndarray,
             slopes: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The cubic Hermite interpolant of ``values`` and ``slopes`` on ``knots`` and its derivative at ``x``."""
    k = _interval(x, knots)
    h, c0, c1, c2, c3 = _coefficients(k, knots, values, slopes)
    s = (x - knots[k]) / h
    return c0 + s * (c1 + s * (c2 + s * c3)), (c1 + s * (2.0 * c2 + 3.0 * s * c3)) / h


def _hermite_inverse(y: np.ndarray, knots: np.ndarray, values: np.ndarray, slopes: np.ndarray) -> np.ndarray:
    """The ``x`` where :func:`_hermite` takes the value ``y``, for increasing ``values`` and a monotone
    interpolant: Newton's method on the cubic of the interval holding ``y``, from the chord."""
    k = _interval(y, values)
    h, c0, c1, c2, c3 = _coefficients(k, knots, values, slopes)
    s = np.clip((y - c0) / (values[k + 1] - c0), 0.0, 1.0)
    for _ in range(_INVERSE_ITERATIONS):
        step = (c0 + s * (c1 + s * (c2 + s * c3)) - y) / (c1 + s * (2.0 * c2 + 3.0 * s * c3))
        s = np.clip(s - step, 0.0, 1.0)
        if np.all(np.abs(step) < 1e-13):  # quadratic convergence: s is now exact to rounding
            break
    return knots[k] + s * h


class CapLaw(Protocol):
    """A cap's law: its force, stiffness and contact radius against its interference, and the inverse."""

    def load(self, w: ArrayLike) -> np.ndarray:
        """Force, N, at the interferences ``w`` (m); 0 for ``w <= 0``."""

    def slope(self, w: ArrayLike) -> np.ndarray:
        """Stiffness ``dP/dw``, N/m, the derivative of :meth:`load`; 0 for ``w <= 0``."""

    def radius(self, w: ArrayLike) -> np.ndarray:
        """Contact radius, m, at the interferences ``w`` (m); 0 for ``w <= 0``."""

    def radius_slope(self, w: ArrayLike) -> np.ndarray:
        """``da/dw``, dimensionless, the derivative of :meth:`radius`; 0 for ``w <= 0``."""

    def interference(self, load: ArrayLike) -> np.ndarray:
        """The interference, m, at which the cap carries ``load`` (N); 0 for ``load <= 0``."""


@dataclass(frozen=True)
class HertzCap:
    """Hertz's elastic cap.

    Attributes
    ----------
    e_star
        Effective modulus E*, Pa.
    beta
        Cap radius, m.
    """

    e_star: float
    beta: float
    #: Whether neighbouring caps' contact discs share their overlaps (no: Hertz's discs are the
    #: validated elastic model's, with the caps' point-load coupling).
    shares_overlap = False

    def __post_init__(self) -> None:
        for name, value in (("e_star", self.e_star), ("beta", self.beta)):
            if not (np.isfinite(value) and value > 0):
                raise ValueError(f"{name} = {value!r} is out of range: must be > 0")

    def load(self, w: ArrayLike) -> np.ndarray:
        """Force ``(4/3) E* sqrt(beta) max(w, 0)^(3/2)``, N, at the interferences ``w`` (m)."""
        return 4.0 / 3.0 * self.e_star * np.sqrt(self.beta) * np.maximum(w, 0.0) ** 1.5

    def slope(self, w: ArrayLike) -> np.ndarray:
        """Stiffness ``dP/dw = 2 E* sqrt(beta w)``, N/m, at the interferences ``w`` (m); 0 for ``w <= 0``."""
        return 1.5 * (4.0 / 3.0 * self.e_star * np.sqrt(self.beta)) * np.sqrt(np.maximum(w, 0.0))

    def radius(self, w: ArrayLike) -> np.ndarray:
        """Contact radius ``sqrt(beta max(w, 0))``, m, at the interferences ``w`` (m)."""
        return np.sqrt(self.beta * np.maximum(w, 0.0))

    def radius_slope(self, w: ArrayLike) -> np.ndarray:
        """``da/dw = sqrt(beta / w) / 2``, dimensionless, at the interferences ``w`` (m); 0 for ``w <= 0``."""
        w = np.asarray(w, dtype=float)
        return np.where(w > 0.0, 0.5 * np.sqrt(self.beta / np.where(w > 0.0, w, 1.0)), 0.0)[()]

    def interference(self, load: ArrayLike) -> np.ndarray:
        """The interference, m, at which the cap carries ``load`` (N); 0 for ``load <= 0``."""
        return (np.maximum(load, 0.0) / (4.0 / 3.0 * self.e_star * np.sqrt(self.beta))) ** (2.0 / 3.0)


@dataclass(frozen=True)
class CappedCap:
    """The cap on the perfectly plastic surface: Hertz's up to the onset, then the tabulated capped law.

    Attributes
    ----------
    e_star
        Effective modulus E*, Pa.
    beta
        Cap radius, m.
    hardness
        Hardness H, Pa: the contact pressure's bound.
    """

    e_star: float
    beta: float
    hardness: float
    shares_overlap = True

    def __post_init__(self) -> None:
        critical_scales(self.beta, self.e_star, self.hardness)  # refuses parameters that are not > 0

    @property
    def omega_c(self) -> float:
        """The onset's interference ``beta (pi H / (2 E*))^2``, m."""
        return critical_scales(self.beta, self.e_star, self.hardness)[0]

    @property
    def a_c(self) -> float:
        """The onset's contact radius ``pi beta H / (2 E*)``, m."""
        return critical_scales(self.beta, self.e_star, self.hardness)[1]

    @property
    def F_c(self) -> float:  # noqa: N802 (the force's symbol)
        """The onset's force ``pi^3 beta^2 H^3 / (6 E*^2)``, N."""
        return critical_scales(self.beta, self.e_star, self.hardness)[2]

    def _elastic(self) -> HertzCap:
        """Hertz's law of the same cap, which this one follows up to the onset."""
        return HertzCap(self.e_star, self.beta)

    def load(self, w: ArrayLike) -> np.ndarray:
        """Force, N, at the interferences ``w`` (m); 0 for ``w <= 0``."""
        w = np.asarray(w, dtype=float)
        omega_c, _, f_c = critical_scales(self.beta, self.e_star, self.hardness)
        ratio, top = w / omega_c, CAP_INTERFERENCE[-1]
        table = f_c * np.exp(_hermite(np.log(np.clip(ratio, 1.0, top)), _LOG_W, _LOG_F, _SLOPE_F)[0])
        far = f_c * uniform_disc_law(uniform_disc_radius(np.maximum(ratio, top)))[1]
        return np.where(w <= omega_c, self._elastic().load(w), np.where(ratio <= top, table, far))[()]

    def slope(self, w: ArrayLike) -> np.ndarray:
        """Stiffness ``dP/dw``, N/m, the derivative of :meth:`load`, at the interferences ``w`` (m);
        0 for ``w <= 0``. It rises from Hertz's toward the plastic ``2 pi beta H``."""
        f_c = critical_scales(self.beta, self.e_star, self.hardness)[2]
        return self._tabulated_slope(w, f_c, _LOG_F, _SLOPE_F, lambda x, scale: scale * 3.0 * x / (x + 8.0 / np.pi**2),
                                     self._elastic().slope)

    def radius(self, w: ArrayLike) -> np.ndarray:
        """Contact radius, m, at the interferences ``w`` (m); 0 for ``w <= 0``."""
        w = np.asarray(w, dtype=float)
        omega_c, a_c, _ = critical_scales(self.beta, self.e_star, self.hardness)
        ratio, top = w / omega_c, CAP_INTERFERENCE[-1]
        table = a_c * np.exp(_hermite(np.log(np.clip(ratio, 1.0, top)), _LOG_W, _LOG_A, _SLOPE_A)[0])
        far = a_c * uniform_disc_radius(np.maximum(ratio, top))
        return np.where(w <= omega_c, self._elastic().radius(w), np.where(ratio <= top, table, far))[()]

    def radius_slope(self, w: ArrayLike) -> np.ndarray:
        """``da/dw``, dimensionless, the derivative of :meth:`radius`, at the interferences ``w`` (m);
        0 for ``w <= 0``."""
        a_c = critical_scales(self.beta, self.e_star, self.hardness)[1]
        return self._tabulated_slope(w, a_c, _LOG_A, _SLOPE_A, lambda x, scale: scale / (x + 8.0 / np.pi**2),
                                     self._elastic().radius_slope)

    def _tabulated_slope(self, w: ArrayLike, unit: float, log_values: np.ndarray, log_slopes: np.ndarray,
                         far: Callable[[np.ndarray, float], np.ndarray],
                         elastic: Callable[[np.ndarray], np.ndarray]) -> np.ndarray:
        """The derivative in ``w`` (m) of a quantity tabulated as ``ln(q / unit)`` against ``ln W``:
        Hertz's (``elastic``) up to the onset, the table's to its end, and beyond it ``far(x,
        unit / omega_c)`` with ``x = a / a_c`` of the uniform disc."""
        w = np.asarray(w, dtype=float)
        omega_c = critical_scales(self.beta, self.e_star, self.hardness)[0]
        ratio, top = w / omega_c, CAP_INTERFERENCE[-1]
        inside = np.clip(ratio, 1.0, top)
        value, slope = _hermite(np.log(inside), _LOG_W, log_values, log_slopes)
        table = unit / omega_c * np.exp(value) / inside * slope
        far_value = far(uniform_disc_radius(np.maximum(ratio, top)), unit / omega_c)
        return np.where(w <= omega_c, elastic(w), np.where(ratio <= top, table, far_value))[()]

    def interference(self, load: ArrayLike) -> np.ndarray:
        """The interference, m, at which the cap carries ``load`` (N): the inverse of :meth:`load`;
        0 for ``load <= 0``."""
        load = np.asarray(load, dtype=float)
        omega_c, _, f_c = critical_scales(self.beta, self.e_star, self.hardness)
        ratio, top = load / f_c, CAP_FORCE[-1]
        table = omega_c * np.exp(_hermite_inverse(np.log(np.clip(ratio, 1.0, top)), _LOG_W, _LOG_F, _SLOPE_F))
        far = omega_c * uniform_disc_law(np.sqrt(np.maximum(ratio, top) / 1.5))[0]
        return np.where(load <= f_c, self._elastic().interference(load), np.where(ratio <= top, table, far))[()]
