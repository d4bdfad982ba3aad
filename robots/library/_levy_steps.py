"""Step lengths for Lévy walks: Mantegna's algorithm (Sutantyo et al., IV-B, eq. 11-12) and
Viswanathan's estimate of the best exponent (eq. 3-5).

**Which α.** The code uses *Mantegna's stable index* α ∈ (0, 2] everywhere: the step-length
density has the tail P(l) ~ l^-(1+α), so Viswanathan's power law P(l) ~ l^-μ has μ = 1 + α.
The paper's eq. 2 writes P(l) ≈ l^-α with the same letter for what is μ (Fig. 2 and eq. 4-5
are in that notation: "α ≈ 2 - 1/ln²(λ/r_v)"), while its eq. 1 and 11-12 use the stable index,
for which α = 2 is the Gaussian. Viswanathan's optimal inverse-square law (μ = 2) is therefore
stable α = 1 here; :func:`viswanathan_mu` gives μ and :func:`stable_alpha` turns it into the α
the generator takes.

**Scale and cap.** The generator's output z is dimensionless (γ = 1); a walk's step is
``min(cap, scale · |z|)`` metres (:class:`LevySteps`). ``scale`` (metres per unit step, 1 m
by default: the sensing range of the experiment's robots) sets where the power law starts;
``cap`` (20 m by default: the side of the paper's arena) bounds one step, since a step longer
than the arena ends at a wall anyway.

Cost: one step is ``2 n`` Gaussian draws (n = 100): ~10 µs with numpy, drawn once per walk
phase, not per tick.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

#: Mantegna's C(α) (the nonlinear correction's knee) as the degree-5 fit of his Table I in
#: α, highest power first; valid for about 0.75 ≤ α ≤ 1.99.
_C_FIT = (-17.7767, 113.3855, -281.5879, 337.5439, -193.5494, 44.8754)


def _sigma_x(alpha: float) -> float:
    """Mantegna's σ_x(α) (his eq. 12): the scale of the numerator that makes γ = 1."""
    num = math.gamma(1 + alpha) * math.sin(math.pi * alpha / 2)
    den = math.gamma((1 + alpha) / 2) * alpha * 2 ** ((alpha - 1) / 2)
    return float((num / den) ** (1 / alpha))


def _kappa(alpha: float) -> float:
    """Mantegna's K(α) (his eq. 20)."""
    a = alpha * math.gamma((alpha + 1) / (2 * alpha)) / math.gamma(1 / alpha)
    b = (
        alpha
        * math.gamma((alpha + 1) / 2)
        / (math.gamma(1 + alpha) * math.sin(math.pi * alpha / 2))
    )
    return float(a * b ** (1 / alpha))


def mantegna(
    rng: np.random.Generator,
    alpha: float,
    size: int,
    n: int = 100,
    *,
    correction: bool = False,
) -> np.ndarray:
    """``size`` draws of z_n (Sutantyo et al., eq. 11-12): m = a / |b|^(1/α) with Gaussian a,
    b, and z_n = n^(-1/α) Σ_k m_k over ``n`` of them.

    ``correction``: Mantegna's own version (his eq. 6, 15, 23): a scaled by σ_x(α) so that the
    limit has γ = 1, and each m passed through w = ((K(α) - 1) e^(-|m|/C(α)) + 1) m, which
    makes z_n close to the stable law already for small n (valid 0.75 ≤ α ≤ 1.99).

    At α = 2 the stable law is the Gaussian of variance 2 (eq. 1 with γ = 1), and that is what
    is returned: eq. 11 degenerates there (a / |b|^(1/2) has the tail l^-3 for every n, so the
    sum of eq. 12 keeps it instead of becoming Gaussian). Raises ``ValueError`` outside (0, 2].
    """
    if not 0.0 < alpha <= 2.0:
        raise ValueError(f"alpha must be in (0, 2], got {alpha}")
    if n < 1 or size < 0:
        raise ValueError("n must be positive and size non-negative")
    if alpha == 2.0:
        return rng.normal(0.0, math.sqrt(2.0), size)
    a = rng.standard_normal((size, n))
    b = rng.standard_normal((size, n))
    if correction:
        if not 0.75 <= alpha <= 1.99:
            raise ValueError(f"Mantegna's correction holds for 0.75 <= alpha <= 1.99, got {alpha}")
        m = _sigma_x(alpha) * a / np.abs(b) ** (1 / alpha)
        c = float(np.polyval(_C_FIT, alpha))
        m = ((_kappa(alpha) - 1.0) * np.exp(-np.abs(m) / c) + 1.0) * m
    else:
        m = a / np.abs(b) ** (1 / alpha)
    out: np.ndarray = m.sum(axis=1) / n ** (1 / alpha)
    return out


def viswanathan_mu(lam: float, r_v: float) -> float:
    """Viswanathan's optimal power-law exponent μ ≈ 2 - 1/ln²(λ/r_v) (Sutantyo et al., eq. 4-5,
    where it is written α): ``lam`` is the mean distance between targets, ``r_v`` the sensing
    range. Tends to 2 (the inverse-square law) as λ/r_v grows. Needs λ > r_v."""
    if lam <= r_v or r_v <= 0:
        raise ValueError("need lam > r_v > 0")
    return 2.0 - 1.0 / math.log(lam / r_v) ** 2


def stable_alpha(mu: float) -> float:
    """Mantegna's stable index for a power-law exponent μ (P(l) ~ l^-μ): α = μ - 1."""
    return mu - 1.0


def mean_flights(lam: float, r_v: float, mu: float) -> float:
    """Mean number of flights between successive targets, N ≈ (λ/r_v)^((μ-1)/2) (eq. 3, with
    the paper's α written as μ)."""
    return float((lam / r_v) ** ((mu - 1.0) / 2.0))


@dataclass
class LevySteps:
    """Step lengths of a Lévy walk: ``min(cap, scale · |z_n|)`` metres, z_n from
    :func:`mantegna` with stable index ``alpha`` (α = 1: Viswanathan's μ = 2)."""

    rng: np.random.Generator
    alpha: float = 1.0
    scale: float = 1.0
    """Metres per unit step."""
    cap: float = 20.0
    """The longest step (m)."""
    n: int = 100
    correction: bool = False

    def __post_init__(self) -> None:
        mantegna(self.rng, self.alpha, 0, self.n, correction=self.correction)  # check the args
        if self.scale <= 0 or self.cap <= 0:
            raise ValueError("scale and cap must be positive")

    def draw(self) -> float:
        """The next step length (m)."""
        z = mantegna(self.rng, self.alpha, 1, self.n, correction=self.correction)
        return min(self.cap, self.scale * abs(float(z[0])))


@dataclass
class FixedSteps:
    """The fixed-length walk's steps (the paper's constant-frequency oscillator): ``length`` m."""

    length: float = 1.0

    def draw(self) -> float:
        """The next step length (m)."""
        return self.length
