"""Which of the two period kernels a batch runs, chosen by measuring both.

A control period of ``n`` trials runs its blocks of trials across numba's threads
(:func:`~aerodock.world.period_kernel.period_kernel_parallel`) or one after another
(:func:`~aerodock.world.period_kernel.period_kernel`); the numbers are the same either way
(``tests/unit/test_period_parallel.py``), so only the time differs. On an idle 2-core machine
the blocks across the threads are faster from about 128 trials on. But every physics step's
blocks wait for the slowest, so a thread that loses its core to another process holds up the
whole step: with another process busy on one of the two cores, the same periods took 2.4-2.6 s
in blocks against 0.9 s one after another at 64 trials, 1.1-1.3 against 0.7-0.9 at 256 and
0.7-0.8 against 0.6 at 1,024 (docs/performance.md, "Blocks of trials on a busy machine").

So a batch that may run in blocks times its periods in both ways and keeps the faster:
:class:`BlockChoice` runs the threads first, then short probes of the other way, and switches
when a probe's wall time per physics step is lower by more than :attr:`BlockChoice.MARGIN`
(the threads keep a tie: at 64 trials on an idle machine they take the same wall time for
three quarters more CPU). One choice per batch size and thread count, kept for the process
(campaigns of the same size meet the same machine).
"""

from __future__ import annotations

import numba


class BlockChoice:
    """The running choice for one batch size and thread count: :meth:`parallel` says which
    kernel the next call of the period runs; :meth:`record` takes its wall time.

    A *stretch* is a run of calls in one way; its first call that steps is not timed (a
    thread's wake-up, a cache refilled), and a stretch's cost is the median of its calls' wall
    time per physics step (one slow call, a page fault or another process's turn, does not
    decide). The first stretch (:attr:`FIRST` calls) runs in blocks, the next (:attr:`PROBE`)
    one after another; from then on the faster way (the *home*) runs between probes of
    :attr:`PROBE` calls of the other way, for :attr:`HOME_FIRST` calls after a change of home
    and twice as many after each probe that changes nothing, up to :attr:`HOME`: an early
    choice made while the process was still warming up is looked at again soon, and a settled
    one runs the slower way in at most ``PROBE / (HOME + PROBE)`` (3 %) of the calls.

    Attributes:
        home: whether the home is the blocks across the threads.
        cost_s_per_step: each way's wall time per physics step, s, over its last stretch.
    """

    FIRST = 12
    PROBE = 6
    HOME_FIRST = 25
    HOME = 200
    MARGIN = 0.05
    """The other way must take this much less time per step to become the home."""

    def __init__(self) -> None:
        self.home = True
        self.cost_s_per_step: dict[bool, float] = {}
        self._home_length = self.HOME_FIRST
        self._stretch(True, self.FIRST)

    def parallel(self) -> bool:
        """Whether the next call runs its blocks across the threads."""
        return self._mode

    def record(self, seconds: float, steps: int) -> None:
        """The call just run took ``seconds`` of wall time for ``steps`` physics steps (0: it
        stopped before its first, and is not timed)."""
        if steps > 0:
            if self._untimed:
                self._untimed = False
            else:
                self._per_step.append(seconds / steps)
        self._left -= 1
        if self._left > 0:
            return
        if self._per_step:
            self.cost_s_per_step[self._mode] = float(sorted(self._per_step)[
                len(self._per_step) // 2])
        else:  # nothing timed: no figure rather than an old one
            self.cost_s_per_step.pop(self._mode, None)
        if self._mode == self.home:  # a home stretch ended: probe the other way
            self._stretch(not self.home, self.PROBE)
            return
        here = self.cost_s_per_step.get(self.home)
        there = self.cost_s_per_step.get(self._mode)
        if here is not None and there is not None and there < (1.0 - self.MARGIN) * here:
            self.home = self._mode
            self._home_length = self.HOME_FIRST
        else:
            self._home_length = min(2 * self._home_length, self.HOME)
        self._stretch(self.home, self._home_length)

    def _stretch(self, mode: bool, calls: int) -> None:
        self._mode, self._left, self._untimed = mode, calls, True
        self._per_step: list[float] = []


_CHOICES: dict[tuple[int, int], BlockChoice] = {}


def block_choice(n: int, blocks: int | None = None) -> BlockChoice:
    """The choice for batches of ``n`` trials in ``blocks`` blocks (one a thread; default:
    numba's thread count now) in this process: a change of the thread count (``reproduce``
    lends a core to its side worker) has a choice of its own."""
    key = (n, numba.get_num_threads() if blocks is None else blocks)
    choice = _CHOICES.get(key)
    if choice is None:
        choice = _CHOICES[key] = BlockChoice()
    return choice
