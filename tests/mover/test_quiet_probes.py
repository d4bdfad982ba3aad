"""`mover ps` asks every member for ``mover.status``; a member that hosts no programs (the
world) answers UnknownProcedure without a warning in its log (issue 28), while any other
unknown procedure is still logged as a warning."""

from __future__ import annotations

import logging

import pytest

from mover import Node, UnknownProcedure


async def test_a_status_probe_of_a_member_without_programs_is_not_a_warning(
    nodes: list[Node], caplog: pytest.LogCaptureFixture
) -> None:
    caller, callee = nodes[1], nodes[2]
    with caplog.at_level(logging.DEBUG, logger="mover.rpc"):
        for name in ("mover.status", "no_such_thing"):
            with pytest.raises(UnknownProcedure):
                await caller.call(callee.name, name, timeout=5.0)
    said = {
        r.getMessage().rsplit(" ", 1)[-1]: r.levelno
        for r in caplog.records
        if "unknown" in r.getMessage()
    }
    assert said == {"'mover.status'": logging.DEBUG, "'no_such_thing'": logging.WARNING}
