"""The naive controller: every turn, straight towards the agent's slot, as far as its top
speed allows, whatever stands in the way.

It ignores obstacles and mates on purpose: the harness checks every move it makes, so an
unsafe one is refused and recorded and the agent stays where it is (no collision happens,
the refusals are counted in the run's summary). A holonomic agent only: it gives no end
heading.

    PYTHONPATH=shared/python python3 examples/python/go_to_slot.py
"""

import math

from formation_controller import Controller, Move, serve


class GoToSlot(Controller):
    name = "go-to-slot"

    def turn(self, turn):
        x, y = turn.position_m
        gx, gy = turn.slot_position_m(self.me)
        dx, dy = gx - x, gy - y
        distance = math.hypot(dx, dy)
        if distance == 0.0:
            return None  # at the slot: stay
        top = self.me.max_step_m
        if top is not None and distance > top:
            gx, gy = x + dx * top / distance, y + dy * top / distance
        return Move([(gx, gy)])


if __name__ == "__main__":
    serve(GoToSlot())
