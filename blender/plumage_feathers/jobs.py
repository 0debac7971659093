"""Dressing in the background with progress and cancel (no bpy here, so a
test can drive it without Blender's UI).

The library's create is one C call; it reports progress through the
callback given to `plumage.System(progress=...)` every few milliseconds and
stops (PLUMAGE_STATUS_INTERRUPTED, nothing created) as soon as the callback
returns true. `DressJob` runs that call on a worker thread (ctypes releases
the GIL during it), records the last phase and fraction and answers the
callback with the cancel flag. The modal operator calls `tick()` on each of
its timer events (every 0.1 s) and `cancel()` on Esc; `drive()` is the same
loop for a script or a test, with the clock, the sleep and the cancel
request passed in.
"""

from __future__ import annotations

import threading
import time
from typing import Any, Callable, Optional

RUNNING, FINISHED, CANCELLED, FAILED = "RUNNING", "FINISHED", "CANCELLED", "FAILED"

# the library's phases of a create (plumage._ffi.PHASES) and the share of
# the whole each stands for in the progress bar (roughly their share of the
# time on a large mesh). With several threads the phases interleave (a
# sampling thread still reports while adjusting has begun): the bar shows
# the sum of each phase's furthest fraction, so it never goes back.
PHASE_WEIGHTS = {"preparing": 0.05, "sampling": 0.25, "ordering": 0.1, "adjusting": 0.6}


class DressJob:
    """`make_system(progress)` builds the system (on a worker thread) with
    the given progress callback; `tick()` reports how it goes."""

    def __init__(self, make_system: Callable[[Callable[[str, float], bool]], Any]) -> None:
        self._make = make_system
        self._cancel = threading.Event()
        self._done = threading.Event()
        self._active = True  # the callback stays in the system's config: after the job it never stops a call
        self._thread: Optional[threading.Thread] = None
        self.phase = ""
        self.fraction = 0.0
        self._furthest: dict = {}
        self.system: Any = None
        self.error: Optional[BaseException] = None

    def progress(self, phase: str, fraction: float) -> bool:
        if not self._active:
            return False
        self.phase, self.fraction = phase, float(fraction)
        if fraction > self._furthest.get(phase, 0.0):
            self._furthest[phase] = float(fraction)
        return self._cancel.is_set()

    def start(self) -> None:
        def work() -> None:
            try:
                self.system = self._make(self.progress)
            except BaseException as e:  # reported by tick() on the main thread
                self.error = e
            finally:
                self._active = False
                self._done.set()

        self._thread = threading.Thread(target=work, name="plumage-dress", daemon=True)
        self._thread.start()

    def cancel(self) -> None:
        self._cancel.set()

    @property
    def overall(self) -> float:
        """The whole create's share done, in [0, 1]."""
        if self._done.is_set():
            return 1.0
        done = sum(w * min(max(self._furthest.get(p, 0.0), 0.0), 1.0) for p, w in PHASE_WEIGHTS.items())
        return min(done, 0.999)

    def tick(self, cancel_requested: bool = False) -> str:
        """RUNNING, FINISHED (`system` is set), CANCELLED or FAILED (`error`)."""
        if cancel_requested:
            self.cancel()
        if not self._done.is_set():
            return RUNNING
        if self._thread is not None:
            self._thread.join()
        if self.system is not None:  # also when it finished before the callback saw a late cancel
            return FINISHED
        if self._cancel.is_set():
            return CANCELLED
        return FAILED

    def wait(self, timeout: Optional[float] = None) -> bool:
        return self._done.wait(timeout)


def drive(
    job: DressJob,
    *,
    clock: Callable[[], float] = time.monotonic,
    sleep: Callable[[float], None] = time.sleep,
    cancel_requested: Callable[[float], bool] = lambda now: False,
    report: Callable[[float, float], None] = lambda now, fraction: None,
    interval: float = 0.1,
) -> str:
    """The modal operator's loop without a window: starts the job, then every
    `interval` asks `cancel_requested(now)`, ticks and reports
    `report(now, overall fraction)` until the job ends; returns its status."""
    job.start()
    while True:
        now = clock()
        status = job.tick(cancel_requested(now))
        report(now, job.overall)
        if status != RUNNING:
            return status
        sleep(interval)
