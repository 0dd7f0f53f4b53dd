"""The ground station's clock: the wall clock by default; on a virtual clock the threads
take turns in a fixed order and time jumps to the next deadline when all wait."""

from __future__ import annotations

import queue
import threading

import pytest

from ftlbo_mav import clock
from ftlbo_mav.clock import ClockStopped, VirtualClock


def test_without_a_virtual_clock_the_primitives_are_the_standard_librarys():
    assert clock.virtual() is None
    assert isinstance(clock.Event(), threading.Event)
    assert isinstance(clock.SimpleQueue(), queue.SimpleQueue)
    assert abs(clock.time() - __import__("time").time()) < 5.0


def test_sleeping_threads_wake_in_the_order_of_their_deadlines_at_exactly_them():
    log = []
    with VirtualClock(start_s=100.0, utc_s=1_000_000.0) as vc:
        def sleeper(name: str, every: float) -> None:
            for _ in range(3):
                clock.sleep(every)
                log.append((round(clock.monotonic(), 9), name))

        threads = [clock.Thread(sleeper, ("a", 1.5)), clock.Thread(sleeper, ("b", 1.0))]
        for t in threads:
            t.start()
        for t in threads:
            t.join()
        assert clock.virtual() is vc and clock.monotonic() == 104.5
        assert clock.time() == pytest.approx(1_000_004.5)
    assert log == [(101.0, "b"), (101.5, "a"), (102.0, "b"), (103.0, "a"), (103.0, "b"),
                   (104.5, "a")]
    assert clock.virtual() is None  # the block's end: the wall clock again


def test_an_event_wakes_its_waiter_at_the_instant_it_is_set_or_times_out():
    with VirtualClock(start_s=0.0):
        ev, late = clock.Event(), clock.Event()
        woke = []

        def setter() -> None:
            clock.sleep(2.0)
            ev.set()

        clock.Thread(setter).start()
        assert ev.wait(10.0) and clock.monotonic() == 2.0
        assert not late.wait(0.5) and clock.monotonic() == 2.5
        t = clock.Thread(lambda: woke.append(late.wait()))
        t.start()
        clock.sleep(1.0)
        late.set()
        t.join()
        assert woke == [True] and clock.monotonic() == 3.5


def test_a_queue_hands_items_over_in_order_and_an_empty_get_times_out():
    with VirtualClock(start_s=0.0):
        q = clock.SimpleQueue()

        def producer() -> None:
            for k in range(3):
                clock.sleep(0.25)
                q.put(k)

        clock.Thread(producer).start()
        got = [(q.get(timeout=1.0), clock.monotonic()) for _ in range(3)]
        assert got == [(0, 0.25), (1, 0.5), (2, 0.75)]
        with pytest.raises(queue.Empty):
            q.get(timeout=2.0)
        assert clock.monotonic() == 2.75 and q.empty()


def test_a_condition_waits_for_its_notify_releasing_its_lock_meanwhile():
    with VirtualClock(start_s=0.0):
        cond, state = clock.Condition(), {"n": 0}

        def bump() -> None:
            for _ in range(2):
                clock.sleep(1.0)
                with cond:  # the waiter released the lock: this does not block
                    state["n"] += 1
                    cond.notify_all()

        clock.Thread(bump).start()
        with cond:
            assert cond.wait_for(lambda: state["n"] == 2, timeout=5.0)
            assert clock.monotonic() == 2.0
            assert not cond.wait(0.5)  # nobody notifies: times out
        assert clock.monotonic() == 2.5


def test_an_executor_runs_its_tasks_side_by_side_and_hands_back_their_errors():
    with VirtualClock(start_s=0.0):
        def task(k: float) -> float:
            clock.sleep(k)
            if k == 2.0:
                raise ValueError("two")
            return clock.monotonic()

        with clock.Executor(3) as pool:
            futures = [pool.submit(task, k) for k in (3.0, 1.0, 2.0)]
        assert clock.monotonic() == 3.0  # together, not one after the other
        assert [futures[0].result(), futures[1].result()] == [3.0, 1.0]
        assert isinstance(futures[2].exception(), ValueError)
        with pytest.raises(ValueError, match="two"):
            futures[2].result()
        with clock.Executor(2) as pool:
            assert list(pool.map(lambda k: k * 2, [1, 2])) == [2, 4]


def test_everyone_waiting_for_nothing_stops_the_clock_instead_of_hanging():
    with pytest.raises(ClockStopped), VirtualClock() as vc:
        clock.Event().wait()  # no thread will ever set it, no deadline
    assert vc.stalled


def test_threads_still_waiting_when_the_clock_closes_end_quietly():
    ended = threading.Event()
    with VirtualClock():
        def forever() -> None:
            try:
                while True:
                    clock.sleep(1.0)
            finally:
                ended.set()

        clock.Thread(forever).start()
        clock.sleep(10.0)
    assert ended.wait(5.0)  # ClockStopped unwound it (a SystemExit: no traceback)


def test_a_turn_held_on_something_the_clock_does_not_know_stops_it_as_stalled(monkeypatch):
    """The safety net: a thread that blocks with the turn on a primitive of the standard
    library (not this module's) holds every other up; after STALL_WALL_S of wall time
    the clock stops, names the thread, and the others end."""
    monkeypatch.setattr(clock, "STALL_WALL_S", 1.5)
    outside = threading.Event()
    with VirtualClock() as vc:
        t = clock.Thread(lambda: outside.wait(), name="blocked elsewhere")
        t.start()
        with pytest.raises(ClockStopped):
            clock.sleep(1.0)  # hands the turn to the thread that never gives it back
    outside.set()
    assert vc.stalled and "'blocked elsewhere'" in vc.stall_reason


def test_a_scheduled_call_runs_in_its_turn_by_the_thread_passing_it():
    """No thread of its own: the call runs at its time, in the order it was scheduled
    among threads due then, in whichever thread gives up the turn (even one that ends),
    on the virtual clock."""
    log = []
    threads_before = threading.active_count()
    with VirtualClock(start_s=0.0):
        def tick() -> None:
            log.append((round(clock.monotonic(), 9), "call", threading.active_count()))
            if clock.monotonic() < 0.5:
                clock.call_later(0.2, tick)

        def sleeper() -> None:
            clock.sleep(0.4)
            log.append((round(clock.monotonic(), 9), "thread"))

        clock.call_later(0.2, tick)
        t = clock.Thread(sleeper)
        t.start()
        clock.call_later(0.0, lambda: log.append((clock.monotonic(), "now")))
        t.join()
        clock.sleep(1.0)
    assert log[0] == (0.0, "now")
    # at 0.4 the thread first: it went to sleep (at 0) before the call was scheduled (0.2)
    assert [e[:2] for e in log[1:]] == [(0.2, "call"), (0.4, "thread"), (0.4, "call"),
                                        (0.6, "call")]
    assert all(e[2] <= threads_before + 2 for e in log if e[1] == "call")


def test_a_scheduled_call_that_waits_or_fails_stops_the_clock_naming_it(capsys):
    for bad, words in ((lambda: clock.sleep(1.0), "may not wait"),
                       (lambda: 1 / 0, "ZeroDivisionError")):
        with pytest.raises(ClockStopped), VirtualClock() as vc:
            clock.call_later(1.0, bad, name="the bad one")
            clock.sleep(5.0)
        assert vc.stalled and "the bad one failed" in vc.stall_reason
        assert words in vc.stall_reason
    assert "ZeroDivisionError" in capsys.readouterr().err  # its traceback, said
