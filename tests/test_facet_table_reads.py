"""runtime.parallel_map: the order of the items, the threads, the first failure raised."""
import threading
import time

import pytest

from waveoptics import runtime


def test_parallel_map_keeps_order_and_uses_threads():
    seen = set()
    lock = threading.Lock()
    barrier = threading.Barrier(2, timeout=10)

    def fn(x):
        if x < 2:   # the first two items meet: they run at the same time, in two threads
            barrier.wait()
        with lock:
            seen.add(threading.get_ident())
        return x * x

    assert runtime.parallel_map(fn, range(20), workers=2) == [x * x for x in range(20)]
    assert len(seen) == 2 and threading.get_ident() not in seen


def test_parallel_map_with_one_worker_runs_in_the_calling_thread(monkeypatch):
    monkeypatch.setenv("WAVEOPTICS_WORKERS", "1")
    assert runtime.parallel_map(lambda x: threading.get_ident(), range(5)) == [threading.get_ident()] * 5
    assert list(runtime.parallel_imap(str, [3, 1, 2], workers=4)) == ["3", "1", "2"]
    assert runtime.parallel_map(str, []) == []


def test_parallel_map_raises_the_first_failing_items_exception():
    done = []

    def fn(x):
        if x == 3:
            raise ValueError(f"item {x}")
        time.sleep(0.01)
        done.append(x)
        return x

    with pytest.raises(ValueError, match="item 3"):
        runtime.parallel_map(fn, range(200), workers=2)
    assert 3 <= len(done) < 150   # the items not started when it failed are dropped (all 199: 1 s of sleeps)
