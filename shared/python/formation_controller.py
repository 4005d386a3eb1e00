"""Write a formation controller in Python: one class, one method.

The agent process starts your program and talks to it over its standard input and
output, one JSON object a line (the protocol, ``docs/controllers.md``). This module
speaks that protocol for you: subclass :class:`Controller`, write :meth:`Controller.turn`
(the turn in, the move out) and call :func:`serve`::

    from formation_controller import Controller, Move, serve

    class GoToSlot(Controller):
        name = "go-to-slot"

        def turn(self, turn):
            return Move([turn.slot_position_m(self.me)])

    if __name__ == "__main__":
        serve(GoToSlot())

Standard library only: use it from a checkout with ``PYTHONPATH=shared/python`` or
install it with ``pip install shared/python``. Points are ``(x, y)`` tuples in metres,
angles radians anticlockwise from the x axis, time counted in steps.
"""

from __future__ import annotations

import json
import math
import sys
from dataclasses import dataclass, field
from typing import BinaryIO, Iterable, Iterator, List, Optional, Sequence, Tuple

__all__ = [
    "PROTOCOL_VERSION",
    "XY",
    "Circle",
    "Pose",
    "Kinematics",
    "AgentInfo",
    "Mission",
    "Mate",
    "Velocities",
    "Turn",
    "Move",
    "Controller",
    "ProtocolError",
    "serve",
    "replay",
]

#: The protocol version this module speaks.
PROTOCOL_VERSION = 1

#: A point or a vector, metres: ``(x, y)``.
XY = Tuple[float, float]


class ProtocolError(Exception):
    """The agent sent something this module cannot read (a bug, or another version)."""


def _xy(value) -> XY:
    return (float(value[0]), float(value[1]))


@dataclass(frozen=True)
class Circle:
    """A disk: an obstacle or another agent's body."""

    centre_m: XY
    radius_m: float

    @staticmethod
    def _of(d: dict) -> "Circle":
        return Circle(_xy(d["centre_m"]), float(d["radius_m"]))


@dataclass(frozen=True)
class Pose:
    """Where, and which way it faces."""

    position_m: XY
    heading_rad: float

    @staticmethod
    def _of(d: dict) -> "Pose":
        return Pose(_xy(d["position_m"]), float(d["heading_rad"]))


@dataclass(frozen=True)
class Kinematics:
    """How an agent can move: ``model`` is ``holonomic`` (any polyline), ``unicycle``
    (turns in place at most ``max_turn_rad`` a step, drives along its heading) or ``car``
    (bends no tighter than ``turning_radius_m``)."""

    model: str
    max_turn_rad: Optional[float] = None
    turning_radius_m: Optional[float] = None
    reverse: bool = False

    @staticmethod
    def _of(d: dict) -> "Kinematics":
        return Kinematics(
            d["model"],
            d.get("max_turn_rad"),
            d.get("turning_radius_m"),
            bool(d.get("reverse", False)),
        )


@dataclass(frozen=True)
class AgentInfo:
    """One agent of the formation: its slot (polar, from the centre and its heading), its
    body, its top speed (metres a step, ``None``: no limit), its sensing radius
    (``None``: it knows every body) and its kinematics."""

    slot_r_m: float
    slot_theta_rad: float
    radius_m: float
    max_step_m: Optional[float]
    sensing_radius_m: Optional[float]
    kinematics: Kinematics

    @staticmethod
    def _of(d: dict) -> "AgentInfo":
        return AgentInfo(
            float(d["slot_r_m"]),
            float(d["slot_theta_rad"]),
            float(d["radius_m"]),
            d.get("max_step_m"),
            d.get("sensing_radius_m"),
            Kinematics._of(d["kinematics"]),
        )


@dataclass(frozen=True)
class Mission:
    """What stays the same for the whole run: the field ``[0, w] x [0, h]``, the static
    obstacles (disks and polygons, a map's blocked cells among the polygons), every agent
    in agent order, and how they take turns (``sequential``, ``parallel`` or
    ``simultaneous``)."""

    field_m: XY
    obstacles: List[Circle]
    polygons_m: List[List[XY]]
    agents: List[AgentInfo]
    turns: str

    @staticmethod
    def _of(d: dict) -> "Mission":
        return Mission(
            _xy(d["field_m"]),
            [Circle._of(o) for o in d["obstacles"]],
            [[_xy(p) for p in poly] for poly in d["polygons_m"]],
            [AgentInfo._of(a) for a in d["agents"]],
            d["turns"],
        )


@dataclass(frozen=True)
class Mate:
    """Another agent: its index, where it stands, and whether it still belongs to the
    formation (``False``: frozen where it stopped, an obstacle)."""

    index: int
    position_m: XY
    alive: bool


@dataclass(frozen=True)
class Velocities:
    """How the bodies moved over the last step, metres a step (when every agent moves at
    once): this agent's, and each other body's in the order of ``Turn.others``."""

    me_m_per_step: XY
    others_m_per_step: List[XY]


@dataclass(frozen=True)
class Turn:
    """One turn: the step, the formation centre's pose and its next poses (``ahead``,
    the pose of ``step + 1`` first), where this agent stands and faces (``None`` for a
    holonomic agent), the other agents' bodies (which stand still while it moves), the
    other agents by index, the moving obstacles where they stand this step, and the
    velocities when every agent moves at once."""

    step: int
    centre: Pose
    ahead: List[Pose]
    position_m: XY
    heading_rad: Optional[float]
    others: List[Circle]
    mates: List[Mate]
    moving: List[Circle]
    velocities: Optional[Velocities]

    @staticmethod
    def _of(d: dict) -> "Turn":
        v = d.get("velocities")
        return Turn(
            int(d["step"]),
            Pose._of(d["centre"]),
            [Pose._of(p) for p in d["ahead"]],
            _xy(d["position_m"]),
            d.get("heading_rad"),
            [Circle._of(o) for o in d["others"]],
            [Mate(int(m["index"]), _xy(m["position_m"]), bool(m["alive"])) for m in d["mates"]],
            [Circle._of(o) for o in d["moving"]],
            None
            if v is None
            else Velocities(_xy(v["me_m_per_step"]), [_xy(o) for o in v["others_m_per_step"]]),
        )

    def slot_position_m(self, agent: AgentInfo, centre: Optional[Pose] = None) -> XY:
        """Where ``agent``'s slot is with the centre at ``centre`` (this turn's when
        ``None``): the paper's ideal position, the slot turned by the centre's heading."""
        c = self.centre if centre is None else centre
        angle = c.heading_rad + agent.slot_theta_rad
        return (
            c.position_m[0] + agent.slot_r_m * math.cos(angle),
            c.position_m[1] + agent.slot_r_m * math.sin(angle),
        )


@dataclass(frozen=True)
class Move:
    """A move: the polyline the agent follows this turn from where it stands, and the
    heading it ends with (required for a unicycle or a car, ignored otherwise). The agent
    checks it as any controller's move: a move that is unsafe, too long for the top
    speed or not drivable is refused and recorded, and the agent stays."""

    waypoints_m: Sequence[XY]
    end_heading_rad: Optional[float] = None

    def _to_json(self) -> dict:
        reply = {"type": "move", "waypoints_m": [[float(x), float(y)] for x, y in self.waypoints_m]}
        if self.end_heading_rad is not None:
            reply["end_heading_rad"] = float(self.end_heading_rad)
        return reply


class Controller:
    """A formation controller: override :meth:`turn`; :meth:`start` is there if you
    need to prepare. State kept on ``self`` lasts from turn to turn; after a respawn the
    program starts again from the hello."""

    #: The name the reports give the controller.
    name: str = "python"

    #: The mission, set before the first turn.
    mission: Mission
    #: This agent's index.
    agent: int
    #: This agent's own entry of ``mission.agents``.
    me: AgentInfo

    def start(self, mission: Mission, agent: int) -> None:
        """Called once, before the first turn; keeps the mission on ``self``."""
        self.mission = mission
        self.agent = agent
        self.me = mission.agents[agent]

    def turn(self, turn: Turn) -> Optional[Move]:
        """The move for ``turn``; ``None`` stays where the agent stands."""
        raise NotImplementedError("write turn(self, turn) -> Move or None")


def _reply_line(move: Optional[Move]) -> bytes:
    reply = {"type": "stay"} if move is None else move._to_json()
    return (json.dumps(reply, allow_nan=False) + "\n").encode()


def _messages(lines: Iterable[bytes]) -> Iterator[dict]:
    for line in lines:
        if line.strip():
            try:
                yield json.loads(line)
            except json.JSONDecodeError as e:
                raise ProtocolError(f"not JSON: {e}") from e


def _answers(controller: Controller, lines: Iterable[bytes]) -> Iterator[bytes]:
    messages = _messages(lines)
    hello = next(messages, None)
    if hello is None:
        return
    if hello.get("type") != "hello":
        raise ProtocolError(f"expected the hello first, got {hello.get('type')!r}")
    if hello.get("protocol") != PROTOCOL_VERSION:
        raise ProtocolError(
            f"the agent speaks protocol {hello.get('protocol')}, this module {PROTOCOL_VERSION}"
        )
    controller.start(Mission._of(hello["mission"]), int(hello["agent"]))
    ready = {"type": "ready", "protocol": PROTOCOL_VERSION, "name": str(controller.name)[:64]}
    yield (json.dumps(ready) + "\n").encode()
    for message in messages:
        if message.get("type") != "turn":
            raise ProtocolError(f"expected a turn, got {message.get('type')!r}")
        yield _reply_line(controller.turn(Turn._of(message)))


def serve(controller: Controller, stdin: Optional[BinaryIO] = None, stdout: Optional[BinaryIO] = None) -> None:
    """Answer the agent until it closes the standard input: the hello with ready, each
    turn with ``controller``'s move. Print to stderr, never to stdout (stdout is the
    protocol's)."""
    stdin = sys.stdin.buffer if stdin is None else stdin
    stdout = sys.stdout.buffer if stdout is None else stdout
    for answer in _answers(controller, stdin):
        stdout.write(answer)
        stdout.flush()


def replay(controller: Controller, lines: Iterable[str]) -> List[Optional[Move]]:
    """Try ``controller`` offline on protocol lines (a hello, then turns, as the agent
    sends them): the moves it makes, ``None`` where it stays. No process is started; for
    unit tests and notebooks."""
    moves: List[Optional[Move]] = []
    answers = _answers(controller, (line.encode() for line in lines))
    next(answers, None)  # the ready
    for answer in answers:
        reply = json.loads(answer)
        if reply["type"] == "stay":
            moves.append(None)
        else:
            moves.append(
                Move([tuple(p) for p in reply["waypoints_m"]], reply.get("end_heading_rad"))
            )
    return moves
