"""The world's nodes and their fields, as a supervisor sees them (Webots' `Node` and
`Field`): one module, since each hands out the other."""

from . import _wb
from ._wb import c_bool, c_char_p, c_double, c_double_p, c_int, c_void_p, function

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
        return Field.of(_get_field(self._ref, _wb.cstr(fieldName)))

    def getProtoField(self, fieldName):
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


_field_get_type = function('wb_supervisor_field_get_type', c_int, c_void_p)
_field_get_type_name = function('wb_supervisor_field_get_type_name', c_char_p, c_void_p)
_get_name = function('wb_supervisor_field_get_name', c_char_p, c_void_p)
_get_count = function('wb_supervisor_field_get_count', c_int, c_void_p)
_get_bool = function('wb_supervisor_field_get_sf_bool', c_bool, c_void_p)
_get_int32 = function('wb_supervisor_field_get_sf_int32', c_int, c_void_p)
_get_float = function('wb_supervisor_field_get_sf_float', c_double, c_void_p)
_get_vec2f = function('wb_supervisor_field_get_sf_vec2f', c_double_p, c_void_p)
_get_vec3f = function('wb_supervisor_field_get_sf_vec3f', c_double_p, c_void_p)
_get_rotation = function('wb_supervisor_field_get_sf_rotation', c_double_p, c_void_p)
_get_color = function('wb_supervisor_field_get_sf_color', c_double_p, c_void_p)
_get_string = function('wb_supervisor_field_get_sf_string', c_char_p, c_void_p)
_get_node = function('wb_supervisor_field_get_sf_node', c_void_p, c_void_p)
_set_bool = function('wb_supervisor_field_set_sf_bool', None, c_void_p, c_bool)
_set_int32 = function('wb_supervisor_field_set_sf_int32', None, c_void_p, c_int)
_set_float = function('wb_supervisor_field_set_sf_float', None, c_void_p, c_double)
_set_vec2f = function('wb_supervisor_field_set_sf_vec2f', None, c_void_p, c_double_p)
_set_vec3f = function('wb_supervisor_field_set_sf_vec3f', None, c_void_p, c_double_p)
_set_rotation = function('wb_supervisor_field_set_sf_rotation', None, c_void_p, c_double_p)
_set_color = function('wb_supervisor_field_set_sf_color', None, c_void_p, c_double_p)
_set_string = function('wb_supervisor_field_set_sf_string', None, c_void_p, c_char_p)

# Webots' field types (WbFieldType).
FIELD_TYPES = {
    'NO_FIELD': 0x00,
    'SF_BOOL': 0x01, 'SF_INT32': 0x02, 'SF_FLOAT': 0x03, 'SF_VEC2F': 0x04, 'SF_VEC3F': 0x05,
    'SF_ROTATION': 0x06, 'SF_COLOR': 0x07, 'SF_STRING': 0x08, 'SF_NODE': 0x09,
    'MF': 0x10,
    'MF_BOOL': 0x11, 'MF_INT32': 0x12, 'MF_FLOAT': 0x13, 'MF_VEC2F': 0x14, 'MF_VEC3F': 0x15,
    'MF_ROTATION': 0x16, 'MF_COLOR': 0x17, 'MF_STRING': 0x18, 'MF_NODE': 0x19,
}


class Field:
    """A field of a node: `Node.getField(name)`."""

    def __init__(self, ref):
        self._ref = ref

    @staticmethod
    def of(ref):
        return Field(ref) if ref else None

    def __eq__(self, other):
        return isinstance(other, Field) and other._ref == self._ref

    def __hash__(self):
        return hash(self._ref)

    def __repr__(self):
        return 'Field(%s %s)' % (self.getTypeName(), self.getName())

    def getType(self):
        return _field_get_type(self._ref)

    def getTypeName(self):
        return _wb.text(_field_get_type_name(self._ref))

    def getName(self):
        return _wb.text(_get_name(self._ref))

    def getCount(self):
        return _get_count(self._ref)

    def getSFBool(self):
        return bool(_get_bool(self._ref))

    def getSFInt32(self):
        return _get_int32(self._ref)

    def getSFFloat(self):
        return _get_float(self._ref)

    def getSFVec2f(self):
        return _wb.values(_get_vec2f(self._ref), 2)

    def getSFVec3f(self):
        return _wb.values(_get_vec3f(self._ref), 3)

    def getSFRotation(self):
        return _wb.values(_get_rotation(self._ref), 4)

    def getSFColor(self):
        return _wb.values(_get_color(self._ref), 3)

    def getSFString(self):
        return _wb.text(_get_string(self._ref))

    def getSFNode(self):
        return Node.of(_get_node(self._ref))

    def setSFBool(self, value):
        _set_bool(self._ref, bool(value))

    def setSFInt32(self, value):
        _set_int32(self._ref, int(value))

    def setSFFloat(self, value):
        _set_float(self._ref, float(value))

    def setSFVec2f(self, values):
        _set_vec2f(self._ref, _wb.doubles(values, 2))

    def setSFVec3f(self, values):
        _set_vec3f(self._ref, _wb.doubles(values, 3))

    def setSFRotation(self, values):
        _set_rotation(self._ref, _wb.doubles(values, 4))

    def setSFColor(self, values):
        _set_color(self._ref, _wb.doubles(values, 3))

    def setSFString(self, value):
        _set_string(self._ref, _wb.cstr(value))

    # Webots' properties.
    @property
    def name(self):
        return self.getName()

    @property
    def type(self):
        return self.getType()

    @property
    def value(self):
        getter = {
            0x01: self.getSFBool, 0x02: self.getSFInt32, 0x03: self.getSFFloat,
            0x04: self.getSFVec2f, 0x05: self.getSFVec3f, 0x06: self.getSFRotation,
            0x07: self.getSFColor, 0x08: self.getSFString, 0x09: self.getSFNode,
        }.get(self.getType())
        if getter is None:
            raise NotImplementedError('regatta reads single (SF) fields only, not %s' % self.getTypeName())
        return getter()

    @value.setter
    def value(self, value):
        setter = {
            0x01: self.setSFBool, 0x02: self.setSFInt32, 0x03: self.setSFFloat,
            0x04: self.setSFVec2f, 0x05: self.setSFVec3f, 0x06: self.setSFRotation,
            0x07: self.setSFColor, 0x08: self.setSFString,
        }.get(self.getType())
        if setter is None:
            raise NotImplementedError('regatta writes single (SF) fields only, not %s' % self.getTypeName())
        setter(value)


for _name, _number in FIELD_TYPES.items():
    setattr(Field, _name, _number)
