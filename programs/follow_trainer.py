"""Follow the trainer (Jennings et al., section 5): a robot that knows some places leads a
trainee to each of them; at each place the trainee records a sensor snapshot, for training
its own recogniser later. The result is a dataset file of JSON lines, one per place.

Every member runs this program; ``trainer`` names the robot that knows the places. For each
place: ``distributed_or`` — the trainer drives there while the trainees follow it, and the
step ends when the trainer arrives (the followers are stopped); then ``distributed_and`` — the
trainees record, and the trainer waits for them before leading on.
"""

from __future__ import annotations

import json
from functools import partial
from pathlib import Path
from typing import Any

from mover import RunTeam
from robots import Robot
from robots.library import follow, goto_point, snapshot


async def follow_trainer(
    robot: Robot,
    team: RunTeam,
    trainer: str,
    places: dict[str, list[float]] | None = None,
    dataset: str = "trainee.jsonl",
) -> dict[str, Any]:
    """Lead (trainer) or follow and record (trainees) at every labelled place (section 5).

    ``places`` (label → [x, y] in the trainer's odometry frame) is read on the trainer only;
    it tells the others the labels. Each trainee appends ``{"label", "trainee", "snapshot"}``
    lines to ``dataset``. Returns the labels and how many snapshots this robot recorded.
    """
    lead = team.me == trainer
    shared = await team.distributed_and(lambda: _labels(list(places or {}) if lead else []))
    records = 0
    for label in shared[trainer]:
        await team.report("leading" if lead else "following", place=label)
        if lead:
            x, y = (places or {})[label]
            await team.distributed_or(partial(goto_point, robot, (x, y), speed=0.25))
        else:
            await team.distributed_or(partial(follow, robot, trainer))
        if not lead:
            _record(dataset, label, team.me, snapshot(robot))
            records += 1
        await team.distributed_and(_nothing)  # the trainer leads on once all recorded
    return {"places": shared[trainer], "records": records}


def _record(dataset: str, label: str, trainee: str, shot: dict[str, Any]) -> None:
    with Path(dataset).open("a") as out:
        out.write(json.dumps({"label": label, "trainee": trainee, "snapshot": shot}) + "\n")


async def _labels(labels: list[str]) -> list[str]:
    return labels


async def _nothing() -> None:
    return None
