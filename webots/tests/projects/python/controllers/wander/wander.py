"""Drives the e-puck along a wide arc, its wheel speeds set by the older accessor getMotor."""

from controller import Robot

robot = Robot()
left = robot.getMotor('left wheel motor')
right = robot.getMotor('right wheel motor')
for motor in (left, right):
    motor.setPosition(float('inf'))
left.setVelocity(4.0)
right.setVelocity(3.0)
while robot.step(32) != -1:
    pass
