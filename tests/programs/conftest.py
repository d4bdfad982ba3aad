"""Quiet robot processes: their INFO lines would flood the test output."""

from __future__ import annotations

import pytest


@pytest.fixture(autouse=True)
def _quiet_processes(monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setenv("MOVER_LOG_LEVEL", "WARNING")
