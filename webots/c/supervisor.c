/*
 * The supervisor's part of regatta's Webots controller library, written from Webots'
 * published reference manual. It is included by regatta_controller.c (one translation unit,
 * so that it shares the connection and its buffers). Every call is one request answered at
 * once, between steps, as Webots answers a supervisor.
 */
#include <webots/supervisor.h>

enum {
  REQUEST_SELF = 1,
  REQUEST_FROM_DEF,
  REQUEST_FROM_PROTO_DEF,
  REQUEST_NODE_INFO,
  REQUEST_FIELD,
  REQUEST_FIELD_GET,
  REQUEST_FIELD_SET,
  REQUEST_NODE_STATE,
  REQUEST_SET_VELOCITY,
  REQUEST_RESET_PHYSICS,
  REQUEST_SIMULATION_RESET_PHYSICS,
  REQUEST_SIMULATION_RESET,
  REQUEST_SIMULATION_MODE,
  REQUEST_SIMULATION_QUIT
};

struct WbNodeStructPrivate {
  uint32_t id;
  int has_info;
  char *type_name, *base_type_name, *def;
  int is_proto;
  double position[3], orientation[9], velocity[6];
};

struct WbFieldStructPrivate {
  uint32_t id;
  int type;
  char *name;
  double values[4];
  char *string;
};

static struct WbNodeStructPrivate **supervisor_nodes;
static uint32_t supervisor_nodes_capacity;
static WbSimulationMode simulation_mode = WB_SUPERVISOR_SIMULATION_MODE_FAST;

/* The request being written: length, kind (1: a request), then the request. */
static unsigned char *request_bytes;
static size_t request_length, request_capacity;

static void request_put(const void *data, size_t n) {
  if (request_length + n > request_capacity) {
    size_t capacity = request_capacity ? request_capacity * 2 : 256;
    while (capacity < request_length + n)
      capacity *= 2;
    request_bytes = realloc(request_bytes, capacity);
    if (!request_bytes)
      fail("out of memory");
    request_capacity = capacity;
  }
  memcpy(request_bytes + request_length, data, n);
  request_length += n;
}

static int supervisor_allowed(const char *function) {
  if (!R.initialized)
    fail("%s() called before wb_robot_init()", function);
  if (!R.supervisor) {
    fprintf(stderr, "Error: %s() can only be called by a robot whose supervisor field is TRUE.\n", function);
    return 0;
  }
  return 1;
}

static void request_begin(int op) {
  unsigned char header[6] = {0, 0, 0, 0, 1, (unsigned char)op};
  request_length = 0;
  request_put(header, sizeof header);
}

static void request_u32(uint32_t v) {
  request_put(&v, 4);
}

static void request_f64(double v) {
  request_put(&v, 8);
}

static void request_str(const char *s) {
  uint32_t n = s ? (uint32_t)strlen(s) : 0;
  request_u32(n);
  request_put(s ? s : "", n);
}

/* Sends the request and reads its answer into the frame buffer. */
static void request_send(void) {
  uint32_t length = (uint32_t)(request_length - 4);
  memcpy(request_bytes, &length, 4);
  write_all(request_bytes, request_length);
  read_frame();
}

static WbNodeRef node_of(uint32_t id) {
  if (id == 0)
    return NULL;
  if (id >= supervisor_nodes_capacity) {
    uint32_t capacity = supervisor_nodes_capacity ? supervisor_nodes_capacity : 64;
    while (capacity <= id)
      capacity *= 2;
    supervisor_nodes = realloc(supervisor_nodes, capacity * sizeof *supervisor_nodes);
    if (!supervisor_nodes)
      fail("out of memory");
    memset(supervisor_nodes + supervisor_nodes_capacity, 0,
           (capacity - supervisor_nodes_capacity) * sizeof *supervisor_nodes);
    supervisor_nodes_capacity = capacity;
  }
  if (!supervisor_nodes[id]) {
    supervisor_nodes[id] = calloc(1, sizeof(struct WbNodeStructPrivate));
    if (!supervisor_nodes[id])
      fail("out of memory");
    supervisor_nodes[id]->id = id;
  }
  return supervisor_nodes[id];
}

WbNodeRef wb_supervisor_node_get_self(void) {
  if (!supervisor_allowed("wb_supervisor_node_get_self"))
    return NULL;
  request_begin(REQUEST_SELF);
  request_send();
  return node_of(take_u32());
}

WbNodeRef wb_supervisor_node_get_root(void) {
  if (!supervisor_allowed("wb_supervisor_node_get_root"))
    return NULL;
  fprintf(stderr, "Warning: wb_supervisor_node_get_root(): the scene tree's root is not available in regatta.\n");
  return NULL;
}

WbNodeRef wb_supervisor_node_get_from_def(const char *def) {
  if (!supervisor_allowed("wb_supervisor_node_get_from_def"))
    return NULL;
  request_begin(REQUEST_FROM_DEF);
  request_str(def);
  request_send();
  return node_of(take_u32());
}

WbNodeRef wb_supervisor_node_get_from_proto_def(WbNodeRef node, const char *def) {
  if (!supervisor_allowed("wb_supervisor_node_get_from_proto_def") || !node)
    return NULL;
  request_begin(REQUEST_FROM_PROTO_DEF);
  request_u32(node->id);
  request_str(def);
  request_send();
  return node_of(take_u32());
}

int wb_supervisor_node_get_id(WbNodeRef node) {
  return node ? (int)node->id : -1;
}

WbNodeRef wb_supervisor_node_get_from_id(int id) {
  if (!supervisor_allowed("wb_supervisor_node_get_from_id") || id <= 0)
    return NULL;
  return node_of((uint32_t)id);
}

static void node_info(WbNodeRef node) {
  if (node->has_info)
    return;
  request_begin(REQUEST_NODE_INFO);
  request_u32(node->id);
  request_send();
  node->type_name = take_str();
  node->base_type_name = take_str();
  node->def = take_str();
  node->is_proto = take_u8();
  node->has_info = 1;
}

/* Webots' node types by their base type's name. */
static WbNodeType node_type_of(const char *name) {
  static const struct {
    const char *name;
    WbNodeType type;
  } types[] = {{"Robot", WB_NODE_ROBOT},
               {"DifferentialWheels", WB_NODE_ROBOT},
               {"Solid", WB_NODE_SOLID},
               {"Transform", WB_NODE_TRANSFORM},
               {"Group", WB_NODE_GROUP},
               {"Shape", WB_NODE_SHAPE},
               {"Appearance", WB_NODE_APPEARANCE},
               {"PBRAppearance", WB_NODE_PBR_APPEARANCE},
               {"Material", WB_NODE_MATERIAL},
               {"Box", WB_NODE_BOX},
               {"Sphere", WB_NODE_SPHERE},
               {"Cylinder", WB_NODE_CYLINDER},
               {"Cone", WB_NODE_CONE},
               {"Plane", WB_NODE_PLANE},
               {"WorldInfo", WB_NODE_WORLD_INFO},
               {"Viewpoint", WB_NODE_VIEWPOINT},
               {"PointLight", WB_NODE_POINT_LIGHT},
               {"SpotLight", WB_NODE_SPOT_LIGHT},
               {"DirectionalLight", WB_NODE_DIRECTIONAL_LIGHT},
               {"DistanceSensor", WB_NODE_DISTANCE_SENSOR},
               {"LightSensor", WB_NODE_LIGHT_SENSOR},
               {"Camera", WB_NODE_CAMERA},
               {"GPS", WB_NODE_GPS},
               {"Compass", WB_NODE_COMPASS},
               {"LED", WB_NODE_LED},
               {"Emitter", WB_NODE_EMITTER},
               {"Receiver", WB_NODE_RECEIVER},
               {"HingeJoint", WB_NODE_HINGE_JOINT},
               {"RotationalMotor", WB_NODE_ROTATIONAL_MOTOR},
               {"PositionSensor", WB_NODE_POSITION_SENSOR},
               {"Physics", WB_NODE_PHYSICS}};
  for (size_t i = 0; i < sizeof types / sizeof types[0]; i++)
    if (strcmp(types[i].name, name) == 0)
      return types[i].type;
  return WB_NODE_NO_NODE;
}

WbNodeType wb_supervisor_node_get_type(WbNodeRef node) {
  if (!supervisor_allowed("wb_supervisor_node_get_type") || !node)
    return WB_NODE_NO_NODE;
  node_info(node);
  return node_type_of(node->base_type_name);
}

const char *wb_supervisor_node_get_type_name(WbNodeRef node) {
  if (!supervisor_allowed("wb_supervisor_node_get_type_name") || !node)
    return "";
  node_info(node);
  return node->type_name;
}

const char *wb_supervisor_node_get_base_type_name(WbNodeRef node) {
  if (!supervisor_allowed("wb_supervisor_node_get_base_type_name") || !node)
    return "";
  node_info(node);
  return node->base_type_name;
}

const char *wb_supervisor_node_get_def(WbNodeRef node) {
  if (!supervisor_allowed("wb_supervisor_node_get_def") || !node)
    return "";
  node_info(node);
  return node->def;
}

bool wb_supervisor_node_is_proto(WbNodeRef node) {
  if (!supervisor_allowed("wb_supervisor_node_is_proto") || !node)
    return false;
  node_info(node);
  return node->is_proto != 0;
}

WbFieldRef wb_supervisor_node_get_field(WbNodeRef node, const char *field_name) {
  if (!supervisor_allowed("wb_supervisor_node_get_field") || !node || !field_name)
    return NULL;
  request_begin(REQUEST_FIELD);
  request_u32(node->id);
  request_str(field_name);
  request_send();
  uint32_t id = take_u32();
  int type = take_u8();
  if (id == 0)
    return NULL;
  struct WbFieldStructPrivate *field = calloc(1, sizeof *field);
  if (!field)
    fail("out of memory");
  field->id = id;
  field->type = type;
  field->name = strdup(field_name);
  return field;
}

WbFieldRef wb_supervisor_node_get_proto_field(WbNodeRef node, const char *field_name) {
  return wb_supervisor_node_get_field(node, field_name);
}

static void node_state(WbNodeRef node) {
  request_begin(REQUEST_NODE_STATE);
  request_u32(node->id);
  request_send();
  for (int i = 0; i < 3; i++)
    node->position[i] = take_f64();
  for (int i = 0; i < 9; i++)
    node->orientation[i] = take_f64();
  for (int i = 0; i < 6; i++)
    node->velocity[i] = take_f64();
}

const double *wb_supervisor_node_get_position(WbNodeRef node) {
  if (!supervisor_allowed("wb_supervisor_node_get_position") || !node)
    return NULL;
  node_state(node);
  return node->position;
}

const double *wb_supervisor_node_get_orientation(WbNodeRef node) {
  if (!supervisor_allowed("wb_supervisor_node_get_orientation") || !node)
    return NULL;
  node_state(node);
  return node->orientation;
}

const double *wb_supervisor_node_get_pose(WbNodeRef node, WbNodeRef from_node) {
  static double pose[16];
  if (!supervisor_allowed("wb_supervisor_node_get_pose") || !node)
    return NULL;
  if (from_node)
    fprintf(stderr, "Warning: wb_supervisor_node_get_pose(): poses relative to another node are given in the world's frame.\n");
  node_state(node);
  for (int r = 0; r < 3; r++) {
    for (int c = 0; c < 3; c++)
      pose[4 * r + c] = node->orientation[3 * r + c];
    pose[4 * r + 3] = node->position[r];
  }
  pose[12] = pose[13] = pose[14] = 0.0;
  pose[15] = 1.0;
  return pose;
}

const double *wb_supervisor_node_get_velocity(WbNodeRef node) {
  if (!supervisor_allowed("wb_supervisor_node_get_velocity") || !node)
    return NULL;
  node_state(node);
  return node->velocity;
}

void wb_supervisor_node_set_velocity(WbNodeRef node, const double velocity[6]) {
  if (!supervisor_allowed("wb_supervisor_node_set_velocity") || !node || !velocity)
    return;
  request_begin(REQUEST_SET_VELOCITY);
  request_u32(node->id);
  for (int i = 0; i < 6; i++)
    request_f64(velocity[i]);
  request_send();
}

void wb_supervisor_node_reset_physics(WbNodeRef node) {
  if (!supervisor_allowed("wb_supervisor_node_reset_physics") || !node)
    return;
  request_begin(REQUEST_RESET_PHYSICS);
  request_u32(node->id);
  request_send();
}

void wb_supervisor_node_restart_controller(WbNodeRef node) {
  (void)node;
  fprintf(stderr, "Warning: wb_supervisor_node_restart_controller(): not available in regatta.\n");
}

void wb_supervisor_node_remove(WbNodeRef node) {
  (void)node;
  fprintf(stderr, "Warning: wb_supervisor_node_remove(): not available in regatta.\n");
}

void wb_supervisor_simulation_quit(int status) {
  if (!supervisor_allowed("wb_supervisor_simulation_quit"))
    return;
  request_begin(REQUEST_SIMULATION_QUIT);
  request_u32((uint32_t)status);
  request_send();
}

void wb_supervisor_simulation_reset(void) {
  if (!supervisor_allowed("wb_supervisor_simulation_reset"))
    return;
  request_begin(REQUEST_SIMULATION_RESET);
  request_send();
}

void wb_supervisor_simulation_reset_physics(void) {
  if (!supervisor_allowed("wb_supervisor_simulation_reset_physics"))
    return;
  request_begin(REQUEST_SIMULATION_RESET_PHYSICS);
  request_send();
}

void wb_supervisor_simulation_physics_reset(void) {
  wb_supervisor_simulation_reset_physics();
}

WbSimulationMode wb_supervisor_simulation_get_mode(void) {
  return simulation_mode;
}

void wb_supervisor_simulation_set_mode(WbSimulationMode mode) {
  if (!supervisor_allowed("wb_supervisor_simulation_set_mode"))
    return;
  simulation_mode = mode;
  request_begin(REQUEST_SIMULATION_MODE);
  request_u32((uint32_t)mode);
  request_send();
}

/* ---- fields ---- */

WbFieldType wb_supervisor_field_get_type(WbFieldRef field) {
  return field ? (WbFieldType)field->type : WB_NO_FIELD;
}

const char *wb_supervisor_field_get_type_name(WbFieldRef field) {
  static const char *names[] = {"", "SFBool", "SFInt32", "SFFloat", "SFVec2f", "SFVec3f", "SFRotation", "SFColor", "SFString", "SFNode"};
  if (!field)
    return "";
  if (field->type > 0 && field->type <= WB_SF_NODE)
    return names[field->type];
  return "MF";
}

const char *wb_supervisor_field_get_name(WbFieldRef field) {
  return field ? field->name : "";
}

int wb_supervisor_field_get_count(WbFieldRef field) {
  return field && field->type < WB_MF ? -1 : 0;
}

/* Reads a field's value (as many numbers as its type has, or its string). */
static int field_get(WbFieldRef field, int type, const char *function) {
  if (!supervisor_allowed(function) || !field)
    return 0;
  if (field->type != type) {
    fprintf(stderr, "Error: %s() called with a field of another type.\n", function);
    return 0;
  }
  request_begin(REQUEST_FIELD_GET);
  request_u32(field->id);
  request_send();
  int count = take_u8();
  for (int i = 0; i < count && i < 4; i++)
    field->values[i] = take_f64();
  if (type == WB_SF_STRING) {
    free(field->string);
    field->string = take_str();
  }
  return 1;
}

static void field_set(WbFieldRef field, int type, const double *values, int count, const char *string, const char *function) {
  if (!supervisor_allowed(function) || !field)
    return;
  if (field->type != type) {
    fprintf(stderr, "Error: %s() called with a field of another type.\n", function);
    return;
  }
  request_begin(REQUEST_FIELD_SET);
  request_u32(field->id);
  unsigned char n = (unsigned char)count;
  request_put(&n, 1);
  for (int i = 0; i < count; i++)
    request_f64(values[i]);
  request_str(string);
  request_send();
}

bool wb_supervisor_field_get_sf_bool(WbFieldRef field) {
  return field_get(field, WB_SF_BOOL, "wb_supervisor_field_get_sf_bool") && field->values[0] != 0.0;
}

int wb_supervisor_field_get_sf_int32(WbFieldRef field) {
  return field_get(field, WB_SF_INT32, "wb_supervisor_field_get_sf_int32") ? (int)field->values[0] : 0;
}

double wb_supervisor_field_get_sf_float(WbFieldRef field) {
  return field_get(field, WB_SF_FLOAT, "wb_supervisor_field_get_sf_float") ? field->values[0] : 0.0;
}

const double *wb_supervisor_field_get_sf_vec2f(WbFieldRef field) {
  return field_get(field, WB_SF_VEC2F, "wb_supervisor_field_get_sf_vec2f") ? field->values : NULL;
}

const double *wb_supervisor_field_get_sf_vec3f(WbFieldRef field) {
  return field_get(field, WB_SF_VEC3F, "wb_supervisor_field_get_sf_vec3f") ? field->values : NULL;
}

const double *wb_supervisor_field_get_sf_rotation(WbFieldRef field) {
  return field_get(field, WB_SF_ROTATION, "wb_supervisor_field_get_sf_rotation") ? field->values : NULL;
}

const double *wb_supervisor_field_get_sf_color(WbFieldRef field) {
  return field_get(field, WB_SF_COLOR, "wb_supervisor_field_get_sf_color") ? field->values : NULL;
}

const char *wb_supervisor_field_get_sf_string(WbFieldRef field) {
  return field_get(field, WB_SF_STRING, "wb_supervisor_field_get_sf_string") ? field->string : "";
}

WbNodeRef wb_supervisor_field_get_sf_node(WbFieldRef field) {
  if (!field_get(field, WB_SF_NODE, "wb_supervisor_field_get_sf_node"))
    return NULL;
  return node_of((uint32_t)field->values[0]);
}

void wb_supervisor_field_set_sf_bool(WbFieldRef field, bool value) {
  double v = value ? 1.0 : 0.0;
  field_set(field, WB_SF_BOOL, &v, 1, NULL, "wb_supervisor_field_set_sf_bool");
}

void wb_supervisor_field_set_sf_int32(WbFieldRef field, int value) {
  double v = value;
  field_set(field, WB_SF_INT32, &v, 1, NULL, "wb_supervisor_field_set_sf_int32");
}

void wb_supervisor_field_set_sf_float(WbFieldRef field, double value) {
  field_set(field, WB_SF_FLOAT, &value, 1, NULL, "wb_supervisor_field_set_sf_float");
}

void wb_supervisor_field_set_sf_vec2f(WbFieldRef field, const double values[2]) {
  field_set(field, WB_SF_VEC2F, values, 2, NULL, "wb_supervisor_field_set_sf_vec2f");
}

void wb_supervisor_field_set_sf_vec3f(WbFieldRef field, const double values[3]) {
  field_set(field, WB_SF_VEC3F, values, 3, NULL, "wb_supervisor_field_set_sf_vec3f");
}

void wb_supervisor_field_set_sf_rotation(WbFieldRef field, const double values[4]) {
  field_set(field, WB_SF_ROTATION, values, 4, NULL, "wb_supervisor_field_set_sf_rotation");
}

void wb_supervisor_field_set_sf_color(WbFieldRef field, const double values[3]) {
  field_set(field, WB_SF_COLOR, values, 3, NULL, "wb_supervisor_field_set_sf_color");
}

void wb_supervisor_field_set_sf_string(WbFieldRef field, const char *value) {
  field_set(field, WB_SF_STRING, NULL, 0, value ? value : "", "wb_supervisor_field_set_sf_string");
}
