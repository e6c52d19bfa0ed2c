"""Drives the e-puck along a wide arc, its wheel speeds set through the older accessor
getMotor, and looks once through its camera (getImage, getImageArray, imageGetGray)."""

from controller import Camera, Robot

robot = Robot()
left = robot.getMotor('left wheel motor')
right = robot.getMotor('right wheel motor')
for motor in (left, right):
    motor.setPosition(float('inf'))
left.setVelocity(4.0)
right.setVelocity(3.0)
camera = robot.getCamera('camera')
camera.enable(64)
looked = False
while robot.step(32) != -1:
    if not looked and robot.getTime() >= 0.128:
        looked = True
        width, height = camera.getWidth(), camera.getHeight()
        image = camera.getImage()
        array = camera.getImageArray()
        x, y = width // 2, height // 2
        print('camera %dx%d: %d bytes, array %dx%dx%d, centre grey %d = mean of rgb %s' % (
            width, height, len(image), len(array), len(array[0]), len(array[0][0]),
            Camera.imageGetGray(image, width, x, y), array[x][y]))
        camera.disable()
