"""Settled starts of single-trial episodes, settled a block of upcoming trials at a time.

An episode starts from the mission's settled start (``mission.settle_s`` of station keeping
before t = 0, 1,500 physics steps by default): about 1 s for one trial, nearly all of it in the
world's physics step, whose cost hardly grows with the batch (batch-first NumPy: 32 trials cost
about 1.2 times one). So :class:`StartCache` settles the trial a reset asks for together with the
trials the next resets are expected to ask for, and serves each of those later resets from its
row of the block (:meth:`aerodock.mission.settle.SettledStart.take_rows`: copies, a few
milliseconds). A trial's settled start does not depend on the batch that settled it (per-trial
random streams, row-wise arithmetic; tested bit for bit in ``tests/integration/
test_settled_start.py``), so a served episode is exactly the one a reset of that trial alone
flies.

Which trials come next is known in advance (:meth:`aerodock.envs.docking.DockingEnv.reset`):
``reset()`` draws the next trial index from the environment's ``np_random``, so the draws of a
copy of it are the trials of the next resets without a seed; after ``reset(seed=k)`` (or
``options={"trial": k}``) the block also holds ``k + 1, k + 2, ...`` (an evaluation loop over
consecutive seeds), alternating with those draws. A reset asking for a trial outside the block
(another seed, or draws made from ``np_random`` by someone else) settles a new block.

No block is settled (each reset settles its own trial, as before) when the world cannot be split
(a plug-in downwash field without ``take_rows``) or with a learnt model as the feed-forward
(``compensation="model"``): its matrix products round differently with the batch's shape, so a
trial settled in a block would differ from the trial settled alone in the last bits.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import replace

import numpy as np

from aerodock.config import Config
from aerodock.control.compensation import AccelPredictor, Compensation
from aerodock.downwash import build_field
from aerodock.mission import MissionSpec, SettledStart, settle_trials

DEFAULT_BLOCK_TRIALS = 32
"""Trials settled together when a reset asks for one outside the current block."""

MAX_BLOCK_TRIALS = 1024
"""Largest block a :class:`StartCache` accepts (its memory grows with it: about 40 kB a trial)."""


class StartCache:
    """The settled starts of one environment's episodes, a block at a time (module docstring).

    Args:
        cfg: the environment's configuration.
        spec: its mission (``trials`` and ``first_trial`` are ignored).
        predictor: its feed-forward model (``compensation="model"``).
        block_trials: trials settled together on a miss (1: each reset settles its own trial).
    """

    def __init__(self, cfg: Config, spec: MissionSpec, predictor: AccelPredictor | None,
                 block_trials: int = DEFAULT_BLOCK_TRIALS):
        if (isinstance(block_trials, bool) or not isinstance(block_trials, int | np.integer)
                or not 1 <= block_trials <= MAX_BLOCK_TRIALS):
            raise ValueError(f"settle_block must be an integer from 1 to {MAX_BLOCK_TRIALS}, "
                             f"got {block_trials!r}")
        self.cfg, self.spec, self.predictor = cfg, spec, predictor
        self.block_trials = int(block_trials)
        self._splits: bool | None = None  # known at the first miss
        self._block: SettledStart | None = None
        self._rows: dict[int, int] = {}  # trial index -> row of the block
        self.blocks = 0  # blocks settled so far
        self.served = 0  # resets served from a block settled by an earlier reset

    @property
    def enabled(self) -> bool:
        """Whether misses settle blocks (a splittable world, no learnt feed-forward)."""
        if self._splits is None:
            self._splits = (self.block_trials > 1
                            and Compensation(self.spec.compensation) != Compensation.MODEL
                            and hasattr(build_field(self.cfg), "take_rows"))
        return self._splits

    def take(self, trial: int, upcoming: Callable[[int], list[int]]) -> SettledStart | None:
        """The settled start of ``trial`` (a batch of one), or None when blocks are off (the
        mission then settles the trial itself).

        Args:
            trial: the trial index the reset asks for.
            upcoming: ``upcoming(k)``: up to ``k`` trial indices the next resets are expected to
                ask for, most likely first; called on a miss only.
        """
        if not self.enabled:
            return None
        row = self._rows.get(trial)
        if row is None:
            trials = [trial]
            for t in upcoming(self.block_trials - 1):
                if len(trials) == self.block_trials:
                    break
                if t not in trials and t >= 0:
                    trials.append(int(t))
            ids = np.array(trials, dtype=np.int64)
            self._block = settle_trials(self.cfg, replace(self.spec, trials=ids.size,
                                                          first_trial=0),
                                        self.predictor, trials=ids)
            self._rows = {t: i for i, t in enumerate(trials)}
            self.blocks += 1
            row = 0
        else:
            self.served += 1
        return self._block.take_rows(np.array([row]))
