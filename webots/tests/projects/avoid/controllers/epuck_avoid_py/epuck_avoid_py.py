"""Obstacle avoidance for the e-puck, in Python: the same Braitenberg vehicle as
controllers/epuck_avoid/epuck_avoid.c, computed in the same order, so that both drive the
e-puck along the same path. `$EPUCK_STOP_S`, when set, is a simulated time at which it
stops (exits), for measurements of the controller process alone (callgrind)."""

import os

from controller import Robot

TIME_STEP = 32
MAX_SPEED = 6.28
# Sensors 0-2 look right and ahead, 5-7 left and ahead.
WEIGHTS_LEFT = [-1.3, -1.0, -0.6, 0.0, 0.0, 0.6, 1.0, 1.3]
WEIGHTS_RIGHT = [1.3, 1.0, 0.6, 0.0, 0.0, -0.6, -1.0, -1.3]

robot = Robot()
sensors = [robot.getDevice('ps%d' % i) for i in range(8)]
for sensor in sensors:
    sensor.enable(TIME_STEP)
left = robot.getDevice('left wheel motor')
right = robot.getDevice('right wheel motor')
left.setPosition(float('inf'))
right.setPosition(float('inf'))
left.setVelocity(0.0)
right.setVelocity(0.0)
# The front LED blinks once a second.
front = robot.getDevice('led9')
steps = 0
stop = float(os.environ.get('EPUCK_STOP_S', 'inf'))
while robot.step(TIME_STEP) != -1 and robot.getTime() < stop:
    if steps % 16 == 0:
        front.set(0 if front.get() else 1)
    l = 0.5 * MAX_SPEED
    r = 0.5 * MAX_SPEED
    for i in range(8):
        v = sensors[i].getValue()
        if v != v:
            v = 0.0
        x = (v - 70.0) / 1000.0
        if x < 0.0:
            x = 0.0
        l += WEIGHTS_LEFT[i] * x * MAX_SPEED
        r += WEIGHTS_RIGHT[i] * x * MAX_SPEED
    l = max(-MAX_SPEED, min(MAX_SPEED, l))
    r = max(-MAX_SPEED, min(MAX_SPEED, r))
    left.setVelocity(l)
    right.setVelocity(r)
    steps += 1
    if steps % 625 == 0:
        print('t = %.3f s: ps0 %.1f, ps7 %.1f, led9 %d' % (robot.getTime(), sensors[0].getValue(),
                                                           sensors[7].getValue(), front.get()))
