"""How the job workers are shared between keys (the runner's scheduling policy).

The promise (docs/service.md): while two or more keys have work, each key may hold at most its
share of the workers (the workers divided among the keys with work, at least one each), and
tasks wait in the executor's queue only while one key has work. A key with work waiting and
none running takes the next worker that frees up; when every worker is held by keys over
their share, the newest of their tasks is asked to yield: it ends after the point in
progress, its points are stored and the rest of its work queued again (an indivisible task,
such as one export, starts again later). So a new key's first task starts within about one
point's time, whatever else runs.

Pure functions of who holds what, so the policy is tested without workers.
"""

from __future__ import annotations

from collections.abc import Mapping


def shares(workers: int, capacity: int, owners_with_work: set[str]) -> dict[str, int]:
    """Tasks in flight each owner may have: the whole capacity for a lone owner, else an even
    share of the workers (at least one)."""
    if len(owners_with_work) <= 1:
        return {owner: capacity for owner in owners_with_work}
    each = max(1, workers // len(owners_with_work))
    return {owner: each for owner in owners_with_work}


def submission_order(in_flight: Mapping[str, int], waiting: Mapping[str, int]) -> list[str]:
    """Owners with tasks waiting, those holding fewest tasks first (ties: most waiting first)."""
    owners = [owner for owner, count in waiting.items() if count > 0]
    return sorted(owners, key=lambda owner: (in_flight.get(owner, 0), -waiting[owner], owner))
