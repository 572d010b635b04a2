"""One clock read through another, over a link that delays but never hurries."""

from __future__ import annotations

from collections.abc import Sequence


def lower_envelope_slope(samples: Sequence[tuple[float, float]], slope: float) -> float:
    """The slope of the line under (x, arrival) samples that touches the least delayed
    sample of each half of them, starting from a guess. Delays push points up, never
    down, so this line is the true one whatever the delays' spread, where a least-squares
    fit leans toward the late ones."""
    half = len(samples) // 2
    first, second = samples[:half], samples[half:]
    for _ in range(3):
        xa, ta = min(first, key=lambda s: s[1] - s[0] * slope)
        xb, tb = min(second, key=lambda s: s[1] - s[0] * slope)
        if xb <= xa:
            break
        slope = (tb - ta) / (xb - xa)
    return slope
