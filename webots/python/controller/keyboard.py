"""Webots' `Keyboard`: regatta has no window, so no key is ever pressed (`getKey` is -1)."""

from ._wb import c_int, function

_enable = function('wb_keyboard_enable', None, c_int)
_disable = function('wb_keyboard_disable', None)
_get_sampling_period = function('wb_keyboard_get_sampling_period', c_int)
_get_key = function('wb_keyboard_get_key', c_int)


class Keyboard:
    END = 312
    HOME = 313
    LEFT = 314
    UP = 315
    RIGHT = 316
    DOWN = 317
    PAGEUP = 366
    PAGEDOWN = 367
    NUMPAD_HOME = 375
    NUMPAD_LEFT = 376
    NUMPAD_UP = 377
    NUMPAD_RIGHT = 378
    NUMPAD_DOWN = 379
    NUMPAD_END = 382
    KEY = 0x0000ffff
    SHIFT = 0x00010000
    CONTROL = 0x00020000
    ALT = 0x00040000

    def __init__(self, samplingPeriod=None):
        if samplingPeriod:
            self.enable(samplingPeriod)

    def enable(self, samplingPeriod):
        _enable(int(samplingPeriod))

    def disable(self):
        _disable()

    def getSamplingPeriod(self):
        return _get_sampling_period()

    def getKey(self):
        return _get_key()

    @property
    def sampling_period(self):
        return self.getSamplingPeriod()
