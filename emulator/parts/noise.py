"""A seeded Gaussian noise source that gives the same numbers under CPython and MicroPython.

The parts need noise (an ADC's, a monitor's, an injected noise fault) that is reproducible
from a seed on both interpreters; MicroPython's ``random`` has no ``gauss`` and its generator
differs from CPython's, so this is a 32-bit xorshift (Marsaglia 2003) and the Box-Muller
transform on top of it.
"""

import math


class Noise:
    def __init__(self, seed: int = 1) -> None:
        self.state = (seed & 0xFFFFFFFF) or 0x9E3779B9
        self.spare = 0.0
        self.has_spare = False

    def u32(self) -> int:
        x = self.state
        x ^= (x << 13) & 0xFFFFFFFF
        x ^= x >> 17
        x ^= (x << 5) & 0xFFFFFFFF
        self.state = x
        return x

    def uniform(self) -> float:
        """A float in (0, 1]."""
        return (self.u32() + 1) / 4294967296.0

    def gauss(self, sigma: float) -> float:
        """One sample of N(0, sigma^2); 0.0 (and no draw) when sigma is 0."""
        if not sigma:
            return 0.0
        if self.has_spare:
            self.has_spare = False
            return self.spare * sigma
        r = math.sqrt(-2.0 * math.log(self.uniform()))
        a = 2.0 * math.pi * self.uniform()
        self.spare = r * math.sin(a)
        self.has_spare = True
        return r * math.cos(a) * sigma
