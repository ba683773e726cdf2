"""The floor under a wheel: obstacles crossed (cables, cleats, ramps) and roughness.

Everything follows from one geometric fact: a rigid wheel of radius R rolling without slip over a
floor profile z(x) carries its centre along the upper envelope
    y_c(x) = max_xi [ z(xi) + sqrt(R^2 - (x - xi)^2) ] - R,
pivoting about edges where the profile has corners, and the wheel turns by the arc length of
that centre path divided by R (in rolling and in pivoting alike, the contact point is the
instantaneous centre). So over an obstacle the wheel rolls a distance sigma while its hub
advances only x(sigma) horizontally; the difference is what an encoder over-reports (004 Eqs.
1-5 are the chord approximation of the same geometry for a thin step; we compute the exact
envelope numerically for any profile). Roughness is the same over a random profile.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from functools import lru_cache

import numpy as np


def envelope(px: np.ndarray, pz: np.ndarray, R: float, x: np.ndarray) -> np.ndarray:
    """Height of the wheel centre above its resting height, over the floor (z = 0) plus an
    obstacle given by points (px, pz) of its top surface (dense enough that the wheel cannot
    touch between them), for hub positions x."""
    yc = np.zeros(x.size)
    for i in range(0, px.size, 64):
        dxp = x[None, :] - px[i : i + 64, None]
        c = np.sqrt(np.maximum(R * R - dxp * dxp, 0.0)) - R + pz[i : i + 64, None]
        c[np.abs(dxp) > R] = -np.inf
        yc = np.maximum(yc, c.max(axis=0))
    return yc


def obstacle_points(kind: str, h: float, width: float, slope_deg: float, step: float):
    """Points of the top surface of an obstacle centred at 0 (mm).

    step:  a flat cleat (e.g. a taped-down cable duct) of height h and top width `width`
    round: a round cable of diameter h lying on the floor
    ramp:  a cable protector: ramps of `slope_deg` up to a flat top of width `width`, height h
    cap:   a grain: a circular cap of height h over a base `width` wide
    """
    if kind == "step":
        px = np.linspace(-width / 2, width / 2, max(2, math.ceil(width / step) + 1))
        return px, np.full(px.size, h)
    if kind == "round":
        a = np.linspace(-math.pi, math.pi, max(64, math.ceil(math.pi * h / step)))
        return h / 2 * np.sin(a), h / 2 + h / 2 * np.cos(a)
    if kind == "ramp":
        run = h / math.tan(math.radians(slope_deg))
        x1 = width / 2 + run
        px = np.linspace(-x1, x1, max(3, math.ceil(2 * x1 / step) + 1))
        px = np.union1d(px, [-width / 2, width / 2])
        return px, np.clip((x1 - np.abs(px)) / run, 0.0, 1.0) * h
    if kind == "cap":
        c = width / 2
        rho = (c * c + h * h) / (2 * h)
        a0 = math.asin(min(c / rho, 1.0))
        a = np.linspace(-a0, a0, 81)
        return rho * np.sin(a), rho * np.cos(a) - (rho - h)
    raise ValueError(f"unknown obstacle {kind!r}")


@dataclass(frozen=True)
class BumpMap:
    """Horizontal hub progress as a function of rolled distance over one obstacle.

    sigma: rolled distance from the first contact (0 .. total); xh: the hub's horizontal
    progress at that sigma; start: hub position at first contact relative to the obstacle's
    centre line (negative); excess = sigma[-1] - xh[-1], what the encoder over-reports."""

    sigma: np.ndarray
    xh: np.ndarray
    start: float

    @property
    def excess(self) -> float:
        return float(self.sigma[-1] - self.xh[-1])

    @property
    def span(self) -> float:
        return float(self.xh[-1])

    def progress(self, s: np.ndarray) -> np.ndarray:
        """x(sigma) extended by identity before and after (minus the excess)."""
        out = np.interp(s, self.sigma, self.xh)
        out = np.where(s < 0, s, out)
        return np.where(s > self.sigma[-1], s - self.excess, out)

    def rolled(self, xh: np.ndarray) -> np.ndarray:
        """The inverse: rolled distance for a given horizontal progress (a pushed wheel)."""
        out = np.interp(xh, self.xh, self.sigma)
        out = np.where(xh < 0, xh, out)
        return np.where(xh > self.xh[-1], xh + self.excess, out)


def _map(px: np.ndarray, pz: np.ndarray, R: float, h: float) -> BumpMap:
    reach = math.sqrt(max(2 * R * h - h * h, 0.0))
    lo, hi = float(px.min()) - reach, float(px.max()) + reach
    n = 3000 if h > 0.05 else 1500
    x = np.linspace(lo - (hi - lo) * 1e-3, hi + (hi - lo) * 1e-3, n)
    yc = envelope(px, pz, R, x)
    on = np.nonzero(yc > 1e-12 * max(h, 1e-3))[0]
    if on.size < 2:
        return BumpMap(np.array([0.0, 1.0]), np.array([0.0, 1.0]), 0.0)
    i0, i1 = max(on[0] - 1, 0), min(on[-1] + 1, x.size - 1)
    xs, ys = x[i0 : i1 + 1], yc[i0 : i1 + 1]
    sigma = np.concatenate([[0.0], np.cumsum(np.hypot(np.diff(xs), np.diff(ys)))])
    return BumpMap(sigma, xs - xs[0], float(xs[0]))


@lru_cache(maxsize=512)
def bump_map(kind: str, h: float, width: float, slope_deg: float, R: float, stretch: float):
    """The map of one obstacle for a wheel of radius R crossing it at an angle whose secant is
    `stretch` (the cross-section along the wheel's path is stretched by it)."""
    px, pz = obstacle_points(kind, h, width, slope_deg, 0.05)
    return _map(px * stretch, pz, R, h)


def thin_step_excess(h: float, R: float) -> float:
    """Closed form for a knife-thin step (up and down): 2 (R acos(1 - h/R) - sqrt(2Rh - h^2)).

    Used by the tests as an independent check of the envelope computation."""
    return 2.0 * (R * math.acos(1.0 - h / R) - math.sqrt(2 * R * h - h * h))


# ------------------------------------------------------------------------------------------------
# roughness: E(u), the cumulative excess rotation (mm) over u mm of a wheel's travel, 1 mm grid
# ------------------------------------------------------------------------------------------------


@lru_cache(maxsize=64)
def _grain_table(R: float, shape_w: float) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Excess and span of one round-topped grain of height h and base width shape_w * h."""
    hs = np.geomspace(0.005, 8.0, 20)
    ex, sp = [], []
    for h in hs:
        px, pz = obstacle_points("cap", float(h), shape_w * float(h), 0.0, 0.0)
        m = _map(px, pz, R, float(h))
        ex.append(m.excess)
        sp.append(m.span)
    return hs, np.array(ex), np.array(sp)


def _loginterp(h: np.ndarray, hs: np.ndarray, v: np.ndarray) -> np.ndarray:
    """log-log interpolation (excess ~ h^1.5 for small grains), 0 for h <= 0."""
    hh = np.clip(h, hs[0] * 1e-3, hs[-1])
    out = np.exp(np.interp(np.log(hh), np.log(hs), np.log(np.maximum(v, 1e-300)),
                           left=None))
    small = hh < hs[0]
    out[small] = v[0] * (hh[small] / hs[0]) ** 1.5
    return np.where(h > 0, out, 0.0)


def grains(
    rng: np.random.Generator, n_mm: int, R: float, rate_per_m: float, h_mm: float, shape_w: float
) -> np.ndarray:
    """Roughness as discrete grains (sand, grit, tile joints): Poisson positions at rate_per_m,
    heights Rayleigh-distributed with mode h_mm, each a round cap; returns E on a 1 mm grid."""
    lam = rate_per_m / 1000.0
    k = rng.poisson(lam * n_mm)
    pos = rng.uniform(0.0, n_mm, k)
    h = rng.rayleigh(h_mm, k)
    # the table barely depends on R at this scale: round it so wheels of a truck share one
    hs, ex, sp = _grain_table(float(f"{R:.2g}"), round(shape_w * 2) / 2)
    e = _loginterp(h, hs, ex)
    span = np.maximum(_loginterp(h, hs, sp), 1.0)
    dens = np.zeros(n_mm + 2)
    i0 = np.clip(pos.astype(np.int64), 0, n_mm)
    i1 = np.clip((pos + span).astype(np.int64) + 1, 0, n_mm + 1)
    np.add.at(dens, i0, e / (i1 - i0))
    np.add.at(dens, i1, -e / (i1 - i0))
    return np.concatenate([[0.0], np.cumsum(np.cumsum(dens)[: n_mm])])


def surface(
    rng: np.random.Generator, n_mm: int, R: float, sigma_mm: float, corr_mm: float
) -> np.ndarray:
    """Roughness as a continuous random surface: Gaussian, with a Gaussian spectrum of
    correlation length corr_mm and RMS height sigma_mm, on a 0.5 mm grid; the wheel rides its
    envelope; returns E on a 1 mm grid."""
    dx = 0.5
    m = int(n_mm / dx) + 2
    nf = 1 << (m - 1).bit_length()
    f = np.fft.rfftfreq(nf, dx)
    spec = np.fft.rfft(rng.normal(0.0, 1.0, nf)) * np.exp(-((np.pi * f * corr_mm) ** 2) / 2)
    z = np.fft.irfft(spec, nf)[:m]
    z *= sigma_mm / max(float(np.std(z)), 1e-12)
    # the wheel bridges dips narrower than its contact chord: envelope by shifted maxima
    w = math.sqrt(2 * R * 4 * sigma_mm)
    yc = z.copy()
    for j in range(1, min(math.ceil(w / dx), m - 1) + 1):
        c = math.sqrt(max(R * R - (j * dx) ** 2, 0.0)) - R
        yc[j:] = np.maximum(yc[j:], z[:-j] + c)
        yc[:-j] = np.maximum(yc[:-j], z[j:] + c)
    ex = np.sqrt(dx * dx + np.diff(yc) ** 2) - dx
    E = np.concatenate([[0.0], np.cumsum(ex)])
    return np.interp(np.arange(n_mm + 1.0), np.arange(E.size) * dx, E)
