"""A robot's device (Webots' `Device`): the base of every device class."""

from . import _wb
from ._wb import c_char_p, c_double_p, c_int, c_ushort, function

_get_device = function('wb_robot_get_device', c_ushort, c_char_p)
_get_name = function('wb_device_get_name', c_char_p, c_ushort)
_get_model = function('wb_device_get_model', c_char_p, c_ushort)
_get_node_type = function('wb_device_get_node_type', c_int, c_ushort)


# The class of each device node type (filled by `robot`, which imports them all), and one
# object per device, so that getDevice returns the same object every time.
_classes = {}
_devices = {}


def register_classes(classes):
    """Names the class of each device node type, for `device_of`."""
    _classes.update(classes)


def device_of(tag):
    """The device object of a tag (None for 0)."""
    if not tag:
        return None
    device = _devices.get(tag)
    if device is None:
        device = _classes.get(_get_node_type(tag), Device)(tag)
        _devices[tag] = device
    return device


class Device:
    """A device of the robot, by name (`Motor('left wheel motor')`) or by tag."""

    def __init__(self, name=None):
        if isinstance(name, int):
            self._tag = name
        elif name is None:
            self._tag = 0
        else:
            self._tag = _get_device(_wb.cstr(name))

    def __repr__(self):
        return '%s(%r)' % (type(self).__name__, self.getName())

    def getName(self):
        return _wb.text(_get_name(self._tag))

    def getModel(self):
        return _wb.text(_get_model(self._tag))

    def getNodeType(self):
        return _get_node_type(self._tag)

    def getTag(self):
        return self._tag

    @property
    def name(self):
        return self.getName()

    @property
    def model(self):
        return self.getModel()

    @property
    def node_type(self):
        return self.getNodeType()

    @property
    def tag(self):
        return self._tag


class Sensor(Device):
    """A device read every sampling period: `enable(ms)`, `disable()`."""

    # Set by each sensor class: the C functions of its kind.
    _enable = None
    _disable = None
    _get_sampling_period = None

    def enable(self, samplingPeriod):
        type(self)._enable(self._tag, int(samplingPeriod))

    def disable(self):
        type(self)._disable(self._tag)

    def getSamplingPeriod(self):
        return type(self)._get_sampling_period(self._tag)

    @property
    def sampling_period(self):
        return self.getSamplingPeriod()

    @sampling_period.setter
    def sampling_period(self, period):
        if period:
            self.enable(period)
        else:
            self.disable()


def sampled(prefix):
    """The enable, disable and get_sampling_period functions of the devices `wb_PREFIX_…`."""
    return (
        staticmethod(function('wb_%s_enable' % prefix, None, c_ushort, c_int)),
        staticmethod(function('wb_%s_disable' % prefix, None, c_ushort)),
        staticmethod(function('wb_%s_get_sampling_period' % prefix, c_int, c_ushort)),
    )


class VectorSensor(Sensor):
    """A sensor of three values through a lookup table (Webots' `Accelerometer`, `Compass`,
    `Gyro`): a subclass names its kind (`class Gyro(VectorSensor, kind='gyro')`)."""

    def __init_subclass__(cls, kind=None, **kwargs):
        super().__init_subclass__(**kwargs)
        if kind is not None:
            cls._enable, cls._disable, cls._get_sampling_period = sampled(kind)
            cls._get_values = staticmethod(function('wb_%s_get_values' % kind, c_double_p, c_ushort))
            cls._get_table_size = staticmethod(
                function('wb_%s_get_lookup_table_size' % kind, c_int, c_ushort))
            cls._get_table = staticmethod(
                function('wb_%s_get_lookup_table' % kind, c_double_p, c_ushort))

    def getValues(self):
        return _wb.values(type(self)._get_values(self._tag), 3)

    def getLookupTable(self):
        rows = type(self)._get_table_size(self._tag)
        return _wb.values(type(self)._get_table(self._tag), 3 * rows) or []

    @property
    def value(self):
        return self.getValues()
