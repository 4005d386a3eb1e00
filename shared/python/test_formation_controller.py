"""Unit tests of the Python SDK (standard library only):
``python3 -m unittest discover -s shared/python``."""

import io
import json
import unittest

from formation_controller import (
    PROTOCOL_VERSION,
    Controller,
    Move,
    ProtocolError,
    replay,
    serve,
)

MISSION = {
    "field_m": [20.0, 10.0],
    "obstacles": [{"centre_m": [5.0, 5.0], "radius_m": 1.0}],
    "polygons_m": [[[8.0, 1.0], [9.0, 1.0], [9.0, 2.0]]],
    "agents": [
        {
            "slot_r_m": 1.0,
            "slot_theta_rad": 0.0,
            "radius_m": 0.3,
            "max_step_m": 0.5,
            "sensing_radius_m": None,
            "kinematics": {"model": "holonomic"},
        },
        {
            "slot_r_m": 1.0,
            "slot_theta_rad": 3.141592653589793,
            "radius_m": 0.3,
            "max_step_m": None,
            "sensing_radius_m": 3.0,
            "kinematics": {"model": "unicycle", "max_turn_rad": 0.5, "reverse": True},
        },
    ],
    "turns": "sequential",
}


def hello(agent=0, protocol=PROTOCOL_VERSION):
    return json.dumps({"type": "hello", "protocol": protocol, "agent": agent, "mission": MISSION})


def turn(step, position, centre=(2.0, 2.0), heading=None):
    return json.dumps(
        {
            "type": "turn",
            "step": step,
            "centre": {"position_m": list(centre), "heading_rad": 0.0},
            "ahead": [],
            "position_m": list(position),
            "heading_rad": heading,
            "others": [{"centre_m": [0.0, 0.0], "radius_m": 0.3}],
            "mates": [{"index": 1, "position_m": [0.0, 0.0], "alive": True}],
            "moving": [],
            "velocities": None,
        }
    )


class ToSlot(Controller):
    name = "to-slot"

    def turn(self, turn):
        if turn.position_m == turn.slot_position_m(self.me):
            return None
        return Move([turn.slot_position_m(self.me)])


class Recorder(Controller):
    def start(self, mission, agent):
        super().start(mission, agent)
        self.seen = []

    def turn(self, turn):
        self.seen.append(turn)
        return None


class SdkTest(unittest.TestCase):
    def test_the_mission_and_the_turn_arrive_typed(self):
        c = Recorder()
        replay(c, [hello(agent=1), turn(4, (1.0, 2.0), heading=0.25)])
        self.assertEqual(c.agent, 1)
        self.assertEqual(c.me.kinematics.model, "unicycle")
        self.assertEqual(c.me.kinematics.max_turn_rad, 0.5)
        self.assertEqual(c.me.sensing_radius_m, 3.0)
        self.assertEqual(c.mission.obstacles[0].radius_m, 1.0)
        self.assertEqual(c.mission.polygons_m[0][2], (9.0, 2.0))
        (t,) = c.seen
        self.assertEqual((t.step, t.position_m, t.heading_rad), (4, (1.0, 2.0), 0.25))
        self.assertEqual(t.mates[0].index, 1)
        self.assertIsNone(t.velocities)

    def test_the_slot_is_the_centre_plus_the_turned_offset(self):
        c = Recorder()
        replay(c, [hello(agent=1), turn(0, (0.0, 0.0), centre=(2.0, 2.0))])
        x, y = c.seen[0].slot_position_m(c.me)
        self.assertAlmostEqual(x, 1.0)
        self.assertAlmostEqual(y, 2.0)

    def test_replay_gives_each_turns_move_or_none(self):
        moves = replay(ToSlot(), [hello(), turn(1, (0.0, 0.0)), turn(2, (3.0, 2.0))])
        self.assertEqual(moves[0].waypoints_m, [(3.0, 2.0)])
        self.assertIsNone(moves[1])

    def test_serve_answers_ready_then_one_line_a_turn(self):
        stdin = io.BytesIO("\n".join([hello(), turn(1, (0.0, 0.0)), turn(2, (3.0, 2.0))]).encode() + b"\n")
        stdout = io.BytesIO()
        serve(ToSlot(), stdin, stdout)
        lines = [json.loads(l) for l in stdout.getvalue().splitlines()]
        self.assertEqual(lines[0], {"type": "ready", "protocol": PROTOCOL_VERSION, "name": "to-slot"})
        self.assertEqual(lines[1], {"type": "move", "waypoints_m": [[3.0, 2.0]]})
        self.assertEqual(lines[2], {"type": "stay"})

    def test_another_protocol_version_is_refused(self):
        with self.assertRaises(ProtocolError):
            replay(ToSlot(), [hello(protocol=PROTOCOL_VERSION + 1)])

    def test_a_move_with_a_nan_is_not_sent(self):
        class Nan(Controller):
            def turn(self, turn):
                return Move([(float("nan"), 0.0)])

        with self.assertRaises(ValueError):
            replay(Nan(), [hello(), turn(1, (0.0, 0.0))])


if __name__ == "__main__":
    unittest.main()
