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
:class:`BlockChoice` runs the threads first, then a short probe of the other way at regular
intervals, and switches when the probe's wall time per physics step is lower by more than
:attr:`BlockChoice.MARGIN`. One choice per batch size, kept for the process (campaigns of the
same size meet the same machine).
"""

from __future__ import annotations


class BlockChoice:
    """The running choice for one batch size: :meth:`parallel` says which kernel the next
    period runs; :meth:`record` takes its wall time.

    A *stretch* is a run of periods in one way; its first period that steps is not timed (a
    thread's wake-up, a cache refilled). The first stretch (:attr:`FIRST` periods) runs in
    blocks, the next (:attr:`PROBE`) one after another; from then on the faster way (the
    *home*) runs :attr:`HOME` periods between probes of :attr:`PROBE` periods of the other way.
    At most ``PROBE / (HOME + PROBE)`` (3 %) of the periods run the slower way.

    Attributes:
        home: whether the home is the blocks across the threads.
        cost_s_per_step: each way's wall time per physics step, s, over its last stretch.
    """

    FIRST = 8
    PROBE = 6
    HOME = 200
    MARGIN = 0.05
    """The other way must be this much faster per step to become the home."""

    def __init__(self) -> None:
        self.home = True
        self.cost_s_per_step: dict[bool, float] = {}
        self._stretch(True, self.FIRST)

    def parallel(self) -> bool:
        """Whether the next period runs its blocks across the threads."""
        return self._mode

    def record(self, seconds: float, steps: int) -> None:
        """The period just run took ``seconds`` of wall time for ``steps`` physics steps (0:
        it stopped before its first, and is not timed)."""
        if steps > 0:
            if self._untimed:
                self._untimed = False
            else:
                self._seconds += seconds
                self._steps += steps
        self._left -= 1
        if self._left > 0:
            return
        if self._steps:
            self.cost_s_per_step[self._mode] = self._seconds / self._steps
        if self._mode == self.home:  # a home stretch ended: probe the other way
            self._stretch(not self.home, self.PROBE)
            return
        here = self.cost_s_per_step.get(self.home)
        there = self.cost_s_per_step.get(self._mode)
        if here is not None and there is not None and there < (1.0 - self.MARGIN) * here:
            self.home = self._mode
        self._stretch(self.home, self.HOME)

    def _stretch(self, mode: bool, periods: int) -> None:
        self._mode, self._left, self._untimed, self._seconds, self._steps = (
            mode, periods, True, 0.0, 0)


_CHOICES: dict[int, BlockChoice] = {}


def block_choice(n: int) -> BlockChoice:
    """The choice for batches of ``n`` trials in this process."""
    choice = _CHOICES.get(n)
    if choice is None:
        choice = _CHOICES[n] = BlockChoice()
    return choice
