"""Webots' `TouchSensor` (regatta's robots are kinematic: its values are NaN)."""

from . import _wb
from ._wb import c_double, c_double_p, c_int, c_ushort, function
from .device import Sensor, sampled

_get_value = function('wb_touch_sensor_get_value', c_double, c_ushort)
_get_values = function('wb_touch_sensor_get_values', c_double_p, c_ushort)
_get_type = function('wb_touch_sensor_get_type', c_int, c_ushort)
_get_lookup_table_size = function('wb_touch_sensor_get_lookup_table_size', c_int, c_ushort)
_get_lookup_table = function('wb_touch_sensor_get_lookup_table', c_double_p, c_ushort)


class TouchSensor(Sensor):
    BUMPER = 0
    FORCE = 1
    FORCE3D = 2
    _enable, _disable, _get_sampling_period = sampled('touch_sensor')

    def getValue(self):
        return _get_value(self._tag)

    def getValues(self):
        return _wb.values(_get_values(self._tag), 3)

    def getType(self):
        return _get_type(self._tag)

    def getLookupTable(self):
        return _wb.values(_get_lookup_table(self._tag), 3 * _get_lookup_table_size(self._tag)) or []

    @property
    def value(self):
        return self.getValue()
