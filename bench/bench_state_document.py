"""The state document's cost per call (prints numbers; not a test).

    python bench/bench_state_document.py

The pendant feed encodes the document 25 times a second on the loop that runs the
interpolation ticks. Two numbers per run, each the best and the median of 7 rounds:
the encoder alone (``document_encoder(ControllerSnapshot)`` on one snapshot of the
default cell after 50 ticks) and the whole state document as ``GET /api/state`` builds
it (``controller.snapshot()`` and ``state_document``). Run it from the worktree with
``PYTHONPATH=src``; compare two versions by alternating runs in one sitting.
"""

from __future__ import annotations

import statistics
import time
from collections.abc import Callable
from typing import Any

from pymotoros.controller import VirtualController
from pymotoros.runtime.pendant.document import state_document
from pymotoros.runtime.snapshot_document import document_encoder
from pymotoros.runtime.ticker import LatenessStats, TickStats

ROUNDS = 7
STATS = TickStats(4.0, 1000, 2, 0, 0, LatenessStats(0.05, 0.2, 1.5))


def per_call_us(call: Callable[[], Any], n: int) -> tuple[float, float]:
    """(best, median) of ``ROUNDS`` rounds of ``n`` calls, in µs per call."""
    rounds = []
    for _ in range(ROUNDS):
        t0 = time.perf_counter()
        for _ in range(n):
            call()
        rounds.append((time.perf_counter() - t0) / n * 1e6)
    return min(rounds), statistics.median(rounds)


def main() -> None:
    vc = VirtualController()
    for _ in range(50):
        vc.tick()
    snapshot = vc.snapshot()
    encode = document_encoder(type(snapshot))
    best, median = per_call_us(lambda: encode(snapshot), 20_000)
    print(f"encoder alone:        best {best:7.2f} µs, median {median:7.2f} µs per document")
    best, median = per_call_us(
        lambda: state_document(vc.snapshot(), STATS, (None, None, None)), 2_000
    )
    print(f"snapshot + document:  best {best:7.2f} µs, median {median:7.2f} µs per document")


if __name__ == "__main__":
    main()
