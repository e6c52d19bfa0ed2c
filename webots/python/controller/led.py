"""Webots' `LED`."""

from ._wb import c_int, c_ushort, function
from .device import Device

_set = function('wb_led_set', None, c_ushort, c_int)
_get = function('wb_led_get', c_int, c_ushort)


class LED(Device):
    def set(self, value):
        _set(self._tag, int(value))

    def get(self):
        return _get(self._tag)

    @property
    def value(self):
        return self.get()

    @value.setter
    def value(self, value):
        self.set(value)
