"""Which period kernel a batch runs (aerodock/world/block_choice.py): the faster by measurement,
the slower probed a few periods in every two hundred, and the numbers the same whichever runs."""

from __future__ import annotations

import numpy as np
import pytest

from aerodock.bench.simulator import SimLoop
from aerodock.config import load_config
from aerodock.world import block_choice, period
from aerodock.world.block_choice import BlockChoice


def fly(choice: BlockChoice, periods: int, cost: dict[bool, float], steps: int = 5) -> list[bool]:
    """Run ``periods`` periods whose wall time per step is ``cost[parallel]``; which way each
    ran."""
    ways = []
    for _ in range(periods):
        way = choice.parallel()
        ways.append(way)
        choice.record(cost[way] * steps, steps)
    return ways


SETTLED = BlockChoice.PROBE / (BlockChoice.HOME + BlockChoice.PROBE)  # the slower way's share


def test_the_threads_stay_where_they_are_faster():
    choice = BlockChoice()
    ways = fly(choice, 3000, {True: 1.0, False: 1.6})
    assert choice.home is True
    assert ways[:BlockChoice.FIRST] == [True] * BlockChoice.FIRST
    # once settled, the other way only in its probes
    assert ways[-2000:].count(False) <= SETTLED * 2000 + BlockChoice.PROBE
    assert choice.cost_s_per_step == {True: 1.0, False: 1.6}


def test_a_busy_machine_moves_the_periods_off_the_threads_and_back():
    """Another process on a core makes the threads the slower way: after the first probe the
    periods run one after another, the threads only probed; when the core is free again the
    next probe brings them back."""
    choice = BlockChoice()
    ways = fly(choice, 3000, {True: 3.0, False: 1.0})
    assert choice.home is False
    assert ways[BlockChoice.FIRST:BlockChoice.FIRST + BlockChoice.PROBE] == \
        [False] * BlockChoice.PROBE
    assert ways[-2000:].count(True) <= SETTLED * 2000 + BlockChoice.PROBE
    ways = fly(choice, BlockChoice.HOME + 2 * BlockChoice.PROBE,
               {True: 0.7, False: 1.0})  # the core is free again
    assert choice.home is True and ways[-1] is True


def test_an_early_choice_is_looked_at_again_soon():
    """The threads measured slow while the process warmed up: the first home is one thread,
    but the next probe comes after HOME_FIRST calls, not HOME, and brings the threads back."""
    choice = BlockChoice()
    fly(choice, BlockChoice.FIRST + BlockChoice.PROBE, {True: 2.0, False: 1.0})
    assert choice.home is False
    fly(choice, BlockChoice.HOME_FIRST + BlockChoice.PROBE, {True: 0.5, False: 1.0})
    assert choice.home is True


def test_a_small_difference_does_not_move_the_home():
    choice = BlockChoice()
    fly(choice, 1000, {True: 1.0, False: 0.97})  # within MARGIN
    assert choice.home is True


def test_one_slow_call_does_not_decide():
    """A stretch's cost is its median call: one call slowed by a page fault or another
    process's turn does not make its way the slower."""
    choice = BlockChoice()
    for i in range(BlockChoice.FIRST):
        choice.record(5.0 * (100.0 if i == 3 else 1.0), 5)  # one slow call
    fly(choice, BlockChoice.PROBE, {True: 1.0, False: 1.2})
    assert choice.cost_s_per_step == {True: 1.0, False: 1.2}
    assert choice.home is True


def test_the_first_period_of_a_stretch_and_empty_periods_are_not_timed():
    """A thread's wake-up (the first period of a stretch) and a period that stopped before its
    first step say nothing of the way's speed; a stretch with nothing timed leaves no figure."""
    choice = BlockChoice()
    choice.record(1e6, 5)  # the first period: a wake-up
    for _ in range(BlockChoice.FIRST - 1):
        choice.record(10.0, 5)
    assert not choice.parallel()  # probing now
    choice.record(123.0, 0)  # stopped at once: not timed, and not the stretch's first either
    choice.record(1e6, 5)  # the probe's first stepping period: a wake-up
    for _ in range(BlockChoice.PROBE - 2):
        choice.record(5.0, 5)
    assert choice.cost_s_per_step == {True: 2.0, False: 1.0}
    assert choice.home is False and not choice.parallel()
    for _ in range(BlockChoice.HOME_FIRST):  # the home stretch, then a probe of the threads
        choice.record(5.0, 5)
    for _ in range(BlockChoice.PROBE):  # that steps nothing: no figure, no change
        choice.record(1.0, 0)
    assert True not in choice.cost_s_per_step and choice.home is False


def test_one_choice_per_batch_size_and_thread_count():
    assert block_choice.block_choice(97, 2) is block_choice.block_choice(97, 2)
    assert block_choice.block_choice(97, 2) is not block_choice.block_choice(98, 2)
    assert block_choice.block_choice(97, 2) is not block_choice.block_choice(97, 3)


@pytest.mark.skipif(not period.PERIOD_OK, reason="no compiled period here")
def test_the_numbers_do_not_depend_on_which_way_ran(monkeypatch):
    """A campaign whose periods switch between the two kernels every few periods ends where the
    same campaign run one after another throughout ends, to the bit."""
    n = 70

    def run(switching: bool) -> list[np.ndarray]:
        ran: list[int] = []
        if switching:
            monkeypatch.setattr(period, "kernel_blocks", lambda n: 2)
            monkeypatch.setattr(period, "CHOOSE_BLOCKS", True)
            choice = BlockChoice()
            # short stretches, and every probe wins (a margin below -1): the home changes at
            # every probe's end, whatever the timing
            choice.FIRST, choice.PROBE, choice.HOME_FIRST, choice.MARGIN = 3, 2, 3, -10.0
            choice.__init__()
            monkeypatch.setattr(period, "block_choice", lambda n: choice)
        else:
            monkeypatch.setattr(period, "kernel_blocks", lambda n: 1)
        for name, way in (("period_kernel", False), ("period_kernel_parallel", True)):
            kernel = getattr(period, name)

            def counted(*args, kernel=kernel, way=way):
                ran.append(way)
                return kernel(*args)

            monkeypatch.setattr(period, name, counted)
        loop = SimLoop(load_config(), n)
        loop.run(24, True)
        monkeypatch.undo()
        if switching:  # both kernels ran, in turns
            assert True in ran and False in ran, ran
        else:
            assert set(ran) == {False}
        s = loop.world.state
        return [s.both.p, s.both.v, s.both.R, s.both.w, s.bar.p, s.imu.attitude]

    for a, b in zip(run(False), run(True), strict=True):
        assert np.array_equal(a, b)
