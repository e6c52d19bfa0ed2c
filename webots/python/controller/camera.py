"""Webots' `Camera`: images as bytes in BGRA order (`getImage`), or as RGB lists indexed
[x][y][channel] (`getImageArray`), and the `imageGet*` helpers."""

import ctypes

from . import _wb
from ._wb import c_char_p, c_double, c_int, c_ubyte_p, c_ushort, function
from .device import Sensor, sampled

_get_image = function('wb_camera_get_image', c_ubyte_p, c_ushort)
_get_width = function('wb_camera_get_width', c_int, c_ushort)
_get_height = function('wb_camera_get_height', c_int, c_ushort)
_get_fov = function('wb_camera_get_fov', c_double, c_ushort)
_get_min_fov = function('wb_camera_get_min_fov', c_double, c_ushort)
_get_max_fov = function('wb_camera_get_max_fov', c_double, c_ushort)
_set_fov = function('wb_camera_set_fov', None, c_ushort, c_double)
_get_exposure = function('wb_camera_get_exposure', c_double, c_ushort)
_set_exposure = function('wb_camera_set_exposure', None, c_ushort, c_double)
_get_focal_length = function('wb_camera_get_focal_length', c_double, c_ushort)
_get_focal_distance = function('wb_camera_get_focal_distance', c_double, c_ushort)
_get_max_focal_distance = function('wb_camera_get_max_focal_distance', c_double, c_ushort)
_get_min_focal_distance = function('wb_camera_get_min_focal_distance', c_double, c_ushort)
_set_focal_distance = function('wb_camera_set_focal_distance', None, c_ushort, c_double)
_get_near = function('wb_camera_get_near', c_double, c_ushort)
_save_image = function('wb_camera_save_image', c_int, c_ushort, c_char_p, c_int)


class Camera(Sensor):
    _enable, _disable, _get_sampling_period = sampled('camera')

    def getImage(self):
        """The last image as bytes, 4 a pixel (blue, green, red, alpha), row by row; None
        before the first image."""
        pointer = _get_image(self._tag)
        if not pointer:
            return None
        size = 4 * _get_width(self._tag) * _get_height(self._tag)
        return ctypes.string_at(pointer, size)

    def getImageArray(self):
        """The last image as lists of [red, green, blue], indexed [x][y]."""
        image = self.getImage()
        if image is None:
            return None
        width, height = _get_width(self._tag), _get_height(self._tag)
        return [[[image[4 * (y * width + x) + 2], image[4 * (y * width + x) + 1], image[4 * (y * width + x)]]
                 for y in range(height)] for x in range(width)]

    def saveImage(self, filename, quality):
        return _save_image(self._tag, _wb.cstr(filename), int(quality))

    def getWidth(self):
        return _get_width(self._tag)

    def getHeight(self):
        return _get_height(self._tag)

    def getFov(self):
        return _get_fov(self._tag)

    def getMinFov(self):
        return _get_min_fov(self._tag)

    def getMaxFov(self):
        return _get_max_fov(self._tag)

    def setFov(self, fov):
        _set_fov(self._tag, fov)

    def getExposure(self):
        return _get_exposure(self._tag)

    def setExposure(self, exposure):
        _set_exposure(self._tag, exposure)

    def getFocalLength(self):
        return _get_focal_length(self._tag)

    def getFocalDistance(self):
        return _get_focal_distance(self._tag)

    def getMaxFocalDistance(self):
        return _get_max_focal_distance(self._tag)

    def getMinFocalDistance(self):
        return _get_min_focal_distance(self._tag)

    def setFocalDistance(self, distance):
        _set_focal_distance(self._tag, distance)

    def getNear(self):
        return _get_near(self._tag)

    def hasRecognition(self):
        return False

    @staticmethod
    def imageGetRed(image, width, x, y):
        return image[4 * (y * width + x) + 2]

    @staticmethod
    def imageGetGreen(image, width, x, y):
        return image[4 * (y * width + x) + 1]

    @staticmethod
    def imageGetBlue(image, width, x, y):
        return image[4 * (y * width + x)]

    @staticmethod
    def imageGetGray(image, width, x, y):
        at = 4 * (y * width + x)
        return (image[at] + image[at + 1] + image[at + 2]) // 3

    imageGetGrey = imageGetGray

    @property
    def image(self):
        return self.getImage()

    @property
    def width(self):
        return self.getWidth()

    @property
    def height(self):
        return self.getHeight()

    @property
    def fov(self):
        return self.getFov()
