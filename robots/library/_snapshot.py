"""A sensor snapshot: what a trainee records at a place (Jennings et al., section 5)."""

from __future__ import annotations

from typing import Any

from robots._robot import Robot


def snapshot(robot: Robot) -> dict[str, Any]:
    """Sonar ranges, camera sightings and odometry of the last tick, as plain data."""
    hw = robot.hw
    return {
        "t": hw.clock.now(),
        "odometry": list(hw.odometry.pose()),
        "sonar": list(hw.sonar.ranges()) if hw.sonar is not None else None,
        "camera": [
            {"kind": s.kind, "id": s.id, "status": s.status, "range": s.range, "bearing": s.bearing}
            for s in (hw.camera.sightings() if hw.camera is not None else ())
        ],
        "bumper": hw.bumper.side() if hw.bumper is not None else None,
    }
