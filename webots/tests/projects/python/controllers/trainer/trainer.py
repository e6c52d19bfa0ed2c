"""A training loop's supervisor: episodes of 64 steps (2.048 s), each ended by
simulationReset (the e-puck goes back to where the world put it); in the third episode the
e-puck is moved by setSFVec3f. Every step it sends the time, as text and as floats."""

from controller import Node, Supervisor

EPISODE_STEPS = 64


def xy(values):
    return '%.6f %.6f' % (values[0], values[1])


supervisor = Supervisor()
epuck = supervisor.getFromDef('EPUCK')
assert epuck is not None and supervisor.getFromDef('NO_SUCH_DEF') is None
assert supervisor.getSelf().getType() == Node.ROBOT
translation = epuck.getField('translation')
emitter = supervisor.getDevice('emitter')
start = translation.getSFVec3f()
print('start %s type %s' % (xy(start), epuck.getTypeName()))
steps = 0
episode = 0
while supervisor.step(32) != -1:
    steps += 1
    time = supervisor.getTime()
    emitter.send('t=%.3f' % time)
    emitter.send([time, 2.0 * time])
    if steps == 2 and episode == 2:
        # The third episode starts elsewhere.
        translation.setSFVec3f([0.2, -0.2, start[2]])
        epuck.getField('rotation').setSFRotation([0, 0, 1, 1.0])
    if steps == 3 and episode == 2:
        print('moved to %s' % xy(epuck.getPosition()))
    if steps == EPISODE_STEPS:
        print('episode %d ends at %s after %.3f s' % (episode, xy(epuck.getPosition()), time))
        supervisor.simulationReset()
        supervisor.simulationResetPhysics()
        epuck.resetPhysics()
        steps = 0
        episode += 1
    elif steps == 1:
        print('episode %d starts at %s' % (episode, xy(epuck.getPosition())))
    if episode == 4:
        break
