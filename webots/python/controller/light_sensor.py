"""Webots' `LightSensor`."""

from . import _wb
from ._wb import c_double, c_double_p, c_int, c_ushort, function
from .device import Sensor, sampled

_get_value = function('wb_light_sensor_get_value', c_double, c_ushort)
_get_lookup_table_size = function('wb_light_sensor_get_lookup_table_size', c_int, c_ushort)
_get_lookup_table = function('wb_light_sensor_get_lookup_table', c_double_p, c_ushort)


class LightSensor(Sensor):
    _enable, _disable, _get_sampling_period = sampled('light_sensor')

    def getValue(self):
        return _get_value(self._tag)

    def getLookupTable(self):
        return _wb.values(_get_lookup_table(self._tag), 3 * _get_lookup_table_size(self._tag)) or []

    @property
    def value(self):
        return self.getValue()
