"""An outsider: a process with the wrong key (or another team's) that tries to use a team.

``python -m tests.helpers.outsider TARGET``: calls TARGET's procedures and injects a broadcast,
prints what happened, then ``DONE``.
"""

from __future__ import annotations

import asyncio
import sys

from mover import Node, NodeConfig, Refused, TeamCredentials, UnknownRobot


async def main(target: str) -> None:
    team = TeamCredentials.from_env()
    async with Node("outsider", team, config=NodeConfig.from_env()) as node:
        await asyncio.sleep(0.5)  # let the links come up
        for procedure in ("bump", "add"):
            try:
                result = await node.call(target, procedure, 1, 2, timeout=3)
                print("UNEXPECTED result", result, flush=True)
            except (Refused, UnknownRobot) as exc:
                print("refused:", type(exc).__name__, exc, flush=True)
        # A broadcast on the team's key (mover/alpha/...), signed with the wrong key.
        node._sealer.team = "alpha"
        await node.broadcast("chatter", "forged", range=None)
        await asyncio.sleep(0.3)
    print("DONE", flush=True)


if __name__ == "__main__":
    asyncio.run(main(sys.argv[1]))
