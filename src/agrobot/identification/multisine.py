"""Random-phase multisines (Pintelon & Schoukens): u(t) = sum_k A cos(2 pi k f0 t + phi_k) over
the excited harmonics k of f0 = fs / N.

- ``odd``: every odd k in the band;
- ``odd_odd``: k = 1, 5, 9, ... (k = 1 mod 4) in the band, so that the odd lines k = 3 mod 4 and
  all even lines stay free to show odd and even nonlinear distortions.
Crest factor: the realisation with the lowest crest factor of ``candidates`` random-phase draws.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

KINDS = ("odd", "odd_odd", "full")


@dataclass(frozen=True)
class MultisineDesign:
    fs: float                 # sample rate [Hz]
    period_samples: int       # N
    f_min: float              # band [Hz]
    f_max: float
    rms: float                # of the signal
    kind: str = "odd_odd"

    def __post_init__(self) -> None:
        if self.kind not in KINDS:
            raise ValueError(f"multisine kind {self.kind!r}; expected one of {KINDS}")
        if not (0 <= self.f_min < self.f_max <= self.fs / 2):
            raise ValueError(f"band {self.f_min}..{self.f_max} Hz must lie in 0..fs/2 = {self.fs / 2} Hz")
        if len(self.excited) == 0:
            raise ValueError("no harmonic of the period falls in the band")

    @property
    def f0(self) -> float:
        return self.fs / self.period_samples

    @property
    def excited(self) -> np.ndarray:
        k = np.arange(1, self.period_samples // 2)
        f = k * self.f0
        band = (f >= self.f_min - 1e-12) & (f <= self.f_max + 1e-12)
        if self.kind == "odd":
            band &= k % 2 == 1
        elif self.kind == "odd_odd":
            band &= k % 4 == 1
        return k[band]


def crest_factor(x: np.ndarray) -> float:
    return float(np.max(np.abs(x)) / np.sqrt(np.mean(x**2)))


def realisation(design: MultisineDesign, rng: np.random.Generator, candidates: int = 20) -> np.ndarray:
    """One period (N samples) of a random-phase multisine, the best crest factor of the draws."""
    N, k = design.period_samples, design.excited
    best, best_cf = None, np.inf
    for _ in range(max(1, candidates)):
        spectrum = np.zeros(N // 2 + 1, dtype=complex)
        spectrum[k] = np.exp(1j * rng.uniform(0, 2 * np.pi, len(k)))
        x = np.fft.irfft(spectrum, n=N)
        x *= design.rms / np.sqrt(np.mean(x**2))
        cf = crest_factor(x)
        if cf < best_cf:
            best, best_cf = x, cf
    return best
