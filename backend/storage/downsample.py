"""Min/max-preserving downsampling: a chart of the result shows the true extremes.

Every n-th row would step over a short spike; instead the rows are cut into equal
buckets and each bucket keeps its lowest and highest sample, in time order.
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from typing import TypeVar

Row = TypeVar("Row")


def minmax_downsample(
    rows: Sequence[Row], points: int, value: Callable[[Row], float | None]
) -> list[Row]:
    """At most ``points`` rows (``points`` ≥ 2), keeping each bucket's min and max."""
    if len(rows) <= points:
        return list(rows)
    buckets = points // 2
    kept: list[Row] = []
    for bucket in range(buckets):
        start = bucket * len(rows) // buckets
        end = (bucket + 1) * len(rows) // buckets
        low_index = high_index = start
        low = high = None
        for index in range(start, end):
            current = value(rows[index])
            if current is None:
                continue
            if low is None or current < low:
                low, low_index = current, index
            if high is None or current > high:
                high, high_index = current, index
        first, second = sorted((low_index, high_index))
        kept.append(rows[first])
        if second != first:
            kept.append(rows[second])
    return kept
