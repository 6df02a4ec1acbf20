"""The runner's sharing of workers between keys (service.jobs.fair_share), as pure policy."""

from __future__ import annotations

from flexmech.service.jobs.fair_share import shares, submission_order


def test_a_lone_key_may_fill_the_queue_and_keys_together_split_the_workers():
    assert shares(2, 4, {"a"}) == {"a": 4}
    assert shares(2, 4, {"a", "b"}) == {"a": 1, "b": 1}
    assert shares(4, 8, {"a", "b"}) == {"a": 2, "b": 2}
    assert shares(2, 4, {"a", "b", "c"}) == {"a": 1, "b": 1, "c": 1}  # at least one each
    assert shares(2, 4, set()) == {}


def test_the_key_holding_fewest_workers_is_served_first():
    assert submission_order({"a": 2, "b": 0}, {"a": 5, "b": 1}) == ["b", "a"]
    assert submission_order({"a": 1, "b": 1}, {"a": 1, "b": 3}) == ["b", "a"]  # then most waiting
    assert submission_order({"a": 0}, {"a": 0, "b": 2}) == ["b"]  # a key with nothing waiting is not served
