"""The ground station's clock: the wall clock, or a simulated one shared with the emulator.

Kept whole: the virtual clock and the waiting primitives that park on it are one mechanism
(each primitive is a few lines over the clock's turn-taking); apart they would reach into
each other's internals.

Everything on the ground that waits or tells the time (the links' reader threads, the
vehicles' status pumps, the watch, the keeper, the uploads) does it through this module:
:func:`monotonic`, :func:`time`, :func:`sleep`, and the waiting primitives
:class:`Event`, :class:`Condition`, :class:`SimpleQueue`, :class:`Thread` and
:class:`Executor`. By default they are the standard library's, on the wall clock.

Inside ``with VirtualClock():`` (and in every :class:`Thread` started there) they run on
simulated time instead, as a discrete-event simulation: the threads take turns, one at a
time, in a fixed order; time stands still while one runs, and when every thread waits
it jumps to the earliest deadline. Work that never waits can be a *scheduled call*
instead of a thread (:func:`call_later`): it takes its turn in the same order, run by
whichever thread is giving up the turn, so it costs no thread switch (a switch between
two threads costs tens of microseconds of the machine's time, most of a short turn). An
in-process emulator (:mod:`ftlbo_mav.sim.inprocess`) steps its copters every 20 ms of
that time as such a call, and a link to it does its own duties so. A flight then costs
only the computation it needs, however long it lasts, the ground's own delays are no
longer the flight's error, and the same seed flies the same flight.

A thread that blocks on something this module does not know (a socket, a lock held
across a wait, the standard library's own ``threading.Event``) holds everyone up: code
that runs on a virtual clock uses only these primitives to wait.
"""

from __future__ import annotations

import contextvars
import heapq
import itertools
import queue
import threading
import time as _time
import traceback
from collections import deque
from collections.abc import Callable, Iterable
from concurrent.futures import ThreadPoolExecutor
from typing import Any, Self

__all__ = ["ClockStopped", "Condition", "Event", "Executor", "SimpleQueue", "Thread",
           "VirtualClock", "call_later", "monotonic", "sleep", "time", "virtual"]


STALL_WALL_S = 60.0
"""Wall seconds a virtual clock's turn may stay with one thread before the clock is
stopped as stalled (a flight takes a few seconds of wall time, a turn milliseconds)."""


class ClockStopped(SystemExit):
    """Raised in a thread still waiting on a virtual clock when the clock is closed (a
    :class:`SystemExit`: the thread ends quietly)."""


class _Wall:
    """The wall clock: the standard library's time and primitives."""

    @staticmethod
    def monotonic() -> float:
        return _time.monotonic()

    @staticmethod
    def time() -> float:
        return _time.time()

    @staticmethod
    def sleep(seconds: float) -> None:
        _time.sleep(max(0.0, seconds))


WALL = _Wall()
_current: contextvars.ContextVar = contextvars.ContextVar("ftlbo_mav.clock", default=WALL)


def virtual() -> VirtualClock | None:
    """The virtual clock this thread runs on, or None on the wall clock."""
    c = _current.get()
    return c if isinstance(c, VirtualClock) else None


def monotonic() -> float:
    """Seconds on this thread's clock (``time.monotonic`` on the wall clock)."""
    return _current.get().monotonic()


def time() -> float:
    """UTC seconds since the epoch on this thread's clock (``time.time``)."""
    return _current.get().time()


def sleep(seconds: float) -> None:
    _current.get().sleep(seconds)


def call_later(delay: float, fn: Callable[[], None], *, name: str = "a scheduled call") -> None:
    """:meth:`VirtualClock.call_later` on this thread's clock (a virtual one only: on the
    wall clock a thread waits instead)."""
    c = virtual()
    if c is None:
        raise RuntimeError("call_later needs a virtual clock")
    c.call_later(delay, fn, name=name)


class _Waiter:
    __slots__ = ("gate", "name", "released", "woken")

    def __init__(self, name: str | None = None) -> None:
        self.name = name or threading.current_thread().name  # the thread it lets run
        self.gate = threading.Lock()
        self.gate.acquire()
        self.woken = False     # queued for the turn
        self.released = False  # given the turn (or let go: the clock stopped)

    def release(self) -> None:
        if not self.released:
            self.released = True
            self.gate.release()


class _Call:
    """A function the clock calls in its turn (:meth:`VirtualClock.call_later`)."""

    __slots__ = ("fn", "name", "woken")

    def __init__(self, fn: Callable[[], None], name: str) -> None:
        self.fn, self.name, self.woken = fn, name, False


class VirtualClock:
    """Simulated time for the threads that run on it, one at a time.

    ``with VirtualClock() as clock:`` makes the calling thread run on it until the block
    ends; :class:`Thread` s started inside join it. ``utc_s``: the UTC time (seconds since
    the epoch) at its start, ``start_s`` its :func:`monotonic` value then.
    """

    def __init__(self, *, start_s: float = 1000.0, utc_s: float | None = None) -> None:
        self._lock = threading.Lock()
        self._now = float(start_s)
        self.utc_offset = (_time.time() if utc_s is None else utc_s) - self._now
        self._timers: list = []       # (deadline, order, waiter)
        self._parked: set = set()     # every waiter not yet given the turn
        self._ready: deque = deque()  # woken waiters, in the order they were woken
        self._order = itertools.count()
        self._running = False         # one thread holds the turn
        self._stopped = False
        self.stalled = False          # every thread waited with no deadline: closed
        self.stall_reason: str | None = None
        self._holder = "the thread that opened it"  # who has the turn (what a stall names)
        self._turns = 0               # turns passed so far (the watchdog's sign of life)
        self._token = None
        self._calling: int | None = None  # the thread running a scheduled call, if one is

    # -- time
    def monotonic(self) -> float:
        return self._now

    def time(self) -> float:
        return self._now + self.utc_offset

    def sleep(self, seconds: float) -> None:
        with self._lock:
            self._park(self._now + max(0.0, seconds))

    def call_later(self, delay: float, fn: Callable[[], None], *,
                   name: str = "a scheduled call") -> None:
        """``fn()`` after ``delay`` seconds, in its turn among the threads (at once: queued
        now, as a thread started now is), run by whichever thread passes the turn then:
        no thread of its own, so no thread switch. ``fn`` may not wait (sleep, or wait
        on anything); it may set events, put on queues and call :meth:`call_later`."""
        call = _Call(fn, name)
        with self._lock:
            if self._stopped:
                return
            if delay <= 0:
                self._wake(call)
            else:
                heapq.heappush(self._timers, (self._now + delay, next(self._order), call))

    # -- the turn (called with self._lock held)
    def _park(self, deadline: float | None, *lists: list) -> None:
        """The calling thread gives up its turn until woken (by a primitive it waits on,
        in ``lists``, or by time reaching ``deadline``); returns holding the lock."""
        if self._stopped:
            raise ClockStopped("virtual clock closed")
        if self._calling == threading.get_ident():
            raise RuntimeError("a call scheduled on a virtual clock may not wait")
        w = _Waiter()
        self._parked.add(w)
        for waiters in lists:
            waiters.append(w)
        if deadline is not None:
            heapq.heappush(self._timers, (deadline, next(self._order), w))
        self._running = False
        self._pass_turn()
        self._lock.release()
        try:
            w.gate.acquire()
        finally:
            self._lock.acquire()
            for waiters in lists:
                if w in waiters:
                    waiters.remove(w)
        if self._stopped:
            raise ClockStopped("virtual clock closed")

    def _wake(self, w: _Waiter) -> None:
        if not w.woken:
            w.woken = True
            self._ready.append(w)

    def _wake_all(self, waiters: list) -> None:
        for w in list(waiters):
            self._wake(w)

    def _pass_turn(self) -> None:
        """Nobody runs: the next woken thread runs, else time moves to the next deadline.
        A scheduled call whose turn it is runs here, in the thread passing the turn."""
        while not (self._running or self._stopped):
            if not self._ready:
                while self._timers and self._timers[0][2].woken:
                    heapq.heappop(self._timers)
                if not self._timers:
                    self._stall("every thread waits for something no thread will do")
                    return
                t = self._timers[0][0]
                self._now = max(self._now, t)
                while self._timers and self._timers[0][0] <= t:
                    self._wake(heapq.heappop(self._timers)[2])
            w = self._ready.popleft()
            self._running, self._holder = True, w.name
            self._turns += 1
            if isinstance(w, _Call):
                self._call(w)
                continue
            self._parked.discard(w)
            w.release()
            return

    def _call(self, call: _Call) -> None:
        """Run a scheduled call, the lock let go meanwhile (it may use the primitives)."""
        self._calling = threading.get_ident()
        self._lock.release()
        token = _current.set(self)  # a thread may pass the turn as it ends, off the clock
        try:
            call.fn()
        except ClockStopped:
            pass
        except BaseException as exc:  # noqa: BLE001 - ends the simulation, said why
            traceback.print_exception(exc)
            with self._lock:
                self._calling = None
                if not self._stopped:
                    self._stall(f"{call.name} failed: {exc!r}")
            self._lock.acquire()
            return
        finally:
            _current.reset(token)
            if self._calling is not None:
                self._calling = None
                self._lock.acquire()
        self._running = False

    def _stall(self, why: str) -> None:
        self.stalled, self.stall_reason = True, why
        self._stop()

    def _stop(self) -> None:
        self._stopped = True
        for w in self._parked:
            w.release()
        self._parked.clear()
        self._ready.clear()
        self._timers.clear()

    def _enroll(self, name: str) -> _Waiter:
        """A thread about to start: queued for the turn now, in its starter's order."""
        w = _Waiter(name)
        with self._lock:
            if not self._stopped:
                self._parked.add(w)
                self._wake(w)
            else:
                w.release()
        return w

    def _first_turn(self, w: _Waiter) -> None:
        w.gate.acquire()
        if self._stopped:
            raise ClockStopped("virtual clock closed")

    def _leave(self) -> None:
        with self._lock:
            self._running = False
            self._pass_turn()

    # -- lifetime
    def __enter__(self) -> Self:
        with self._lock:
            self._running = True  # the thread that opened it has the turn
        self._token = _current.set(self)
        threading.Thread(target=self._watch, name="virtual clock watchdog", daemon=True).start()
        return self

    def _watch(self) -> None:
        """A safety net on the wall clock: a turn held for :data:`STALL_WALL_S` without
        any thread running on (a thread blocked on something this module does not know)
        stops the clock, so a run of many flights records a stalled one instead of
        hanging; its threads end with :class:`ClockStopped`."""
        last, since = -1, _time.monotonic()
        while not self._stopped:
            _time.sleep(1.0)
            if self._turns != last:
                last, since = self._turns, _time.monotonic()
            elif _time.monotonic() - since >= STALL_WALL_S:
                with self._lock:
                    if not self._stopped and self._turns == last:
                        self._stall(f"no turn passed for {STALL_WALL_S:g} s of wall time "
                                    f"(the turn with {self._holder!r}, "
                                    f"{len(self._parked)} threads waiting)")

    def __exit__(self, *exc) -> None:
        _current.reset(self._token)
        with self._lock:
            self._stop()


def _wait(clock: VirtualClock, ready: Callable[[], bool], timeout: float | None,
          waiters: list) -> bool:
    """Under ``clock``'s lock: until ``ready()`` or ``timeout`` seconds; ``ready()``."""
    deadline = None if timeout is None else clock._now + max(0.0, timeout)
    while not ready():
        if deadline is not None and clock._now >= deadline:
            return False
        clock._park(deadline, waiters)
    return True


class _VirtualEvent:
    def __init__(self, clock: VirtualClock) -> None:
        self._clock, self._flag, self._waiters = clock, False, []

    def is_set(self) -> bool:
        return self._flag

    def set(self) -> None:
        with self._clock._lock:
            self._flag = True
            self._clock._wake_all(self._waiters)

    def clear(self) -> None:
        self._flag = False

    def wait(self, timeout: float | None = None) -> bool:
        with self._clock._lock:
            return _wait(self._clock, lambda: self._flag, timeout, self._waiters)


class _VirtualQueue:
    def __init__(self, clock: VirtualClock) -> None:
        self._clock, self._items, self._waiters = clock, deque(), []

    def put(self, item: Any, block: bool = True, timeout: float | None = None) -> None:
        with self._clock._lock:
            self._items.append(item)
            self._clock._wake_all(self._waiters)

    put_nowait = put

    def get(self, block: bool = True, timeout: float | None = None) -> Any:
        with self._clock._lock:
            if not block:
                timeout = 0.0
            if not _wait(self._clock, lambda: bool(self._items), timeout, self._waiters):
                raise queue.Empty
            return self._items.popleft()

    def get_nowait(self) -> Any:
        return self.get(block=False)

    def empty(self) -> bool:
        return not self._items

    def qsize(self) -> int:
        return len(self._items)


class _VirtualCondition:
    def __init__(self, clock: VirtualClock) -> None:
        self._clock, self._lock, self._waiters = clock, threading.RLock(), []

    def __enter__(self) -> bool:
        return self._lock.__enter__()

    def __exit__(self, *exc) -> None:
        self._lock.__exit__(*exc)

    def wait(self, timeout: float | None = None) -> bool:
        clock = self._clock
        clock._lock.acquire()
        deadline = None if timeout is None else clock._now + max(0.0, timeout)
        saved = self._lock._release_save()  # all of it, however often it was entered
        try:
            clock._park(deadline, self._waiters)
            return deadline is None or clock._now < deadline
        finally:
            clock._lock.release()
            self._lock._acquire_restore(saved)

    def wait_for(self, predicate: Callable[[], bool], timeout: float | None = None) -> bool:
        deadline = None if timeout is None else self._clock._now + timeout
        while not (result := predicate()):
            left = None if deadline is None else deadline - self._clock._now
            if left is not None and left <= 0:
                return result
            self.wait(left)
        return result

    def notify_all(self) -> None:
        with self._clock._lock:
            self._clock._wake_all(self._waiters)

    notify = notify_all


def Event():  # noqa: N802 - a factory standing in for the class
    """``threading.Event``, on this thread's clock."""
    c = virtual()
    return threading.Event() if c is None else _VirtualEvent(c)


def SimpleQueue():  # noqa: N802
    """``queue.SimpleQueue``, on this thread's clock."""
    c = virtual()
    return queue.SimpleQueue() if c is None else _VirtualQueue(c)


def Condition():  # noqa: N802
    """``threading.Condition``, on this thread's clock."""
    c = virtual()
    return threading.Condition() if c is None else _VirtualCondition(c)


class Thread:
    """``threading.Thread`` on this thread's clock: on a virtual clock it takes turns
    with the others and runs on the clock of the thread that started it."""

    def __init__(self, target: Callable, args: Iterable = (), *, name: str | None = None,
                 daemon: bool = True) -> None:
        self._target, self._args = target, tuple(args)
        self._clock = virtual()
        self._done = Event()
        self._thread = threading.Thread(target=self._run, name=name, daemon=daemon)
        self._context: contextvars.Context | None = None

    @property
    def name(self) -> str:
        return self._thread.name

    def start(self) -> None:
        self._context = contextvars.copy_context()
        self._turn = None if self._clock is None else self._clock._enroll(self.name)
        self._thread.start()

    def _run(self) -> None:
        clock = self._clock
        if clock is None:
            try:
                self._context.run(self._target, *self._args)
            finally:
                self._done.set()
            return
        try:
            clock._first_turn(self._turn)
            self._context.run(self._target, *self._args)
        except ClockStopped:
            return
        finally:
            if not clock._stopped:
                self._done.set()
                clock._leave()

    def join(self, timeout: float | None = None) -> None:
        if self._clock is None:
            self._thread.join(timeout)
        else:
            self._done.wait(timeout)

    def is_alive(self) -> bool:
        return not self._done.is_set() and self._thread.is_alive()


class _Future:
    def __init__(self) -> None:
        self._done = Event()
        self._result: Any = None
        self._error: BaseException | None = None

    def result(self, timeout: float | None = None) -> Any:
        self._done.wait(timeout)
        if self._error is not None:
            raise self._error
        return self._result

    def exception(self, timeout: float | None = None) -> BaseException | None:
        self._done.wait(timeout)
        return self._error


class _VirtualExecutor:
    """``ThreadPoolExecutor`` on a virtual clock: a thread per task (every use here
    gives as many workers as tasks)."""

    def __init__(self) -> None:
        self._threads: list[Thread] = []

    def submit(self, fn: Callable, *args) -> _Future:
        f = _Future()

        def run() -> None:
            try:
                f._result = fn(*args)
            except Exception as exc:  # noqa: BLE001 - handed to whoever asks the future
                f._error = exc
            finally:
                f._done.set()

        t = Thread(run, name="task")
        self._threads.append(t)
        t.start()
        return f

    def map(self, fn: Callable, items: Iterable) -> Iterable:
        futures = [self.submit(fn, a) for a in items]
        return (f.result() for f in futures)

    def __enter__(self) -> Self:
        return self

    def __exit__(self, *exc) -> None:
        for t in self._threads:
            t.join()


def Executor(max_workers: int):  # noqa: N802
    """``concurrent.futures.ThreadPoolExecutor``, on this thread's clock."""
    return ThreadPoolExecutor(max_workers=max_workers) if virtual() is None else _VirtualExecutor()
