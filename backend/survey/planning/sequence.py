"""The order and direction lanes are flown in, improved by local search.

The planner chains boustrophedon cells (planner._order); that is good on most areas but not
all: on a strip crossed at a shallow angle, flying every other row and coming back for the
rest is shorter than turning into the next row, whose piece is shifted far along. This pass
takes the chain and applies the best improving move until none is left: reversing a run of
lanes (2-opt, each lane flown the other way) or moving a run of up to three lanes elsewhere,
either way round (Or-opt). A transit joins one lane's exit turnaround to the next one's
entry turnaround in a straight line, so reversing a run leaves the transits inside it as
they were and each move's gain is found from four or six distances; all moves of a kind are
weighed at once as numpy arrays.
"""

from __future__ import annotations

import numpy as np

Step = tuple[int, int]  # (lane, end it is entered at: 0 its west end, 1 its east end)

_MAX_LANES = 600  # above this, the chain is kept as it is (the n x n arrays grow large)
_MAX_MOVES = 2000
_GAIN_M = 1e-6


def improve(
    steps: list[Step],
    ends: np.ndarray,
    origin: tuple[float, float] | None,
    blocked: np.ndarray | None = None,
    restarts: int = 0,
) -> list[Step]:
    """`steps` reordered for a shorter path. `ends` holds each lane's turnaround points,
    (n, 2, 2): lane, west/east, (x, y); `origin` is where the vehicle comes from, if the
    first transit counts; `blocked` (2n, 2n), which transits would cross a hole: each costs
    more than any path, so the search first has as few of them as it can. With `restarts`,
    the search also starts from that many nearest-neighbour chains (from lanes spread over
    the list), and the best of all is kept: around holes, the cells' chain can leave the
    search in a poor local optimum."""
    n = len(steps)
    if n == 0 or n > _MAX_LANES:
        return steps
    points = ends.reshape(-1, 2)  # node 2 i + e: lane i's end e
    m = len(points)
    start, finish = m, m + 1  # the way in (from the origin, or free) and the way out (free)
    dist = np.zeros((m + 2, m + 2))
    dist[:m, :m] = np.hypot(*(points[:, None, :] - points[None, :, :]).transpose(2, 0, 1))
    if blocked is not None:
        dist[:m, :m] += blocked * (n + 1) * float(dist[:m, :m].max())
    if origin is not None:
        dist[start, :m] = dist[:m, start] = np.hypot(*(points - np.asarray(origin)).T)
    firsts = [
        steps,
        *(_nearest_chain(dist, n, (k * n // restarts, k % 2)) for k in range(restarts)),
    ]
    found = [_descend(list(first), dist, start, finish) for first in firsts]
    return min(found, key=lambda seq: _cost(seq, dist, start))


def _descend(seq: list[Step], dist: np.ndarray, start: int, finish: int) -> list[Step]:
    """The best improving move each time, until none is left."""
    for _ in range(_MAX_MOVES):
        move = _best_move(seq, dist, start, finish)
        if move is None:
            break
        seq = _apply(seq, move)
    return seq


def _cost(seq: list[Step], dist: np.ndarray, start: int) -> float:
    entry = np.array([2 * lane + end for lane, end in seq])
    return float(dist[start, entry[0]] + dist[(entry ^ 1)[:-1], entry[1:]].sum())


def _nearest_chain(dist: np.ndarray, n: int, first: Step) -> list[Step]:
    """From `first`, the nearest unflown lane's nearer end each time."""
    seq = [first]
    done = np.zeros(n, dtype=bool)
    done[first[0]] = True
    for _ in range(n - 1):
        lane, end = seq[-1]
        row = dist[2 * lane + 1 - end, : 2 * n].reshape(n, 2).copy()
        row[done] = np.inf
        nxt, at = np.unravel_index(int(np.argmin(row)), row.shape)
        seq.append((int(nxt), int(at)))
        done[nxt] = True
    return seq


def _best_move(
    seq: list[Step], dist: np.ndarray, start: int, finish: int
) -> tuple[str, int, int, int, bool] | None:
    n = len(seq)
    entry = np.array([2 * lane + end for lane, end in seq])
    exit_ = entry ^ 1
    before = np.concatenate(([start], exit_[:-1]))  # what each lane is entered from
    after = np.concatenate((entry[1:], [finish]))  # what each lane is left for
    into = dist[before, entry]
    out = dist[exit_, after]
    # 2-opt: lanes i..j flown backwards, in reverse order.
    reverse = (
        dist[before[:, None], exit_[None, :]]
        + dist[entry[:, None], after[None, :]]
        - into[:, None]
        - out[None, :]
    )
    reverse[np.tril_indices(n, -1)] = np.inf
    i, j = np.unravel_index(int(np.argmin(reverse)), reverse.shape)
    best: tuple[float, tuple[str, int, int, int, bool]] = (
        float(reverse[i, j]),
        ("reverse", int(i), int(j), 0, False),
    )
    # Or-opt: lanes i..i+L-1 moved between lanes k and k+1 (k = -1: first; n - 1: last).
    left = np.concatenate(([start], exit_))  # the way out of slot k
    right = np.concatenate((entry, [finish]))  # the way into slot k + 1
    slot = dist[left, right]
    for length in (1, 2, 3):
        if length >= n:
            break
        first = np.arange(n - length + 1)
        last = first + length - 1
        removed = into[first] + out[last] - dist[before[first], after[last]]
        for flipped in (False, True):
            block_in = exit_[last] if flipped else entry[first]
            block_out = entry[first] if flipped else exit_[last]
            gain = (
                dist[left[None, :], block_in[:, None]]
                + dist[block_out[:, None], right[None, :]]
                - slot[None, :]
                - removed[:, None]
            )
            k = np.arange(-1, n)
            inside = (k[None, :] >= first[:, None] - 1) & (k[None, :] <= last[:, None])
            gain[inside] = np.inf
            a, b = np.unravel_index(int(np.argmin(gain)), gain.shape)
            if gain[a, b] < best[0]:
                best = (float(gain[a, b]), ("move", int(a), length, int(b) - 1, flipped))
    return best[1] if best[0] < -_GAIN_M else None


def _apply(seq: list[Step], move: tuple[str, int, int, int, bool]) -> list[Step]:
    kind, i, j, k, flipped = move
    if kind == "reverse":
        return seq[:i] + [(lane, 1 - end) for lane, end in reversed(seq[i : j + 1])] + seq[j + 1 :]
    length = j
    block = seq[i : i + length]
    if flipped:
        block = [(lane, 1 - end) for lane, end in reversed(block)]
    rest = seq[:i] + seq[i + length :]
    at = k + 1 if k < i else k - length + 1
    return rest[:at] + block + rest[at:]
