"""A grid world's run recorded as MCAP with ROS 2 messages, one snapshot a recorded round
(``mover gridworld FILE --record run.mcap``).

Topics (frame ``world``, one metre a cell, x along columns and y along rows from the grid's
corner, so that a robot at row r, column c is at (c + 0.5, r + 0.5) as its own ``loc`` says;
round k is stamped k seconds, a grid world having no time of its own):

* ``/grid/cells`` ``nav_msgs/OccupancyGrid`` — obstacles 100, free cells 0;
* ``/grid/floor`` ``nav_msgs/OccupancyGrid`` — the floor values: unmarked -1 (unknown), the
  others clipped to 0..100 (a viewer's colour scale);
* ``/grid/frame`` ``std_msgs/String`` — the exact state as JSON, what ``view.frame`` answers
  (round, robots' cells, floor values, colours, resources, cells seen): ``mover replay`` plays it;
* ``/ROBOT/pose`` ``geometry_msgs/PoseStamped`` and ``/tf`` — each robot at its cell's centre.

The file's ``mover`` metadata holds the seed and the scene (``view.scene``'s answer).
"""

from __future__ import annotations

import json
from collections.abc import Mapping
from pathlib import Path
from typing import TYPE_CHECKING, Any

from sim_hw.continuous._mcap import FRAME, McapFile, pose_msg, stamp, transform
from sim_hw.view._scene import grid_header, grid_state

if TYPE_CHECKING:
    from sim_hw.grid._server import GridServer

SECONDS_PER_ROUND = 1.0
"""The stamp of round k is k times this."""


def occupancy(values: list[int], shape: tuple[int, int], head: Mapping[str, Any]) -> dict[str, Any]:
    """A ``nav_msgs/OccupancyGrid`` of ``values`` (row-major, already -1..100) over ``shape``."""
    h, w = shape
    return {
        "header": head,
        "info": {
            "map_load_time": head["stamp"],
            "resolution": 1.0,
            "width": w,
            "height": h,
            "origin": pose_msg((0.0, 0.0, 0.0)),
        },
        "data": values,
    }


class GridMcapSink:
    """Writes ``server``'s grid run to ``path``: the scene as metadata, then a snapshot each
    time it is called (a hook on the door's ``on_tick``) at every ``every``-th round, and one
    at :meth:`close` if the last round was not written."""

    def __init__(self, path: str | Path, server: GridServer, *, seed: int = 0, every: int = 1):
        self.server, self.every = server, max(1, every)
        self._file = McapFile(path)
        stepper = server.stepper
        self._shape = (stepper.grid.height, stepper.grid.width)
        self._cells = [100 if o else 0 for o in stepper.grid.obstacles.ravel().tolist()]
        self._file.metadata({**grid_header(stepper), "seed": seed})
        self._last: int | None = None
        self.snapshot()

    def __call__(self, _commands: object = None) -> None:
        if self.server.round % self.every == 0:
            self.snapshot()

    def snapshot(self) -> None:
        """Write the grid as it is now (once a round)."""
        stepper = self.server.stepper
        if self._last == stepper.round:
            return
        self._last = stepper.round
        frame = grid_state(stepper)
        t = stepper.round * SECONDS_PER_ROUND
        frame["t"] = t
        head = {"stamp": stamp(t), "frame_id": FRAME}
        put = self._file.put
        put("/grid/cells", "nav_msgs/OccupancyGrid", occupancy(self._cells, self._shape, head), t)
        floor = [-1 if v < 0 else min(v, 100) for v in frame["marks"]]
        put("/grid/floor", "nav_msgs/OccupancyGrid", occupancy(floor, self._shape, head), t)
        put("/grid/frame", "std_msgs/String", {"data": json.dumps(frame)}, t)
        tf = []
        for rid, (r, c) in frame["robots"].items():
            p = (c + 0.5, r + 0.5, 0.0)
            put(
                f"/{rid}/pose",
                "geometry_msgs/PoseStamped",
                {"header": head, "pose": pose_msg(p)},
                t,
            )
            tf.append(transform(rid, head, p))
        if tf:
            put("/tf", "tf2_msgs/TFMessage", {"transforms": tf}, t)

    def close(self) -> None:
        """Write the last round if it was not, end the file and close it."""
        try:
            self.snapshot()
        finally:
            self._file.close()
