#!/usr/bin/env python3
"""A Braitenberg obstacle avoider for a Khepera, in Python, over the serial protocol.

It speaks only the real robot's protocol (pyserial, 38400 baud, 8N2), so it drives a real
Khepera on its cable or a world served by `regatta serve --pty` without a change. Mondada's
weights and bias, as in regatta's built-in `braitenberg` controller; each control cycle reads
the proximity sensors (N) and sets the wheel speeds (D).

Usage: braitenberg.py PORT [STEPS]
"""
import math
import sys

import serial

LEFT_WEIGHTS = [4, 4, 6, -18, -15, -5, 5, 3]
RIGHT_WEIGHTS = [-5, -15, -18, 6, 4, 4, 3, 5]
BIAS = 10.0


class Khepera:
    """One request at a time; the reply's letter is checked; three tries, as LAMI's code did."""

    def __init__(self, port):
        self.link = serial.Serial(port, 38400, bytesize=8, parity="N", stopbits=2, timeout=1.0)

    def request(self, line):
        expected = line.split(",")[0].lower()
        for _ in range(3):
            self.link.write((line + "\n").encode("ascii"))
            reply = self.link.readline().decode("ascii", "replace").strip()
            fields = reply.split(",")
            if fields[0] == expected:
                return [int(v) for v in fields[1:]]
            self.link.reset_input_buffer()
        raise RuntimeError(f"no valid reply to {line!r} (last: {reply!r})")

    def proximity(self):
        return self.request("N")

    def set_speed(self, left, right):
        self.request(f"D,{left},{right}")


def command(speed):
    # Rounded half away from zero and clamped, as the robot's speed register wants.
    rounded = math.floor(abs(speed) + 0.5) * (1 if speed >= 0 else -1)
    return int(max(-127, min(127, rounded)))


def main():
    port = sys.argv[1]
    steps = int(sys.argv[2]) if len(sys.argv) > 2 else 300
    robot = Khepera(port)
    version = robot.request("B")
    kind = "simulated" if version == [0, 0] else "real"
    closest = 0
    for _ in range(steps):
        prox = robot.proximity()
        closest = max(closest, max(prox))
        left = BIAS + sum(p * w for p, w in zip(prox, LEFT_WEIGHTS)) / 400.0
        right = BIAS + sum(p * w for p, w in zip(prox, RIGHT_WEIGHTS)) / 400.0
        robot.set_speed(command(left), command(right))
    print(f"python braitenberg: {steps} steps on a {kind} Khepera, closest proximity {closest}")


if __name__ == "__main__":
    main()
