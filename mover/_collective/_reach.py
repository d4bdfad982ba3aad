"""Waiting out a lost link: whether a member that did not answer is gone or only cut off; and
waiting for a member to be lost while this node stays linked (:func:`wait_lost`).

Both sides of a step and the program host ask :func:`wait_reachable` after a call was not
delivered; it polls (zenoh offers no event for "links back"), at most every 50 ms, only while a
call has failed. :func:`wait_lost` follows the membership's events: it costs nothing while the
team stays whole.
"""

from __future__ import annotations

import asyncio
import logging
import time
from collections.abc import AsyncGenerator, Iterable, Sequence
from typing import TYPE_CHECKING

from ._step import LOST_GRACE

if TYPE_CHECKING:
    from .._node import Node

log = logging.getLogger("mover.tasks")


class Retry(Exception):
    """A collective's call was not delivered: recover, then ask (the new designated) again."""


async def wait_reachable(
    node: Node, member: str | Sequence[str], stall_timeout: float = 60.0
) -> bool:
    """After a failed call to ``member``: wait out an outage; True if it is a member again.

    A member gone while this node is linked to others is gone (False at once). If this node
    has lost every link, wait up to ``stall_timeout`` for the links, then a moment for
    ``member`` (or every one of several) to be seen again.
    """
    wanted = {member} if isinstance(member, str) else set(member)
    grace = time.monotonic() + 0.5
    while node.connected():
        # A failed call and a lost link can be seen in either order: wait a moment to tell a
        # member that is gone (we stay linked) from an outage (our links go too).
        if wanted <= node.membership.members():
            return True
        if time.monotonic() > grace:
            return False
        await asyncio.sleep(0.02)
    log.warning("%s: links lost: stalling", node.name)
    deadline = time.monotonic() + stall_timeout
    while not node.connected():  # zenoh offers no event for this: poll
        if time.monotonic() > deadline:
            return False
        await asyncio.sleep(0.05)
    settle = time.monotonic() + 2.0
    while not wanted <= node.membership.members() and time.monotonic() < settle:  # noqa: ASYNC110
        await asyncio.sleep(0.05)
    back = wanted <= node.membership.members()
    log.info("%s: links back; %s %s", node.name, sorted(wanted), "back" if back else "gone")
    return back


async def wait_lost(
    node: Node, members: Iterable[str], grace: float = LOST_GRACE
) -> frozenset[str]:
    """Once one or more of ``members`` (this node's own name aside) have been gone for
    ``grace`` seconds while this node is linked, as the designated member counts a loss: who.

    A member gone already when this is called counts from the call. While this node is cut
    off from every other, nobody is lost (it stalls, as the steps do)."""
    others = frozenset(members) - {node.name}
    changes = node.membership.events()
    try:
        while True:
            missing = {m for m in others if m not in node.membership}
            if missing and node.connected():
                await asyncio.sleep(grace)
                lost = frozenset(m for m in missing if m not in node.membership)
                if lost and node.connected():
                    return lost
            else:
                await anext(changes)  # (registered as it first waits: no change is missed)
    finally:
        if isinstance(changes, AsyncGenerator):
            await changes.aclose()
