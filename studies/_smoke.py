"""The studies' ``--smoke`` size: each study's smallest run that crosses every step it takes.

``--smoke`` is for checking that a study still runs (``tests/studies/test_studies.py`` runs every
script with it); it measures nothing worth reading. A mission study flies :data:`SMOKE_TRIALS`
trials a campaign with the mission's waiting times cut (``reproduce --smoke``'s
:data:`~aerodock.experiments.reproduce.SHORT_MISSION`) and fewer cells; a learning study trains
for a few epochs on one or two seeds. Without ``--smoke`` a study computes what it always did.
"""

from __future__ import annotations

import argparse

from aerodock.config import Config
from aerodock.experiments.reproduce import SHORT_MISSION, SMOKE

SMOKE_TRIALS = 2
"""Trials a campaign under ``--smoke``."""
SMOKE_EPOCHS = 3
"""Training epochs under ``--smoke``."""
SMOKE_CURRICULUM = SMOKE.curriculum
"""``reproduce --smoke``'s curriculum: two paper stages and one deep stage of two flights each."""


def add_smoke_option(parser: argparse.ArgumentParser) -> None:
    """Give ``parser`` the ``--smoke`` flag."""
    parser.add_argument("--smoke", action="store_true",
                        help="the smallest run that crosses every step (seconds): checks that "
                             "the study runs, measures nothing")


def smoke_config(cfg: Config) -> Config:
    """``cfg`` with the mission's waiting times cut (:data:`SHORT_MISSION`)."""
    return cfg.with_overrides(SHORT_MISSION, source=f"{cfg.source} + --smoke")
