"""Where the runtime gets its time from.

Every wait in the runtime goes through a :class:`Clock`: ``now()`` and
``sleep_until(deadline)`` on an absolute, monotonic time line in seconds. The
simulator uses :class:`LoopClock` (the event loop's monotonic clock); tests use a
:class:`ManualClock`, on which time moves only when the test moves it, either step by
step with :meth:`ManualClock.advance` or as fast as the loop can go with
:meth:`ManualClock.run_virtual_time` (a 30 s trajectory then runs in well under a
second, the interpolation loop ticking back to back).
"""

from __future__ import annotations

import asyncio
import contextlib
import ctypes
import heapq
import itertools
import logging
import os
import sys
import threading
import time
from collections.abc import Callable
from typing import Final, Protocol

__all__ = [
    "EARLY_WAKE_S",
    "PRECISE_SPIN_S",
    "Clock",
    "LoopClock",
    "ManualClock",
    "ThreadClock",
    "TimerFdClock",
    "precise_clock",
]

logger = logging.getLogger(__name__)


class Clock(Protocol):
    """A monotonic time source with absolute-deadline sleeps."""

    def now(self) -> float:
        """Monotonic time in seconds."""
        ...

    async def sleep_until(self, deadline: float) -> None:
        """Return once ``now() >= deadline`` (at once, after one loop turn, if it already is)."""
        ...


PRECISE_SPIN_S: Final = 0.001
"""The selector waits in whole milliseconds, rounded up (epoll), so a timer fires up to
1 ms late. A precise clock sets its timer this much early and yields to the loop
(``sleep(0)``, other tasks and I/O keep running) until the deadline."""


class LoopClock:
    """Real time: the running event loop's monotonic clock.

    ``spin`` > 0 makes :meth:`sleep_until` precise to a few tens of microseconds
    instead of up to a millisecond late, at the price of keeping the loop busy for
    the last ``spin`` seconds before each deadline (about a quarter of a core for a
    4 ms loop with the default :data:`PRECISE_SPIN_S`). The interpolation loop uses
    it; everything else does not need it.
    """

    def __init__(self, *, spin: float = 0.0) -> None:
        if spin < 0:
            raise ValueError(f"spin must be >= 0, got {spin}")
        self.spin = spin

    def now(self) -> float:
        return asyncio.get_running_loop().time()

    async def sleep_until(self, deadline: float) -> None:
        loop = asyncio.get_running_loop()
        wake = deadline - self.spin
        if wake > loop.time():
            # call_at on the absolute deadline: asyncio.sleep(delay) would recompute the
            # delay from a later now() and add the scheduling latency.
            future: asyncio.Future[None] = loop.create_future()
            handle = loop.call_at(wake, _resolve, future)
            try:
                await future
            finally:
                handle.cancel()
        await asyncio.sleep(0)
        while loop.time() < deadline:  # noqa: ASYNC110 - the precise last stretch, by design
            await asyncio.sleep(0)


def _resolve(future: asyncio.Future[None]) -> None:
    if not future.done():
        future.set_result(None)


EARLY_WAKE_S: Final = 100e-6
"""The timer thread of :class:`ThreadClock` sleeps until this long before a deadline,
then spins the rest. A sleep on this VM overshoots by 55–100 µs (median) and up to
~190 µs (p99) (measured for issue 13), so it rarely has to spin long: a few per cent of
the 4 ms period at most, against the 25 % the loop's own spin costs."""

TIMER_SLACK_NS: Final = 1000
"""Linux timer slack of the timer thread (prctl PR_SET_TIMERSLACK; the default of 50 µs
adds that much to every sleep)."""

_PR_SET_TIMERSLACK: Final = 29
"""From <linux/prctl.h>."""


class _MonotonicClock:
    """Real time on ``time.monotonic`` (the loop's own time line), woken by something
    other than the loop's millisecond timer: the subclass's :meth:`_wait`."""

    def now(self) -> float:
        return time.monotonic()

    async def sleep_until(self, deadline: float) -> None:
        if deadline <= time.monotonic():
            await asyncio.sleep(0)  # a deadline already past still yields once
            return
        await self._wait(deadline, asyncio.get_running_loop())

    async def _wait(self, deadline: float, loop: asyncio.AbstractEventLoop) -> None:
        raise NotImplementedError


class ThreadClock(_MonotonicClock):
    """Real time, precise and cheap: a timer thread wakes the loop at the deadline.

    The event loop's selector rounds its timeouts up to whole milliseconds, so a
    precise :class:`LoopClock` keeps the loop busy for the last millisecond of every
    period (about a quarter of a core for a 4 ms ticker). Here one thread per process,
    shared by every ThreadClock (so many cells in one process share one clock thread),
    sleeps with the OS's precise sleep until :data:`EARLY_WAKE_S` before the earliest
    deadline, spins the few microseconds left, and hands the wake-up to the sleeper's
    loop with ``call_soon_threadsafe`` (which interrupts the selector at once). The tick
    itself still runs on the loop, where the controller lives: nothing is shared with
    the thread but the futures it resolves.

    The thread holds the GIL only while it spins (tens of microseconds) and for the
    hand-off; ``bench/bench_clock.py`` measures the contention with busy servers.
    Same time line as the loop's clock (``time.monotonic``).
    """

    def __init__(self, *, early: float = EARLY_WAKE_S) -> None:
        if early < 0:
            raise ValueError(f"early must be >= 0, got {early}")
        self.early = early

    async def _wait(self, deadline: float, loop: asyncio.AbstractEventLoop) -> None:
        future: asyncio.Future[None] = loop.create_future()
        _timer_thread().add(deadline, self.early, loop, future)
        await future


class _TimerThread:
    """The process's timer thread: a heap of deadlines, woken early, resolved on time."""

    def __init__(self) -> None:
        self._heap: list[tuple[float, int, float, asyncio.AbstractEventLoop, asyncio.Future[None]]]
        self._heap = []
        self._order = itertools.count()
        self._cond = threading.Condition()
        self._thread = threading.Thread(target=self._run, name="pymotoros-clock", daemon=True)
        self._thread.start()

    def add(
        self,
        deadline: float,
        early: float,
        loop: asyncio.AbstractEventLoop,
        future: asyncio.Future[None],
    ) -> None:
        with self._cond:
            heapq.heappush(self._heap, (deadline, next(self._order), early, loop, future))
            if self._heap[0][4] is future:  # a new earliest deadline: re-plan the sleep
                self._cond.notify()

    def _run(self) -> None:
        _precise_sleeps()
        heap = self._heap
        cond = self._cond
        monotonic = time.monotonic
        while True:
            with cond:
                while not heap:
                    cond.wait()
                deadline, _, early, _, future = heap[0]
                if future.cancelled():
                    heapq.heappop(heap)
                    continue
                wait = deadline - early - monotonic()
                if wait > 0:
                    cond.wait(wait)
                    continue  # woken by a new earliest deadline, or time to spin
            while monotonic() < deadline:  # the last few microseconds
                pass
            now = monotonic()
            due = []
            with cond:
                while heap and heap[0][0] <= now:
                    due.append(heapq.heappop(heap))
            for _, _, _, loop, future in due:
                with contextlib.suppress(RuntimeError):  # that loop is closed: nobody waits
                    loop.call_soon_threadsafe(_resolve, future)


_TIMER: _TimerThread | None = None
_TIMER_LOCK = threading.Lock()


def _timer_thread() -> _TimerThread:
    global _TIMER  # one timer thread per process, started on first use
    with _TIMER_LOCK:
        if _TIMER is None:
            _TIMER = _TimerThread()
        return _TIMER


def _precise_sleeps() -> None:
    """Ask Linux for a 1 µs timer slack on this thread (best effort; other OSes: no-op)."""
    if not sys.platform.startswith("linux"):
        return
    try:
        libc = ctypes.CDLL(None, use_errno=True)
        libc.prctl(_PR_SET_TIMERSLACK, TIMER_SLACK_NS, 0, 0, 0)
    except (OSError, AttributeError):  # pragma: no cover - no libc prctl
        logger.debug("could not set the timer slack; sleeps may be ~50 us later")


_CLOCK_MONOTONIC: Final = 1
_TFD_TIMER_ABSTIME: Final = 1
"""From <linux/time.h> and <sys/timerfd.h>."""


class _Timespec(ctypes.Structure):
    _fields_ = (("tv_sec", ctypes.c_long), ("tv_nsec", ctypes.c_long))


class _Itimerspec(ctypes.Structure):
    _fields_ = (("it_interval", _Timespec), ("it_value", _Timespec))


class TimerFdClock(_MonotonicClock):
    """Real time, precise and cheap, on the loop itself (Linux): a timerfd in the selector.

    The selector's own timeouts are whole milliseconds, but a Linux timerfd armed on an
    absolute CLOCK_MONOTONIC deadline (nanoseconds, the loop's time line) makes the fd
    readable at that instant, and epoll returns at once. So the loop sleeps until the
    deadline with no spin and no helper thread (no GIL hand-off): on this VM the wake-up
    lands ~0.1 ms after the deadline (p50), p99 ~0.3 ms, at ~1.6 % of a core for a 4 ms
    ticker doing nothing (``bench/bench_clock.py``; the spinning :class:`LoopClock`:
    ~23 %). One timerfd serves every sleeper of the clock (many cells, one clock);
    it is closed when the last sleeper is cancelled (the simulator stopping).
    """

    def __init__(self) -> None:
        self._libc = _libc()
        self._fd = -1
        self._loop: asyncio.AbstractEventLoop | None = None
        self._sleepers: list[tuple[float, int, asyncio.Future[None]]] = []
        self._order = itertools.count()
        self._armed = 0.0

    @staticmethod
    def available() -> bool:
        """True where a timerfd can be made (Linux with a C library)."""
        lib = _libc()
        return lib is not None and hasattr(lib, "timerfd_create")

    async def _wait(self, deadline: float, loop: asyncio.AbstractEventLoop) -> None:
        self._open(loop)
        future: asyncio.Future[None] = loop.create_future()
        heapq.heappush(self._sleepers, (deadline, next(self._order), future))
        if self._sleepers[0][2] is future:
            self._arm(deadline)
        try:
            await future
        except asyncio.CancelledError:
            self._sleepers = [s for s in self._sleepers if not s[2].done()]
            heapq.heapify(self._sleepers)
            if not self._sleepers:
                self.close()
            raise

    def close(self) -> None:
        """Release the timerfd (reopened by the next sleep)."""
        if self._fd < 0:
            return
        if self._loop is not None and not self._loop.is_closed():
            self._loop.remove_reader(self._fd)
        os.close(self._fd)
        self._fd = -1
        self._loop = None

    def _open(self, loop: asyncio.AbstractEventLoop) -> None:
        if self._fd >= 0:
            if loop is not self._loop:
                raise RuntimeError("a TimerFdClock serves one event loop; make one clock per loop")
            return
        if self._libc is None:  # pragma: no cover - guarded by available()
            raise RuntimeError("timerfd is not available here; use ThreadClock")
        fd = self._libc.timerfd_create(_CLOCK_MONOTONIC, os.O_NONBLOCK | os.O_CLOEXEC)
        if fd < 0:
            err = ctypes.get_errno()
            raise OSError(err, f"timerfd_create failed: {os.strerror(err)}")
        self._fd = fd
        self._loop = loop
        self._armed = 0.0
        loop.add_reader(fd, self._fired)

    def _arm(self, deadline: float) -> None:
        if deadline == self._armed:
            return
        self._armed = deadline
        sec = int(deadline)
        spec = _Itimerspec(_Timespec(0, 0), _Timespec(sec, int((deadline - sec) * 1e9)))
        lib = self._libc
        if lib is None:  # pragma: no cover - _open refused already
            raise RuntimeError("timerfd is not available here; use ThreadClock")
        if lib.timerfd_settime(self._fd, _TFD_TIMER_ABSTIME, ctypes.byref(spec), None) != 0:
            err = ctypes.get_errno()
            raise OSError(err, f"timerfd_settime failed: {os.strerror(err)}")

    def _fired(self) -> None:
        try:
            os.read(self._fd, 8)
        except BlockingIOError:  # a re-arm raced the read: nothing expired
            return
        self._armed = 0.0
        now = time.monotonic()
        sleepers = self._sleepers
        while sleepers and sleepers[0][0] <= now:
            _, _, future = heapq.heappop(sleepers)
            if not future.done():
                future.set_result(None)
        while sleepers and sleepers[0][2].done():
            heapq.heappop(sleepers)
        if sleepers:
            self._arm(sleepers[0][0])


_LIBC: list[ctypes.CDLL | None] = []


def _libc() -> ctypes.CDLL | None:
    """The C library with errno kept, or None where there is none to load."""
    if not _LIBC:
        lib: ctypes.CDLL | None = None
        if sys.platform.startswith("linux"):
            with contextlib.suppress(OSError):
                lib = ctypes.CDLL(None, use_errno=True)
        _LIBC.append(lib)
    return _LIBC[0]


def precise_clock() -> TimerFdClock | ThreadClock:
    """The clock for the interpolation loop: a timerfd where there is one (Linux), the
    timer thread elsewhere."""
    return TimerFdClock() if TimerFdClock.available() else ThreadClock()


class TimerHandle:
    """A callback waiting on a :class:`ManualClock` (:meth:`ManualClock.call_at`)."""

    __slots__ = ("_callback", "_done", "_loop")

    def __init__(self, loop: asyncio.AbstractEventLoop, callback: Callable[[], object]) -> None:
        self._loop = loop
        self._callback = callback
        self._done = False

    def done(self) -> bool:
        """Fired or cancelled."""
        return self._done

    def cancel(self) -> None:
        self._done = True

    def fire(self) -> None:
        if not self._done:
            self._done = True
            self._loop.call_soon(self._callback)


class ManualClock:
    """Virtual time for tests: it moves only when told to.

    Sleepers are kept in a heap of ``(deadline, order, waiter)``; :meth:`advance` wakes
    them in deadline order (ties in the order they went to sleep), so a run is the same
    every time. A waiter is a sleeping task's future, or a callback registered with
    :meth:`call_at`, which is scheduled (``loop.call_soon``) at exactly the place in
    that order where a task's wake-up would be.
    """

    def __init__(self, start: float = 0.0) -> None:
        self._now = start
        self._sleepers: list[tuple[float, int, asyncio.Future[None] | TimerHandle]] = []
        self._order = itertools.count()

    def now(self) -> float:
        """Virtual time in seconds: moves only when advanced, never by itself."""
        return self._now

    @property
    def sleepers(self) -> int:
        """Tasks currently waiting on this clock (callbacks of :meth:`call_at` not counted)."""
        return sum(
            1 for _, _, f in self._sleepers if isinstance(f, asyncio.Future) and not f.done()
        )

    @property
    def next_deadline(self) -> float | None:
        """The earliest deadline anyone is waiting for, or None."""
        self._drop_cancelled()
        return self._sleepers[0][0] if self._sleepers else None

    async def sleep_until(self, deadline: float) -> None:
        """Wait until virtual time reaches ``deadline`` (s): only :meth:`advance` moves it there."""
        if deadline <= self._now:
            await asyncio.sleep(0)
            return
        future: asyncio.Future[None] = asyncio.get_running_loop().create_future()
        heapq.heappush(self._sleepers, (deadline, next(self._order), future))
        await future

    def call_at(self, deadline: float, callback: Callable[[], object]) -> TimerHandle:
        """Run ``callback`` on the running loop once time reaches ``deadline``.

        What a task that calls ``sleep_until(deadline)`` and then ``callback()`` does,
        in the same order among the other sleepers, without a task: a periodic job (the
        twin's state cycle) then costs one callback per period instead of a task's
        wake-up. A deadline already reached schedules it at once.
        """
        handle = TimerHandle(asyncio.get_running_loop(), callback)
        if deadline <= self._now:
            handle.fire()
        else:
            heapq.heappush(self._sleepers, (deadline, next(self._order), handle))
        return handle

    def advance(self, seconds: float) -> None:
        """Move time forward and wake, in deadline order, everyone whose deadline has come."""
        if seconds < 0:
            raise ValueError(f"time cannot go backwards (advance by {seconds} s)")
        self.advance_to(self._now + seconds)

    def advance_to(self, when: float) -> None:
        """Move time forward to ``when`` (absolute) and wake the sleepers that are due."""
        if when < self._now:
            raise ValueError(f"time cannot go backwards ({when} < {self._now})")
        self._now = when
        while self._sleepers and self._sleepers[0][0] <= when:
            _, _, waiter = heapq.heappop(self._sleepers)
            if isinstance(waiter, TimerHandle):
                waiter.fire()
            elif not waiter.done():
                waiter.set_result(None)

    def _drop_cancelled(self) -> None:
        while self._sleepers and self._sleepers[0][2].done():
            heapq.heappop(self._sleepers)

    async def run_virtual_time(self, *, settle_turns: int = 8) -> None:
        """Drive time as fast as possible until cancelled.

        Let the loop run ``settle_turns`` turns (so tasks woken by I/O or by the last
        jump get to run), then jump straight to the earliest deadline. With the ticker
        as a sleeper this runs the interpolation loop back to back. Run it as a task
        and cancel it when done.
        """
        while True:
            for _ in range(settle_turns):
                await asyncio.sleep(0)
            deadline = self.next_deadline
            if deadline is not None:
                self.advance_to(max(deadline, self._now))
