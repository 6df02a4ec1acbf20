"""The accepted states of an event-driven run, held within a bound however long it runs.

A run that comes to rest in contact can take millions of tiny steps (a stiff contact law
bounds an explicit integrator's step); holding every state made `until` = 1e9 exhaust the
memory. Past `cap` rows, every second ordinary row is dropped and later ones are kept at
twice the stride, so the rows stay spread over the whole run; rows where an event happened
(a contact starts or ends, a pin hits its hole) are always kept, because the report finds
its impacts there and compares flags with the previous kept row (flags change only at
events, so any earlier kept row since the last event has the same ones).
"""

from __future__ import annotations

import numpy as np


class KeptRows:
    def __init__(self, cap: int, event_column: int):
        self.cap = cap
        self.event_column = event_column
        self.stride = 1
        self.seen = 0  # rows offered so far (the run's accepted steps)
        self._blocks: list[np.ndarray] = []
        self._numbers: list[np.ndarray] = []  # each kept row's number among the offered ones
        self._kept = 0

    def add(self, rows: np.ndarray) -> None:
        numbers = np.arange(self.seen, self.seen + len(rows))
        self.seen += len(rows)
        chosen = self._chosen(rows, numbers)
        chosen[-1] = True  # the newest state: the run's end is always there
        self._blocks.append(rows[chosen])
        self._numbers.append(numbers[chosen])
        self._kept += int(chosen.sum())
        while self._kept > self.cap and self._thin():
            pass

    def _chosen(self, rows: np.ndarray, numbers: np.ndarray) -> np.ndarray:
        return (numbers % self.stride == 0) | (rows[:, self.event_column] > 0.5)

    def _thin(self) -> bool:
        """Double the stride and drop the rows it no longer keeps; False when nothing could go
        (every kept row is an event: the cap then gives way rather than lose an impact)."""
        rows, numbers = np.vstack(self._blocks), np.concatenate(self._numbers)
        self.stride *= 2
        chosen = self._chosen(rows, numbers)
        chosen[0] = chosen[-1] = True
        self._blocks, self._numbers = [rows[chosen]], [numbers[chosen]]
        dropped = self._kept - int(chosen.sum())
        self._kept -= dropped
        return dropped > 0

    def rows(self) -> np.ndarray:
        return np.vstack(self._blocks)

    def __len__(self) -> int:
        return self._kept


def reported_rows(count: int, every: int, limit: int, events: np.ndarray) -> tuple[np.ndarray, int]:
    """(the rows a report keeps of `count`, the stride): every `every`-th, spread wider when
    that is more than `limit`, plus the event rows (at most `limit` of them, the first ones)
    and the last row. The stride is a multiple of `every`."""
    stride = every
    if -(-count // every) + 1 > limit:
        stride = every * -(-count // (every * (limit - 1)))
    events = np.asarray(events, dtype=int)[:limit]
    return np.unique(np.r_[np.arange(0, count, stride), events, count - 1]), stride
