"""Motors (Webots' `Motor`, `RotationalMotor`, `LinearMotor`)."""

from ._wb import c_double, c_int, c_ushort, function
from .device import Device, device_of

_f = {}
for _name, _res, _args in (
    ('set_position', None, (c_ushort, c_double)),
    ('set_velocity', None, (c_ushort, c_double)),
    ('set_acceleration', None, (c_ushort, c_double)),
    ('set_available_force', None, (c_ushort, c_double)),
    ('set_available_torque', None, (c_ushort, c_double)),
    ('set_force', None, (c_ushort, c_double)),
    ('set_torque', None, (c_ushort, c_double)),
    ('set_control_pid', None, (c_ushort, c_double, c_double, c_double)),
    ('enable_force_feedback', None, (c_ushort, c_int)),
    ('disable_force_feedback', None, (c_ushort,)),
    ('get_force_feedback_sampling_period', c_int, (c_ushort,)),
    ('get_force_feedback', c_double, (c_ushort,)),
    ('enable_torque_feedback', None, (c_ushort, c_int)),
    ('disable_torque_feedback', None, (c_ushort,)),
    ('get_torque_feedback_sampling_period', c_int, (c_ushort,)),
    ('get_torque_feedback', c_double, (c_ushort,)),
    ('get_type', c_int, (c_ushort,)),
    ('get_target_position', c_double, (c_ushort,)),
    ('get_min_position', c_double, (c_ushort,)),
    ('get_max_position', c_double, (c_ushort,)),
    ('get_velocity', c_double, (c_ushort,)),
    ('get_max_velocity', c_double, (c_ushort,)),
    ('get_acceleration', c_double, (c_ushort,)),
    ('get_available_force', c_double, (c_ushort,)),
    ('get_max_force', c_double, (c_ushort,)),
    ('get_available_torque', c_double, (c_ushort,)),
    ('get_max_torque', c_double, (c_ushort,)),
    ('get_multiplier', c_double, (c_ushort,)),
    ('get_brake', c_ushort, (c_ushort,)),
    ('get_position_sensor', c_ushort, (c_ushort,)),
):
    _f[_name] = function('wb_motor_' + _name, _res, *_args)

_set_position = _f['set_position']


def _joint_type(kind):
    """Webots' Python joint type (ROTATIONAL 0, LINEAR 1) of the C library's answer, which
    is the motor's node type."""
    from .node import NODE_TYPE
    return {NODE_TYPE['ROTATIONAL_MOTOR']: 0, NODE_TYPE['LINEAR_MOTOR']: 1, 0: 0, 1: 1}.get(kind, kind)
_set_velocity = _f['set_velocity']


class Motor(Device):
    ROTATIONAL = 0
    LINEAR = 1

    def setPosition(self, position):
        _set_position(self._tag, position)

    def setVelocity(self, velocity):
        _set_velocity(self._tag, velocity)

    def setAcceleration(self, acceleration):
        _f['set_acceleration'](self._tag, acceleration)

    def setAvailableForce(self, force):
        _f['set_available_force'](self._tag, force)

    def setAvailableTorque(self, torque):
        _f['set_available_torque'](self._tag, torque)

    def setForce(self, force):
        _f['set_force'](self._tag, force)

    def setTorque(self, torque):
        _f['set_torque'](self._tag, torque)

    def setControlPID(self, p, i, d):
        _f['set_control_pid'](self._tag, p, i, d)

    def enableForceFeedback(self, samplingPeriod):
        _f['enable_force_feedback'](self._tag, int(samplingPeriod))

    def disableForceFeedback(self):
        _f['disable_force_feedback'](self._tag)

    def getForceFeedbackSamplingPeriod(self):
        return _f['get_force_feedback_sampling_period'](self._tag)

    def getForceFeedback(self):
        return _f['get_force_feedback'](self._tag)

    def enableTorqueFeedback(self, samplingPeriod):
        _f['enable_torque_feedback'](self._tag, int(samplingPeriod))

    def disableTorqueFeedback(self):
        _f['disable_torque_feedback'](self._tag)

    def getTorqueFeedbackSamplingPeriod(self):
        return _f['get_torque_feedback_sampling_period'](self._tag)

    def getTorqueFeedback(self):
        return _f['get_torque_feedback'](self._tag)

    def getType(self):
        """ROTATIONAL (0) or LINEAR (1)."""
        return _joint_type(_f['get_type'](self._tag))

    def getTargetPosition(self):
        return _f['get_target_position'](self._tag)

    def getMinPosition(self):
        return _f['get_min_position'](self._tag)

    def getMaxPosition(self):
        return _f['get_max_position'](self._tag)

    def getVelocity(self):
        return _f['get_velocity'](self._tag)

    def getMaxVelocity(self):
        return _f['get_max_velocity'](self._tag)

    def getAcceleration(self):
        return _f['get_acceleration'](self._tag)

    def getAvailableForce(self):
        return _f['get_available_force'](self._tag)

    def getMaxForce(self):
        return _f['get_max_force'](self._tag)

    def getAvailableTorque(self):
        return _f['get_available_torque'](self._tag)

    def getMaxTorque(self):
        return _f['get_max_torque'](self._tag)

    def getMultiplier(self):
        return _f['get_multiplier'](self._tag)

    def getBrake(self):
        return device_of(_f['get_brake'](self._tag))

    def getPositionSensor(self):
        return device_of(_f['get_position_sensor'](self._tag))

    @property
    def target_position(self):
        return self.getTargetPosition()

    @target_position.setter
    def target_position(self, position):
        self.setPosition(position)

    @property
    def target_velocity(self):
        return self.getVelocity()

    @target_velocity.setter
    def target_velocity(self, velocity):
        self.setVelocity(velocity)

    @property
    def max_velocity(self):
        return self.getMaxVelocity()

    @property
    def position_sensor(self):
        return self.getPositionSensor()


class RotationalMotor(Motor):
    pass


class LinearMotor(Motor):
    pass
