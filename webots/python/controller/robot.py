"""Webots' `Robot`: the controller's robot, its clock and its devices."""

from . import _wb
from ._wb import c_bool, c_char_p, c_double, c_int, c_ushort, function
from .accelerometer import Accelerometer
from .camera import Camera
from .compass import Compass
from .device import device_of, register_classes
from .distance_sensor import DistanceSensor
from .emitter import Emitter
from .gps import GPS
from .gyro import Gyro
from .inertial_unit import InertialUnit
from .keyboard import Keyboard
from .led import LED
from .light_sensor import LightSensor
from .motor import LinearMotor, RotationalMotor
from .node import NODE_TYPE
from .position_sensor import PositionSensor
from .receiver import Receiver
from .touch_sensor import TouchSensor

_init = function('wb_robot_init', c_int)
_cleanup = function('wb_robot_cleanup', None)
_step = function('wb_robot_step', c_int, c_int)
_step_begin = function('wb_robot_step_begin', c_int, c_int)
_step_end = function('wb_robot_step_end', c_int)
_get_time = function('wb_robot_get_time', c_double)
_get_basic_time_step = function('wb_robot_get_basic_time_step', c_double)
_get_name = function('wb_robot_get_name', c_char_p)
_get_model = function('wb_robot_get_model', c_char_p)
_get_custom_data = function('wb_robot_get_custom_data', c_char_p)
_set_custom_data = function('wb_robot_set_custom_data', None, c_char_p)
_get_mode = function('wb_robot_get_mode', c_int)
_set_mode = function('wb_robot_set_mode', None, c_int, c_char_p)
_get_synchronization = function('wb_robot_get_synchronization', c_bool)
_get_supervisor = function('wb_robot_get_supervisor', c_bool)
_get_project_path = function('wb_robot_get_project_path', c_char_p)
_get_world_path = function('wb_robot_get_world_path', c_char_p)
_get_urdf = function('wb_robot_get_urdf', c_char_p, c_char_p)
_get_device = function('wb_robot_get_device', c_ushort, c_char_p)
_get_number_of_devices = function('wb_robot_get_number_of_devices', c_int)
_get_device_by_index = function('wb_robot_get_device_by_index', c_ushort, c_int)
_battery_enable = function('wb_robot_battery_sensor_enable', None, c_int)
_battery_disable = function('wb_robot_battery_sensor_disable', None)
_battery_period = function('wb_robot_battery_sensor_get_sampling_period', c_int)
_battery_value = function('wb_robot_battery_sensor_get_value', c_double)
_wait_for_user_input_event = function('wb_robot_wait_for_user_input_event', c_int, c_int, c_int)

# The class of each device node type.
_CLASSES = {
    NODE_TYPE['ROTATIONAL_MOTOR']: RotationalMotor,
    NODE_TYPE['LINEAR_MOTOR']: LinearMotor,
    NODE_TYPE['POSITION_SENSOR']: PositionSensor,
    NODE_TYPE['DISTANCE_SENSOR']: DistanceSensor,
    NODE_TYPE['LIGHT_SENSOR']: LightSensor,
    NODE_TYPE['LED']: LED,
    NODE_TYPE['CAMERA']: Camera,
    NODE_TYPE['GPS']: GPS,
    NODE_TYPE['COMPASS']: Compass,
    NODE_TYPE['INERTIAL_UNIT']: InertialUnit,
    NODE_TYPE['ACCELEROMETER']: Accelerometer,
    NODE_TYPE['GYRO']: Gyro,
    NODE_TYPE['TOUCH_SENSOR']: TouchSensor,
    NODE_TYPE['EMITTER']: Emitter,
    NODE_TYPE['RECEIVER']: Receiver,
}

register_classes(_CLASSES)


class Robot:
    """The robot this controller drives. One per controller process: its creation connects
    to regatta (`wb_robot_init`)."""

    EVENT_QUIT = -1
    EVENT_NO_EVENT = 0
    EVENT_MOUSE_CLICK = 1
    EVENT_MOUSE_MOVE = 2
    EVENT_KEYBOARD = 4
    EVENT_JOYSTICK_BUTTON = 8
    EVENT_JOYSTICK_AXIS = 16
    EVENT_JOYSTICK_POV = 32
    MODE_SIMULATION = 0
    MODE_CROSS_COMPILATION = 1
    MODE_REMOTE_CONTROL = 2

    created = None

    def __init__(self):
        _init()
        Robot.created = self
        self.keyboard = Keyboard()
        self.devices = {}
        for index in range(_get_number_of_devices()):
            device = device_of(_get_device_by_index(index))
            self.devices[device.getName()] = device

    # The simulation's clock.
    def step(self, duration=None):
        """Lets `duration` ms of simulated time pass (the basic time step by default); -1
        when the simulation ends."""
        if duration is None:
            duration = int(_get_basic_time_step())
        return _step(int(duration))

    def stepBegin(self, duration=None):
        if duration is None:
            duration = int(_get_basic_time_step())
        return _step_begin(int(duration))

    def stepEnd(self):
        return _step_end()

    def getTime(self):
        return _get_time()

    def getBasicTimeStep(self):
        return _get_basic_time_step()

    def waitForUserInputEvent(self, eventType, timeout):
        return _wait_for_user_input_event(int(eventType), int(timeout))

    # The robot.
    def getName(self):
        return _wb.text(_get_name())

    def getModel(self):
        return _wb.text(_get_model())

    def getCustomData(self):
        return _wb.text(_get_custom_data())

    def setCustomData(self, data):
        _set_custom_data(_wb.cstr(data))

    def getData(self):
        return self.getCustomData()

    def setData(self, data):
        self.setCustomData(data)

    def getMode(self):
        return _get_mode()

    def setMode(self, mode, arg=None):
        _set_mode(int(mode), None if arg is None else _wb.cstr(arg))

    def getSynchronization(self):
        return bool(_get_synchronization())

    def getSupervisor(self):
        return bool(_get_supervisor())

    def getProjectPath(self):
        return _wb.text(_get_project_path())

    def getWorldPath(self):
        return _wb.text(_get_world_path())

    def getUrdf(self, prefix=''):
        return _wb.text(_get_urdf(_wb.cstr(prefix)))

    def batterySensorEnable(self, samplingPeriod):
        _battery_enable(int(samplingPeriod))

    def batterySensorDisable(self):
        _battery_disable()

    def batterySensorGetSamplingPeriod(self):
        return _battery_period()

    def batterySensorGetValue(self):
        return _battery_value()

    def getKeyboard(self):
        return self.keyboard

    # Devices.
    def getDevice(self, name):
        """The device called `name`, of its class (`Motor`, `DistanceSensor`, …); None, with
        a warning, when the robot has none of that name."""
        return device_of(_get_device(_wb.cstr(name)))

    def getDeviceByIndex(self, index):
        return device_of(_get_device_by_index(int(index)))

    def getNumberOfDevices(self):
        return _get_number_of_devices()

    # The accessors of Webots before R2022a: each is getDevice.
    def getAccelerometer(self, name):
        return self.getDevice(name)

    def getCamera(self, name):
        return self.getDevice(name)

    def getCompass(self, name):
        return self.getDevice(name)

    def getDistanceSensor(self, name):
        return self.getDevice(name)

    def getEmitter(self, name):
        return self.getDevice(name)

    def getGPS(self, name):
        return self.getDevice(name)

    def getGyro(self, name):
        return self.getDevice(name)

    def getInertialUnit(self, name):
        return self.getDevice(name)

    def getLED(self, name):
        return self.getDevice(name)

    def getLightSensor(self, name):
        return self.getDevice(name)

    def getMotor(self, name):
        return self.getDevice(name)

    def getPositionSensor(self, name):
        return self.getDevice(name)

    def getReceiver(self, name):
        return self.getDevice(name)

    def getTouchSensor(self, name):
        return self.getDevice(name)

    # Webots' properties.
    @property
    def name(self):
        return self.getName()

    @property
    def model(self):
        return self.getModel()

    @property
    def time(self):
        return self.getTime()

    @property
    def basic_time_step(self):
        return self.getBasicTimeStep()

    @property
    def custom_data(self):
        return self.getCustomData()

    @custom_data.setter
    def custom_data(self, data):
        self.setCustomData(data)

    @property
    def project_path(self):
        return self.getProjectPath()

    @property
    def world_path(self):
        return self.getWorldPath()

    @property
    def supervisor(self):
        return self.getSupervisor()

    @property
    def synchronization(self):
        return self.getSynchronization()
