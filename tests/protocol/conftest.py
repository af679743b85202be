"""Fixtures of the plug-in protocol suite (helpers live in ``protocol_helpers``)."""

from __future__ import annotations

from pathlib import Path

import pytest
from protocol_helpers import FIELDS, write_config


@pytest.fixture(scope="session")
def field_configs(tmp_path_factory) -> dict[str, Path]:
    folder = tmp_path_factory.mktemp("protocol-configs")
    return {name: write_config(folder, name) for name in FIELDS}


@pytest.fixture(scope="session")
def collect_configs(tmp_path_factory) -> dict[str, Path]:
    """The same configs with the one paper stage as their curriculum (``collect``'s test)."""
    folder = tmp_path_factory.mktemp("protocol-collect-configs")
    return {name: write_config(folder, name, deep=False) for name in FIELDS}
