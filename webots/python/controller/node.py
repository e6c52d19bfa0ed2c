"""A node of the world, as a supervisor sees it (Webots' `Node`)."""

from . import _wb
from ._wb import c_bool, c_char_p, c_double_p, c_int, c_void_p, function

# Webots' node types, in the order of its WbNodeType (webots/nodes.h).
NODE_TYPES = (
    'NO_NODE',
    'APPEARANCE', 'BACKGROUND', 'BILLBOARD', 'BOX', 'CAPSULE', 'COLOR', 'CONE', 'COORDINATE',
    'CYLINDER', 'DIRECTIONAL_LIGHT', 'ELEVATION_GRID', 'FOG', 'GROUP', 'IMAGE_TEXTURE',
    'INDEXED_FACE_SET', 'INDEXED_LINE_SET', 'MATERIAL', 'MESH', 'MUSCLE', 'NORMAL',
    'PBR_APPEARANCE', 'PLANE', 'POINT_LIGHT', 'POINT_SET', 'POSE', 'SHAPE', 'SPHERE', 'SPOT_LIGHT',
    'TEXTURE_COORDINATE', 'TEXTURE_TRANSFORM', 'TRANSFORM', 'VIEWPOINT',
    'ROBOT',
    'ACCELEROMETER', 'ALTIMETER', 'BRAKE', 'CAMERA', 'COMPASS', 'CONNECTOR', 'DISPLAY',
    'DISTANCE_SENSOR', 'EMITTER', 'GPS', 'GYRO', 'INERTIAL_UNIT', 'LED', 'LIDAR', 'LIGHT_SENSOR',
    'LINEAR_MOTOR', 'PEN', 'POSITION_SENSOR', 'PROPELLER', 'RADAR', 'RANGE_FINDER', 'RECEIVER',
    'ROTATIONAL_MOTOR', 'SKIN', 'SPEAKER', 'TOUCH_SENSOR', 'VACUUM_GRIPPER',
    'BALL_JOINT', 'BALL_JOINT_PARAMETERS', 'CHARGER', 'CONTACT_PROPERTIES', 'DAMPING', 'FLUID',
    'FOCUS', 'HINGE_JOINT', 'HINGE_JOINT_PARAMETERS', 'HINGE_2_JOINT', 'IMMERSION_PROPERTIES',
    'JOINT_PARAMETERS', 'LENS', 'LENS_FLARE', 'PHYSICS', 'RECOGNITION', 'SLIDER_JOINT', 'SLOT',
    'SOLID', 'SOLID_REFERENCE', 'TRACK', 'TRACK_WHEEL', 'WORLD_INFO', 'ZOOM',
    'DIFFERENTIAL_WHEELS', 'SUPERVISOR', 'MICROPHONE', 'RADIO',
)
NODE_TYPE = {name: number for number, name in enumerate(NODE_TYPES)}

_get_id = function('wb_supervisor_node_get_id', c_int, c_void_p)
_get_type = function('wb_supervisor_node_get_type', c_int, c_void_p)
_get_type_name = function('wb_supervisor_node_get_type_name', c_char_p, c_void_p)
_get_base_type_name = function('wb_supervisor_node_get_base_type_name', c_char_p, c_void_p)
_get_def = function('wb_supervisor_node_get_def', c_char_p, c_void_p)
_is_proto = function('wb_supervisor_node_is_proto', c_bool, c_void_p)
_get_field = function('wb_supervisor_node_get_field', c_void_p, c_void_p, c_char_p)
_get_proto_field = function('wb_supervisor_node_get_proto_field', c_void_p, c_void_p, c_char_p)
_get_from_proto_def = function('wb_supervisor_node_get_from_proto_def', c_void_p, c_void_p, c_char_p)
_get_position = function('wb_supervisor_node_get_position', c_double_p, c_void_p)
_get_orientation = function('wb_supervisor_node_get_orientation', c_double_p, c_void_p)
_get_pose = function('wb_supervisor_node_get_pose', c_double_p, c_void_p, c_void_p)
_get_velocity = function('wb_supervisor_node_get_velocity', c_double_p, c_void_p)
_set_velocity = function('wb_supervisor_node_set_velocity', None, c_void_p, c_double_p)
_reset_physics = function('wb_supervisor_node_reset_physics', None, c_void_p)
_restart_controller = function('wb_supervisor_node_restart_controller', None, c_void_p)
_remove = function('wb_supervisor_node_remove', None, c_void_p)


class Node:
    """A node of the world. Obtained from a `Supervisor` (`getFromDef`, `getSelf`, …)."""

    def __init__(self, ref):
        self._ref = ref

    @staticmethod
    def of(ref):
        """The Node of a C reference, None for NULL."""
        return Node(ref) if ref else None

    def __eq__(self, other):
        return isinstance(other, Node) and other._ref == self._ref

    def __hash__(self):
        return hash(self._ref)

    def __repr__(self):
        return 'Node(%s%s)' % (self.getTypeName(), ', DEF ' + self.getDef() if self.getDef() else '')

    def getId(self):
        return _get_id(self._ref)

    def getType(self):
        return _get_type(self._ref)

    def getTypeName(self):
        return _wb.text(_get_type_name(self._ref))

    def getBaseTypeName(self):
        return _wb.text(_get_base_type_name(self._ref))

    def getDef(self):
        return _wb.text(_get_def(self._ref))

    def isProto(self):
        return bool(_is_proto(self._ref))

    def getField(self, fieldName):
        from .field import Field
        return Field.of(_get_field(self._ref, _wb.cstr(fieldName)))

    def getProtoField(self, fieldName):
        from .field import Field
        return Field.of(_get_proto_field(self._ref, _wb.cstr(fieldName)))

    def getFromProtoDef(self, name):
        return Node.of(_get_from_proto_def(self._ref, _wb.cstr(name)))

    def getPosition(self):
        return _wb.values(_get_position(self._ref), 3)

    def getOrientation(self):
        return _wb.values(_get_orientation(self._ref), 9)

    def getPose(self, fromNode=None):
        return _wb.values(_get_pose(self._ref, fromNode._ref if fromNode else None), 16)

    def getVelocity(self):
        return _wb.values(_get_velocity(self._ref), 6)

    def setVelocity(self, velocity):
        _set_velocity(self._ref, _wb.doubles(velocity, 6))

    def resetPhysics(self):
        _reset_physics(self._ref)

    def restartController(self):
        _restart_controller(self._ref)

    def remove(self):
        _remove(self._ref)

    # Webots' properties.
    @property
    def id(self):
        return self.getId()

    @property
    def type(self):
        return self.getType()

    @property
    def type_name(self):
        return self.getTypeName()

    @property
    def def_name(self):
        return self.getDef()


for _number, _name in enumerate(NODE_TYPES):
    setattr(Node, _name, _number)
