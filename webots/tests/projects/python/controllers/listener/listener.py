"""Receives the supervisor's packets: prints the first few, as text and as floats, then how
many arrived each second."""

from controller import Robot

robot = Robot()
receiver = robot.getDevice('receiver')
receiver.enable(32)
count = 0
shown = 0
while robot.step(32) != -1:
    while receiver.getQueueLength() > 0:
        if receiver.getDataSize() == 16:
            floats = receiver.getFloats()
            if shown < 3:
                print('floats %.3f %.3f' % (floats[0], floats[1]))
        else:
            text = receiver.getString()
            if shown < 3:
                print('text %s' % text)
                shown += 1
        count += 1
        receiver.nextPacket()
    if robot.getTime() >= 5.0:
        print('%d packets in %.3f s' % (count, robot.getTime()))
        break
