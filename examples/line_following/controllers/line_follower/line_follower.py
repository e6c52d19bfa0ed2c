"""Follows a black line on a light floor with the e-puck's three ground sensors.

gs0 looks down on the left of the line, gs1 on it, gs2 on its right; each reads high over the
light floor and low over the line. The robot steers towards the darker side, in proportion to
the difference, and, having lost the line, turns back towards the side it last saw it on.
Speeds are in rad/s and the gain per sensor unit: the behaviour does not depend on the
world's time step.
"""

from controller import Robot

MAX_SPEED = 6.28  # rad/s, the e-puck's motors
BASE_SPEED = 3.0  # rad/s
GAIN = 0.008  # rad/s per unit of ground-sensor difference
LOST = 600  # every sensor above this: no line under the robot


def clamp(speed: float) -> float:
    return max(-MAX_SPEED, min(MAX_SPEED, speed))


def main() -> None:
    robot = Robot()
    step = int(robot.getBasicTimeStep())
    ground = [robot.getDevice(f"gs{i}") for i in range(3)]
    for sensor in ground:
        sensor.enable(step)
    left = robot.getDevice("left wheel motor")
    right = robot.getDevice("right wheel motor")
    for motor in (left, right):
        motor.setPosition(float("inf"))
        motor.setVelocity(0.0)
    last_turn = 0.0
    while robot.step(step) != -1:
        gs0, gs1, gs2 = (sensor.getValue() for sensor in ground)
        if min(gs0, gs1, gs2) > LOST:
            # Off the line: turn on the spot towards where it was last seen.
            turn = BASE_SPEED if last_turn >= 0 else -BASE_SPEED
            left.setVelocity(clamp(-turn * 0.5))
            right.setVelocity(clamp(turn * 0.5))
            continue
        # The right sensor lighter than the left: the line lies to the left, turn left.
        turn = GAIN * (gs2 - gs0)
        last_turn = turn if turn != 0 else last_turn
        left.setVelocity(clamp(BASE_SPEED - turn))
        right.setVelocity(clamp(BASE_SPEED + turn))


if __name__ == "__main__":
    main()
