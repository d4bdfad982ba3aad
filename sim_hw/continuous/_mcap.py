"""A recording as MCAP with ROS 2 messages (CDR), the format rosbag2, Foxglove, Lichtblick,
PlotJuggler and rerun open; written from the same header and tick records as JSON lines.

Topics (frame ``world``; stamps and log times in simulated time, t = 0 at the run's start):

* ``/ROBOT/pose`` ``geometry_msgs/msg/PoseStamped`` — the true pose, one a recorded tick;
* ``/ROBOT/odom_pose`` ``geometry_msgs/msg/PoseStamped`` — the odometry pose (live recordings);
* ``/tf`` ``tf2_msgs/msg/TFMessage`` — one transform ``world`` → ``ROBOT`` per robot a tick;
* ``/ROBOT/cmd_vel`` ``geometry_msgs/msg/TwistStamped`` — the drive command in force;
* ``/ROBOT/sonar`` ``sensor_msgs/msg/LaserScan`` — the sonar rays (live recordings);
* ``/ROBOT/led`` ``std_msgs/msg/String`` — the LED, whenever it changes;
* ``/ROBOT/phase`` ``std_msgs/msg/String`` — the phase its program reported, at the first
  recorded tick after the world heard it (live recordings, ``sim_hw.continuous._phases``);
* ``/boxes/BOX/pose`` ``geometry_msgs/msg/PoseStamped`` — each box's pose;
* ``/arena`` ``visualization_msgs/msg/MarkerArray`` — walls, obstacles and immovables, once.

The arena is a MarkerArray rather than Foxglove's scene schema because it is a ROS 2 message
like the rest: one encoding (CDR) in the file, read by rosbags and the ROS 2 tools as well as
by Foxglove and Lichtblick. The run's seed and scene are the file's ``mover`` metadata.
"""

from __future__ import annotations

import json
import math
from collections.abc import Mapping
from pathlib import Path
from typing import Any

from ._contract import TICK
from ._ros2_msgs import msgdef

FRAME = "world"
_CUBE, _CYLINDER, _LINE_STRIP, _LINE_LIST = 1, 3, 4, 5
_GREY = {"r": 0.5, "g": 0.5, "b": 0.5, "a": 1.0}


def _need() -> Any:
    try:
        from mcap_ros2.writer import Writer
    except ImportError:
        from mover.cli import UsageError

        raise UsageError("writing .mcap needs the mcap extra: pip install 'mover[mcap]'") from None
    return Writer


def stamp(t: float) -> dict[str, int]:
    """A ``builtin_interfaces/Time`` of ``t`` seconds (whole nanoseconds)."""
    ns = round(t * 1e9)
    return {"sec": ns // 1_000_000_000, "nanosec": ns % 1_000_000_000}


def _quat(theta: float) -> dict[str, float]:
    return {"x": 0.0, "y": 0.0, "z": math.sin(theta / 2), "w": math.cos(theta / 2)}


def pose_msg(p: Any) -> dict[str, Any]:
    """A ``geometry_msgs/Pose`` in the plane from ``(x, y, theta, ...)``."""
    return {"position": {"x": p[0], "y": p[1], "z": 0.0}, "orientation": _quat(p[2])}


def _point(x: float, y: float) -> dict[str, float]:
    return {"x": float(x), "y": float(y), "z": 0.0}


class McapFile:
    """An MCAP file of ROS 2 messages being written: each message type's schema registered on
    first use, log and publish times in simulated seconds, and mover's metadata record. The
    continuous world's :class:`McapSink` and the grid world's
    (:class:`sim_hw.grid._mcap.GridMcapSink`) write through it."""

    def __init__(self, path: str | Path) -> None:
        writer_class = _need()
        self._file = Path(path).open("wb")  # noqa: SIM115 (closed by close())
        self._writer = writer_class(self._file)
        self._schemas: dict[str, Any] = {}

    def put(self, topic: str, kind: str, message: Mapping[str, Any], t: float) -> None:
        """Write ``message`` of type ``kind`` (``pkg/Type``) on ``topic`` at ``t`` s."""
        schema = self._schemas.get(kind)
        if schema is None:
            schema = self._schemas[kind] = self._writer.register_msgdef(*msgdef(kind))
        ns = round(t * 1e9)
        self._writer.write_message(topic, schema, message, log_time=ns, publish_time=ns)

    def metadata(self, header: Mapping[str, Any]) -> None:
        """The ``mover`` metadata record: the seed, the name and the whole ``header``."""
        meta = {"seed": str(header.get("seed")), "name": str(header.get("name", ""))}
        meta["header"] = json.dumps(header, separators=(",", ":"))
        self._writer._writer.add_metadata("mover", meta)  # mcap_ros2 keeps the raw writer there

    def close(self) -> None:
        """End the file (its summary and index) and close it."""
        if not self._file.closed:
            self._writer.finish()
            self._file.close()


def transform(rid: str, head: Mapping[str, Any], p: Any) -> dict[str, Any]:
    """A ``geometry_msgs/TransformStamped`` from the world's frame to ``rid`` at pose ``p``."""
    return {
        "header": head,
        "child_frame_id": rid,
        "transform": {"translation": _point(p[0], p[1]), "rotation": _quat(p[2])},
    }


class McapSink(McapFile):
    """Writes the header and tick records of :class:`~sim_hw.continuous.Recorder` as ROS 2
    messages to ``path`` (a tick's optional ``sensors``: per robot ``sonar``, ``angles``,
    ``range_max``, ``odom``)."""

    sensors = True  # the Recorder adds the robots' sensor readings to a tick
    phases = True  # and the program phases heard since the last tick (each member's, in order)

    def __init__(self, path: str | Path) -> None:
        super().__init__(path)
        self._twist: dict[str, tuple[float, float]] = {}
        self._led: dict[str, str] = {}

    def _put(self, topic: str, kind: str, message: Mapping[str, Any], t: float) -> None:
        self.put(topic, kind, message, t)

    def write(self, record: Mapping[str, Any]) -> None:
        """Write one record: the header (metadata and the arena) or a tick."""
        if record.get("type") == "header":
            self._header(record)
        else:
            self._tick(record)

    def _header(self, header: Mapping[str, Any]) -> None:
        self.metadata(header)
        markers = arena_markers(header)
        self._put("/arena", "visualization_msgs/MarkerArray", {"markers": markers}, 0.0)

    def _tick(self, tick: Mapping[str, Any]) -> None:
        t = float(tick.get("t", 0.0))
        head = {"stamp": stamp(t), "frame_id": FRAME}
        for rid, cmd in tick.get("commands", {}).items():
            v, w = self._twist.get(rid, (0.0, 0.0))
            self._twist[rid] = (float(cmd.get("v", v)), float(cmd.get("w", w)))
        sensors = tick.get("sensors", {})
        tf = []
        for rid, p in tick.get("robots", {}).items():
            self._put(
                f"/{rid}/pose",
                "geometry_msgs/PoseStamped",
                {"header": head, "pose": pose_msg(p)},
                t,
            )
            tf.append(transform(rid, head, p))
            v, w = self._twist.get(rid, (0.0, 0.0))
            twist = {
                "linear": {"x": v, "y": 0.0, "z": 0.0},
                "angular": {"x": 0.0, "y": 0.0, "z": w},
            }
            self._put(
                f"/{rid}/cmd_vel", "geometry_msgs/TwistStamped", {"header": head, "twist": twist}, t
            )
            led = str(p[3]) if len(p) > 3 else ""
            if self._led.get(rid) != led:
                self._led[rid] = led
                self._put(f"/{rid}/led", "std_msgs/String", {"data": led}, t)
            if rid in sensors:
                self._sensors(rid, sensors[rid], head, t)
        if tf:
            self._put("/tf", "tf2_msgs/TFMessage", {"transforms": tf}, t)
        for member, heard in tick.get("phases", {}).items():
            for phase in heard if isinstance(heard, list) else [heard]:
                self._put(f"/{member}/phase", "std_msgs/String", {"data": str(phase)}, t)
        for bid, p in tick.get("boxes", {}).items():
            self._put(
                f"/boxes/{bid}/pose",
                "geometry_msgs/PoseStamped",
                {"header": head, "pose": pose_msg(p)},
                t,
            )

    def _sensors(self, rid: str, got: Mapping[str, Any], head: Mapping[str, Any], t: float) -> None:
        if got.get("odom"):
            odom = {"header": head, "pose": pose_msg(got["odom"])}
            self._put(f"/{rid}/odom_pose", "geometry_msgs/PoseStamped", odom, t)
        ranges, angles = got.get("sonar"), list(got.get("angles") or ())
        if ranges and len(angles) == len(ranges):
            step = (angles[-1] - angles[0]) / (len(angles) - 1) if len(angles) > 1 else 0.0
            scan = {
                "header": {**head, "frame_id": rid},
                "angle_min": angles[0],
                "angle_max": angles[-1],
                "angle_increment": step,
                "time_increment": 0.0,
                "scan_time": 0.0,
                "range_min": 0.0,
                "range_max": float(got.get("range_max", max(ranges))),
                "ranges": [float(r) for r in ranges],
                "intensities": [],
            }
            self._put(f"/{rid}/sonar", "sensor_msgs/LaserScan", scan, t)


def arena_markers(header: Mapping[str, Any]) -> list[dict[str, Any]]:
    """The arena's walls, obstacles and immovables as Humble ``visualization_msgs/Marker``s."""
    w, h = header.get("size", (0.0, 0.0))
    out: list[dict[str, Any]] = []

    def marker(ns: str, kind: int, pose: Any, scale: tuple[float, float, float], **kw: Any) -> None:
        out.append(
            {
                "header": {"stamp": stamp(0.0), "frame_id": FRAME},
                "ns": ns,
                "id": len(out),
                "type": kind,
                "action": 0,
                "pose": pose_msg(pose),
                "scale": dict(zip("xyz", scale, strict=True)),
                "color": _GREY,
                "lifetime": {"sec": 0, "nanosec": 0},
                "frame_locked": False,
                "points": kw.get("points", []),
                "colors": [],
                "text": kw.get("text", ""),
                "mesh_resource": "",
                "mesh_use_embedded_materials": False,
            }
        )

    walls = [_point(0, 0), _point(w, 0), _point(w, h), _point(0, h), _point(0, 0)]
    marker("walls", _LINE_STRIP, (0.0, 0.0, 0.0), (0.02, 0.0, 0.0), points=walls)
    for o in [*header.get("obstacles", []), *header.get("immovables", [])]:
        shape, (cx, cy) = o.get("shape", "box"), o.get("center", (0.0, 0.0))
        ns = "immovables" if "id" in o else "obstacles"
        if shape == "circle":
            d = 2 * float(o.get("radius", 0.0))
            marker(ns, _CYLINDER, (cx, cy, 0.0), (d, d, 0.2), text=o.get("id", ""))
        elif shape == "segment":
            ends = [_point(*o["a"]), _point(*o["b"])]
            marker(ns, _LINE_LIST, (0.0, 0.0, 0.0), (0.02, 0.0, 0.0), points=ends)
        else:
            sx, sy = o.get("size", (0.0, 0.0))
            angle = float(o.get("angle", 0.0))
            marker(ns, _CUBE, (cx, cy, angle), (sx, sy, 0.2), text=o.get("id", ""))
    return out


def export(src: str | Path, out: str | Path) -> int:
    """Write the JSON-lines recording ``src`` as MCAP to ``out``; the ticks written."""
    from ._record import read_recording

    if Path(src).suffix == ".mcap":
        raise ValueError(f"{src} is MCAP already")
    header, ticks = read_recording(src)
    sink = McapSink(out)
    try:
        sink.write(header)
        for tick in ticks:
            sink.write(tick)
    finally:
        sink.close()
    return len(ticks)


def recording_kind(path: str | Path) -> str:
    """``grid`` or ``continuous``: which world's recording the MCAP file ``path`` is."""
    _need()
    from mcap.reader import make_reader

    with Path(path).open("rb") as f:
        for m in make_reader(f).iter_metadata():
            if m.name == "mover":
                return str(json.loads(m.metadata["header"]).get("kind", "continuous"))
    raise ValueError(f"{path}: no mover metadata: not a recording of mover's")


def read_mcap(path: str | Path) -> tuple[dict[str, Any], list[dict[str, Any]]]:
    """The header and tick records of an MCAP recording made by mover (what
    :func:`~sim_hw.continuous.read_recording` gives for JSON lines): the scene from the
    metadata, the true poses of robots (with their LED) and boxes; commands are not read back.
    A grid world's recording (:mod:`sim_hw.grid._mcap`) gives its scene and its frames."""
    _need()
    from mcap.reader import make_reader
    from mcap_ros2.decoder import DecoderFactory

    with Path(path).open("rb") as f:
        reader = make_reader(f, decoder_factories=[DecoderFactory()])
        header = next((m.metadata for m in reader.iter_metadata() if m.name == "mover"), None)
        if header is None:
            raise ValueError(f"{path}: no mover metadata: not a recording of mover's")
        scene: dict[str, Any] = json.loads(header["header"])
        if scene.get("kind") == "grid":  # sim_hw.grid._mcap: the frames as written
            frames = reader.iter_decoded_messages(topics=["/grid/frame"], log_time_order=True)
            return scene, [{"type": "tick", **json.loads(m.data)} for *_, m in frames]
        by_t: dict[int, dict[str, Any]] = {}
        led: dict[str, str] = {}
        for _, channel, message, msg in reader.iter_decoded_messages(log_time_order=True):
            parts = channel.topic.strip("/").split("/")
            if parts[-1] not in ("pose", "led") or len(parts) > 3:
                continue
            tick = by_t.setdefault(message.log_time, {"type": "tick", "robots": {}, "boxes": {}})
            if parts[-1] == "led":
                tick.setdefault("leds", {})[parts[0]] = msg.data
                continue
            q = msg.pose.orientation
            pose = [msg.pose.position.x, msg.pose.position.y, 2 * math.atan2(q.z, q.w)]
            if parts[0] == "boxes":
                tick["boxes"][parts[1]] = pose
            else:
                tick["robots"][parts[0]] = pose
    ticks = []
    for ns, tick in sorted(by_t.items()):
        led.update(tick.pop("leds", {}))
        for rid, pose in tick["robots"].items():
            pose.append(led.get(rid, ""))
        tick.update(t=ns / 1e9, tick=round(ns / 1e9 / TICK), marked={}, commands={})
        ticks.append(tick)
    return scene, ticks
