/*
 * regatta's Webots controller library: the C API a Webots controller calls, over the
 * controller protocol of regatta (webots/src/protocol.rs holds the contract).
 *
 * Written from Webots' published reference manual: the names, signatures and documented
 * behaviour are Webots'; the code is regatta's. The library keeps every device's state in the
 * controller's process (readings as last received, commands queued), so that reading a sensor
 * costs no exchange: one request and one reply per wb_robot_step.
 */
#include <webots/accelerometer.h>
#include <webots/camera.h>
#include <webots/compass.h>
#include <webots/device.h>
#include <webots/distance_sensor.h>
#include <webots/emitter.h>
#include <webots/gps.h>
#include <webots/gyro.h>
#include <webots/inertial_unit.h>
#include <webots/keyboard.h>
#include <webots/led.h>
#include <webots/light_sensor.h>
#include <webots/motor.h>
#include <webots/position_sensor.h>
#include <webots/receiver.h>
#include <webots/robot.h>
#include <webots/touch_sensor.h>

#include <errno.h>
#include <setjmp.h>
#include <math.h>
#include <stdarg.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/socket.h>
#include <sys/un.h>
#include <unistd.h>

/* The protocol's constants (protocol.rs). */
#define MAGIC 0x42574752u /* "RGWB" little-endian */
#define VERSION 1u
enum {
  KIND_ROTATIONAL_MOTOR = 1,
  KIND_POSITION_SENSOR,
  KIND_DISTANCE_SENSOR,
  KIND_LIGHT_SENSOR,
  KIND_LED,
  KIND_CAMERA,
  KIND_GPS,
  KIND_COMPASS,
  KIND_INERTIAL_UNIT,
  KIND_ACCELEROMETER,
  KIND_GYRO,
  KIND_TOUCH_SENSOR,
  KIND_EMITTER,
  KIND_RECEIVER
};
enum {
  OP_ENABLE = 1,
  OP_MOTOR_POSITION,
  OP_MOTOR_VELOCITY,
  OP_LED_SET,
  OP_EMITTER_SEND,
  OP_EMITTER_CHANNEL,
  OP_EMITTER_RANGE,
  OP_RECEIVER_CHANNEL,
  OP_CUSTOM_DATA
};
enum { STATUS_RUNNING = 0, STATUS_QUIT = 1 };
enum { READING_VALUES = 0, READING_BYTES = 1, READING_PACKETS = 2, READING_CUSTOM_DATA = 3 };

/* A packet a receiver holds. */
typedef struct {
  unsigned char *data;
  int size;
  double strength;
  double direction[3];
} Packet;

typedef struct {
  int kind;
  char *name;
  char *model;
  int n_params;
  double *params;
  int rows;
  double *table; /* rows × 3 */
  int period;    /* ms; 0: disabled */
  int warned_disabled;
  double values[4];
  unsigned char *image;
  int image_size;
  /* motors */
  double target, velocity, acceleration;
  /* LEDs */
  int led;
  /* emitters and receivers */
  int channel;
  double range;
  int sent; /* bytes sent in this step (an emitter's buffer) */
  Packet *packets;
  int n_packets, first_packet, packets_capacity;
} Device;

static struct {
  int fd;
  int initialized;
  int quit;
  double time_step;
  char *name, *model, *custom_data, *project, *world;
  int synchronization, supervisor;
  int n_devices;
  Device *devices;
  double time;
  /* queued commands */
  unsigned char *out;
  size_t out_length, out_capacity;
  int n_commands;
  /* the last frame read */
  unsigned char *in;
  size_t in_capacity, in_length, in_at;
  /* Embedded in a host program (a Gymnasium environment, `regatta_controller_embed`): a
     failure or a vanished simulator ends the call in progress, not the process. */
  int embedded, armed;
} R = {-1};

/* Where an embedded call in progress returns to on a failure. */
static jmp_buf escape;

void regatta_controller_embed(int on) {
  R.embedded = on;
}

/* ---- errors and warnings, in Webots' style ---- */

static void fail(const char *format, ...) __attribute__((format(printf, 1, 2), noreturn));
static void fail(const char *format, ...) {
  va_list args;
  fprintf(stderr, "Error: ");
  va_start(args, format);
  vfprintf(stderr, format, args);
  va_end(args);
  fprintf(stderr, "\n");
  if (R.armed)
    longjmp(escape, 1);
  exit(1);
}

/* The simulator closed the connection: the run has ended (or failed). */
static void gone(void) {
  if (R.armed)
    longjmp(escape, 1);
  exit(0);
}

/* ---- the socket ---- */

static void write_all(const void *data, size_t size) {
  const unsigned char *bytes = data;
  while (size > 0) {
    ssize_t n = write(R.fd, bytes, size);
    if (n < 0 && errno == EINTR)
      continue;
    if (n <= 0)
      gone();
    bytes += n;
    size -= (size_t)n;
  }
}

static void read_all(void *data, size_t size) {
  unsigned char *bytes = data;
  while (size > 0) {
    ssize_t n = read(R.fd, bytes, size);
    if (n < 0 && errno == EINTR)
      continue;
    if (n <= 0)
      gone();
    bytes += n;
    size -= (size_t)n;
  }
}

static void read_frame(void) {
  uint32_t length;
  read_all(&length, 4);
  if (length > R.in_capacity) {
    R.in = realloc(R.in, length);
    if (!R.in)
      fail("out of memory");
    R.in_capacity = length;
  }
  read_all(R.in, length);
  R.in_length = length;
  R.in_at = 0;
}

static const unsigned char *take(size_t n) {
  if (R.in_at + n > R.in_length)
    fail("regatta sent a malformed frame (this library and regatta differ in version?)");
  const unsigned char *p = R.in + R.in_at;
  R.in_at += n;
  return p;
}

static unsigned take_u8(void) {
  return *take(1);
}

static unsigned take_u16(void) {
  uint16_t v;
  memcpy(&v, take(2), 2);
  return v;
}

static uint32_t take_u32(void) {
  uint32_t v;
  memcpy(&v, take(4), 4);
  return v;
}

static double take_f64(void) {
  double v;
  memcpy(&v, take(8), 8);
  return v;
}

static char *take_str(void) {
  uint32_t n = take_u32();
  const unsigned char *p = take(n);
  char *s = malloc(n + 1);
  if (!s)
    fail("out of memory");
  memcpy(s, p, n);
  s[n] = '\0';
  return s;
}

static void put(const void *data, size_t n) {
  if (R.out_length + n > R.out_capacity) {
    size_t capacity = R.out_capacity ? R.out_capacity * 2 : 256;
    while (capacity < R.out_length + n)
      capacity *= 2;
    R.out = realloc(R.out, capacity);
    if (!R.out)
      fail("out of memory");
    R.out_capacity = capacity;
  }
  memcpy(R.out + R.out_length, data, n);
  R.out_length += n;
}

/* The step frame starts with its length (4), kind (1: 0, a step), duration (4) and command
   count (2). */
#define STEP_HEADER 11

static void queue(int op, WbDeviceTag tag, double value) {
  if (R.out_length < STEP_HEADER) {
    unsigned char header[STEP_HEADER] = {0};
    R.out_length = 0;
    put(header, STEP_HEADER);
  }
  uint8_t o = (uint8_t)op;
  uint16_t t = tag;
  put(&o, 1);
  put(&t, 2);
  put(&value, 8);
  R.n_commands++;
}

/* A command followed by bytes (an emitter's packet). */
static void queue_bytes(int op, WbDeviceTag tag, const void *data, int size) {
  queue(op, tag, size);
  put(data, (size_t)size);
}

/* ---- devices ---- */

static Device *device(WbDeviceTag tag, int kind, const char *function) {
  if (!R.initialized)
    fail("%s() called before wb_robot_init()", function);
  if (tag == 0 || tag > R.n_devices) {
    fprintf(stderr, "Error: %s() called with an invalid device tag.\n", function);
    return NULL;
  }
  Device *d = &R.devices[tag - 1];
  if (kind && d->kind != kind) {
    fprintf(stderr, "Error: %s() called with the tag of device \"%s\", which is of another type.\n", function, d->name);
    return NULL;
  }
  return d;
}

static void enable(WbDeviceTag tag, int kind, int period, const char *function) {
  Device *d = device(tag, kind, function);
  if (!d)
    return;
  if (period < 0) {
    fprintf(stderr, "Error: %s() called with a negative sampling period.\n", function);
    return;
  }
  d->period = period;
  d->warned_disabled = 0;
  queue(OP_ENABLE, tag, period);
}

static int sampling_period(WbDeviceTag tag, int kind, const char *function) {
  Device *d = device(tag, kind, function);
  return d ? d->period : 0;
}

static void disabled_warning(Device *d, const char *function, const char *enable_function) {
  if (d->period == 0 && !d->warned_disabled) {
    fprintf(stderr, "Error: %s() called for a disabled device! Please use: %s().\n", function, enable_function);
    d->warned_disabled = 1;
  }
}

static double single_value(WbDeviceTag tag, int kind, const char *function, const char *enable_function) {
  Device *d = device(tag, kind, function);
  if (!d)
    return NAN;
  disabled_warning(d, function, enable_function);
  return d->values[0];
}

static const double *triple(WbDeviceTag tag, int kind, const char *function, const char *enable_function) {
  Device *d = device(tag, kind, function);
  if (!d)
    return NULL;
  disabled_warning(d, function, enable_function);
  return d->values;
}

static double param(const Device *d, int i, double otherwise) {
  return d && i < d->n_params ? d->params[i] : otherwise;
}

/* ---- the robot ---- */

/* Frees what the last connection described, so that `wb_robot_init` can connect again (an
   embedding program's next episode). */
static void forget(void) {
  for (int i = 0; i < R.n_devices; i++) {
    Device *d = &R.devices[i];
    free(d->name);
    free(d->model);
    free(d->params);
    free(d->table);
    free(d->image);
    for (int p = 0; p < d->n_packets; p++)
      free(d->packets[d->first_packet + p].data);
    free(d->packets);
  }
  free(R.devices);
  free(R.name);
  free(R.model);
  free(R.custom_data);
  free(R.project);
  free(R.world);
  R.devices = NULL;
  R.n_devices = 0;
  R.name = R.model = R.custom_data = R.project = R.world = NULL;
  R.quit = 0;
  R.time = 0.0;
  R.out_length = 0;
  R.n_commands = 0;
  R.in_length = R.in_at = 0;
}

static int connect_and_describe(void);

int wb_robot_init(void) {
  if (R.initialized)
    return 1;
  if (R.embedded) {
    if (setjmp(escape)) {
      R.armed = 0;
      if (R.fd >= 0)
        close(R.fd);
      R.fd = -1;
      return 0;
    }
    R.armed = 1;
  }
  int ok = connect_and_describe();
  R.armed = 0;
  return ok;
}

static int connect_and_describe(void) {
  forget();
  const char *url = getenv("REGATTA_CONTROLLER_URL");
  if (!url || !*url)
    url = getenv("WEBOTS_CONTROLLER_URL");
  if (!url || !*url)
    fail("this controller runs under regatta: start it with `regatta run WORLD` (REGATTA_CONTROLLER_URL is not set)");
  if (strncmp(url, "ipc://", 6) == 0 || strncmp(url, "unix:", 5) == 0)
    url = strchr(url, url[0] == 'i' ? '/' : ':') + (url[0] == 'i' ? 2 : 1);
  struct sockaddr_un address;
  memset(&address, 0, sizeof address);
  address.sun_family = AF_UNIX;
  if (strlen(url) >= sizeof address.sun_path)
    fail("the controller socket's path is too long: %s", url);
  strcpy(address.sun_path, url);
  R.fd = socket(AF_UNIX, SOCK_STREAM | SOCK_CLOEXEC, 0);
  if (R.fd < 0 || connect(R.fd, (struct sockaddr *)&address, sizeof address) != 0)
    fail("cannot connect to regatta at %s: %s", url, strerror(errno));
  /* Lines appear as they are printed, as in Webots' console. */
  setvbuf(stdout, NULL, _IOLBF, 0);
  read_frame();
  if (take_u32() != MAGIC || take_u32() != VERSION)
    fail("regatta speaks another version of the controller protocol: recompile the controller");
  R.time_step = take_f64();
  R.name = take_str();
  R.model = take_str();
  R.custom_data = take_str();
  R.project = take_str();
  R.world = take_str();
  R.synchronization = take_u8();
  R.supervisor = take_u8();
  R.n_devices = take_u16();
  R.devices = calloc(R.n_devices ? R.n_devices : 1, sizeof(Device));
  if (!R.devices)
    fail("out of memory");
  for (int i = 0; i < R.n_devices; i++) {
    Device *d = &R.devices[i];
    d->kind = take_u8();
    d->name = take_str();
    d->model = take_str();
    d->n_params = take_u16();
    d->params = calloc(d->n_params ? d->n_params : 1, sizeof(double));
    for (int p = 0; p < d->n_params; p++)
      d->params[p] = take_f64();
    d->rows = take_u16();
    d->table = calloc(d->rows ? 3 * d->rows : 1, sizeof(double));
    for (int r = 0; r < 3 * d->rows; r++)
      d->table[r] = take_f64();
    for (int v = 0; v < 4; v++)
      d->values[v] = NAN;
    d->target = 0.0;
    d->velocity = param(d, 0, 0.0);
    d->channel = (int)param(d, 1, 0);
    d->range = param(d, 2, -1);
  }
  R.initialized = 1;
  return 1;
}

void wb_robot_cleanup(void) {
  if (!R.initialized)
    return;
  if (!R.quit) {
    /* A step of −1 ms: the controller is done, its robot stands still. */
    R.out_length = 0;
    R.n_commands = 0;
    unsigned char header[STEP_HEADER] = {0};
    int32_t duration = -1;
    uint32_t length = STEP_HEADER - 4;
    memcpy(header, &length, 4);
    memcpy(header + 5, &duration, 4);
    write_all(header, STEP_HEADER);
  }
  close(R.fd);
  R.fd = -1;
  R.initialized = 0;
  fflush(stdout);
  fflush(stderr);
}

static void apply_reply(void) {
  R.time = take_f64();
  int status = take_u8();
  int n = take_u16();
  for (int i = 0; i < n; i++) {
    unsigned tag = take_u16();
    unsigned type = take_u8();
    if (tag == 0 && type == READING_CUSTOM_DATA) {
      /* A supervisor wrote this robot's customData. */
      free(R.custom_data);
      R.custom_data = take_str();
      continue;
    }
    if (tag == 0 || tag > (unsigned)R.n_devices)
      fail("regatta sent a reading for device %u, which does not exist", tag);
    Device *d = &R.devices[tag - 1];
    if (type == READING_VALUES) {
      int count = take_u16();
      for (int v = 0; v < count; v++) {
        double x = take_f64();
        if (v < 4)
          d->values[v] = x;
      }
    } else if (type == READING_PACKETS) {
      int count = take_u16();
      for (int k = 0; k < count; k++) {
        double strength = take_f64();
        double direction[3];
        for (int v = 0; v < 3; v++)
          direction[v] = take_f64();
        uint32_t size = take_u32();
        const unsigned char *bytes = take(size);
        int end = d->first_packet + d->n_packets;
        if (end >= d->packets_capacity) {
          /* Compact the queue, then grow it. */
          memmove(d->packets, d->packets + d->first_packet, (size_t)d->n_packets * sizeof(Packet));
          d->first_packet = 0;
          end = d->n_packets;
          if (end >= d->packets_capacity) {
            d->packets_capacity = d->packets_capacity ? 2 * d->packets_capacity : 8;
            d->packets = realloc(d->packets, (size_t)d->packets_capacity * sizeof(Packet));
            if (!d->packets)
              fail("out of memory");
          }
        }
        Packet *packet = &d->packets[end];
        packet->data = malloc(size ? size : 1);
        if (!packet->data)
          fail("out of memory");
        memcpy(packet->data, bytes, size);
        packet->size = (int)size;
        packet->strength = strength;
        memcpy(packet->direction, direction, sizeof direction);
        d->n_packets++;
      }
    } else {
      uint32_t size = take_u32();
      const unsigned char *bytes = take(size);
      if ((int)size != d->image_size) {
        d->image = realloc(d->image, size ? size : 1);
        d->image_size = (int)size;
      }
      memcpy(d->image, bytes, size);
    }
  }
  if (status == STATUS_QUIT)
    R.quit = 1;
}

int wb_robot_step_begin(int duration) {
  if (!R.initialized)
    fail("wb_robot_step() called before wb_robot_init()");
  if (R.quit)
    return -1;
  if (duration < 0)
    duration = 0;
  if (R.out_length < STEP_HEADER) {
    unsigned char header[STEP_HEADER] = {0};
    R.out_length = 0;
    put(header, STEP_HEADER);
  }
  uint32_t length = (uint32_t)(R.out_length - 4);
  int32_t d = duration;
  uint16_t count = (uint16_t)R.n_commands;
  memcpy(R.out, &length, 4);
  R.out[4] = 0;
  memcpy(R.out + 5, &d, 4);
  memcpy(R.out + 9, &count, 2);
  write_all(R.out, R.out_length);
  R.out_length = 0;
  R.n_commands = 0;
  for (int i = 0; i < R.n_devices; i++)
    R.devices[i].sent = 0;
  return 0;
}

int wb_robot_step_end(void) {
  if (R.quit)
    return -1;
  read_frame();
  apply_reply();
  return R.quit ? -1 : 0;
}

int wb_robot_step(int duration) {
  if (R.embedded) {
    if (setjmp(escape)) {
      /* The simulator is gone or the step failed (said on standard error): the run is over
         for this controller. */
      R.armed = 0;
      R.quit = 1;
      return -1;
    }
    R.armed = 1;
  }
  int result = wb_robot_step_begin(duration) < 0 ? -1 : wb_robot_step_end();
  R.armed = 0;
  return result;
}

WbUserInputEvent wb_robot_wait_for_user_input_event(WbUserInputEvent event_type, int timeout) {
  (void)event_type;
  /* No window, no user: time passes as the timeout asks. */
  if (timeout > 0 && wb_robot_step(timeout) < 0)
    return WB_EVENT_QUIT;
  return WB_EVENT_NO_EVENT;
}

const char *wb_robot_get_name(void) {
  return R.name ? R.name : "";
}

const char *wb_robot_get_model(void) {
  return R.model ? R.model : "";
}

const char *wb_robot_get_custom_data(void) {
  return R.custom_data ? R.custom_data : "";
}

void wb_robot_set_custom_data(const char *data) {
  if (!R.initialized)
    fail("wb_robot_set_custom_data() called before wb_robot_init()");
  free(R.custom_data);
  R.custom_data = strdup(data ? data : "");
  queue_bytes(OP_CUSTOM_DATA, 0, R.custom_data, (int)strlen(R.custom_data));
}

const char *wb_robot_get_data(void) {
  return wb_robot_get_custom_data();
}

void wb_robot_set_data(const char *data) {
  wb_robot_set_custom_data(data);
}

WbRobotMode wb_robot_get_mode(void) {
  return WB_MODE_SIMULATION;
}

void wb_robot_set_mode(WbRobotMode mode, const char *arg) {
  (void)arg;
  if (mode != WB_MODE_SIMULATION)
    fprintf(stderr, "Warning: wb_robot_set_mode(): regatta simulates; other modes are not available.\n");
}

bool wb_robot_get_synchronization(void) {
  return R.synchronization != 0;
}

bool wb_robot_get_supervisor(void) {
  return R.supervisor != 0;
}

const char *wb_robot_get_project_path(void) {
  return R.project ? R.project : "";
}

const char *wb_robot_get_world_path(void) {
  return R.world ? R.world : "";
}

double wb_robot_get_basic_time_step(void) {
  return R.time_step;
}

double wb_robot_get_time(void) {
  return R.time;
}

const char *wb_robot_get_urdf(const char *prefix) {
  (void)prefix;
  fprintf(stderr, "Warning: wb_robot_get_urdf(): not available in regatta.\n");
  return "";
}

WbDeviceTag wb_robot_get_device(const char *name) {
  if (!R.initialized)
    fail("wb_robot_get_device() called before wb_robot_init()");
  for (int i = 0; name && i < R.n_devices; i++)
    if (strcmp(R.devices[i].name, name) == 0)
      return (WbDeviceTag)(i + 1);
  fprintf(stderr, "Warning: \"%s\" device not found.\n", name ? name : "(null)");
  return 0;
}

int wb_robot_get_number_of_devices(void) {
  return R.n_devices;
}

WbDeviceTag wb_robot_get_device_by_index(int index) {
  if (index < 0 || index >= R.n_devices) {
    fprintf(stderr, "Error: wb_robot_get_device_by_index(): index %d out of bounds.\n", index);
    return 0;
  }
  return (WbDeviceTag)(index + 1);
}

/* The battery is not simulated: Webots reads −1 without a battery field... */
void wb_robot_battery_sensor_enable(int sampling_period) {
  (void)sampling_period;
  static int warned;
  if (!warned++)
    fprintf(stderr, "Warning: wb_robot_battery_sensor_enable(): regatta does not simulate batteries.\n");
}

void wb_robot_battery_sensor_disable(void) {
}

int wb_robot_battery_sensor_get_sampling_period(void) {
  return 0;
}

double wb_robot_battery_sensor_get_value(void) {
  return NAN;
}

void wb_robot_task_new(void (*task)(void *), void *param) {
  (void)task;
  (void)param;
  fail("wb_robot_task_new(): threads in controllers are not supported by regatta");
}

void *wb_robot_mutex_new(void) {
  return malloc(1);
}

void wb_robot_mutex_lock(void *mutex) {
  (void)mutex;
}

void wb_robot_mutex_unlock(void *mutex) {
  (void)mutex;
}

void wb_robot_mutex_delete(void *mutex) {
  free(mutex);
}

/* ---- devices in general ---- */

static WbNodeType node_type(int kind) {
  switch (kind) {
    case KIND_ROTATIONAL_MOTOR:
      return WB_NODE_ROTATIONAL_MOTOR;
    case KIND_POSITION_SENSOR:
      return WB_NODE_POSITION_SENSOR;
    case KIND_DISTANCE_SENSOR:
      return WB_NODE_DISTANCE_SENSOR;
    case KIND_LIGHT_SENSOR:
      return WB_NODE_LIGHT_SENSOR;
    case KIND_LED:
      return WB_NODE_LED;
    case KIND_CAMERA:
      return WB_NODE_CAMERA;
    case KIND_GPS:
      return WB_NODE_GPS;
    case KIND_COMPASS:
      return WB_NODE_COMPASS;
    case KIND_INERTIAL_UNIT:
      return WB_NODE_INERTIAL_UNIT;
    case KIND_ACCELEROMETER:
      return WB_NODE_ACCELEROMETER;
    case KIND_GYRO:
      return WB_NODE_GYRO;
    case KIND_TOUCH_SENSOR:
      return WB_NODE_TOUCH_SENSOR;
    case KIND_EMITTER:
      return WB_NODE_EMITTER;
    case KIND_RECEIVER:
      return WB_NODE_RECEIVER;
    default:
      return WB_NODE_NO_NODE;
  }
}

const char *wb_device_get_name(WbDeviceTag tag) {
  Device *d = device(tag, 0, "wb_device_get_name");
  return d ? d->name : NULL;
}

const char *wb_device_get_model(WbDeviceTag tag) {
  Device *d = device(tag, 0, "wb_device_get_model");
  return d ? d->model : NULL;
}

WbNodeType wb_device_get_node_type(WbDeviceTag tag) {
  Device *d = device(tag, 0, "wb_device_get_node_type");
  return d ? node_type(d->kind) : WB_NODE_NO_NODE;
}

WbNodeType wb_device_get_type(WbDeviceTag tag) {
  return wb_device_get_node_type(tag);
}

/* ---- motors ---- */

void wb_motor_set_position(WbDeviceTag tag, double position) {
  Device *d = device(tag, KIND_ROTATIONAL_MOTOR, "wb_motor_set_position");
  if (!d)
    return;
  if (isnan(position)) {
    fprintf(stderr, "Error: wb_motor_set_position() called with a NaN value.\n");
    return;
  }
  double low = param(d, 1, 0.0), high = param(d, 2, 0.0);
  if (!isinf(position) && (low != 0.0 || high != 0.0)) {
    if (position < low) {
      fprintf(stderr, "Warning: wb_motor_set_position() called with a position below minPosition (%g < %g): using minPosition.\n", position, low);
      position = low;
    } else if (position > high) {
      fprintf(stderr, "Warning: wb_motor_set_position() called with a position above maxPosition (%g > %g): using maxPosition.\n", position, high);
      position = high;
    }
  }
  d->target = position;
  queue(OP_MOTOR_POSITION, tag, position);
}

void wb_motor_set_velocity(WbDeviceTag tag, double velocity) {
  Device *d = device(tag, KIND_ROTATIONAL_MOTOR, "wb_motor_set_velocity");
  if (!d)
    return;
  if (isnan(velocity)) {
    fprintf(stderr, "Error: wb_motor_set_velocity() called with a NaN value.\n");
    return;
  }
  double max = param(d, 0, 0.0);
  if (!isinf(d->target) && velocity < 0.0) {
    fprintf(stderr, "Warning: wb_motor_set_velocity() called with a negative velocity in position control: using its absolute value.\n");
    velocity = -velocity;
  }
  if (fabs(velocity) > max) {
    fprintf(stderr, "Warning: wb_motor_set_velocity() called with a velocity beyond maxVelocity (|%g| > %g): using maxVelocity.\n", velocity, max);
    velocity = velocity < 0.0 ? -max : max;
  }
  d->velocity = velocity;
  queue(OP_MOTOR_VELOCITY, tag, velocity);
}

void wb_motor_set_acceleration(WbDeviceTag tag, double acceleration) {
  Device *d = device(tag, KIND_ROTATIONAL_MOTOR, "wb_motor_set_acceleration");
  if (d)
    d->acceleration = acceleration; /* wheels reach their speed within a step */
}

static void no_force_control(const char *function) {
  static int warned;
  if (!warned++)
    fprintf(stderr, "Warning: %s(): regatta drives wheels by velocity and position only; force and torque control are not simulated.\n", function);
}

void wb_motor_set_force(WbDeviceTag tag, double force) {
  (void)tag;
  (void)force;
  no_force_control("wb_motor_set_force");
}

void wb_motor_set_torque(WbDeviceTag tag, double torque) {
  (void)tag;
  (void)torque;
  no_force_control("wb_motor_set_torque");
}

void wb_motor_set_available_force(WbDeviceTag tag, double force) {
  (void)tag;
  (void)force;
}

void wb_motor_set_available_torque(WbDeviceTag tag, double torque) {
  (void)tag;
  (void)torque;
}

void wb_motor_set_control_pid(WbDeviceTag tag, double p, double i, double d) {
  (void)tag;
  (void)p;
  (void)i;
  (void)d;
  static int warned;
  if (!warned++)
    fprintf(stderr, "Warning: wb_motor_set_control_pid(): regatta keeps Webots' default P = 10.\n");
}

void wb_motor_enable_force_feedback(WbDeviceTag tag, int sampling_period) {
  (void)tag;
  (void)sampling_period;
  no_force_control("wb_motor_enable_force_feedback");
}

void wb_motor_disable_force_feedback(WbDeviceTag tag) {
  (void)tag;
}

int wb_motor_get_force_feedback_sampling_period(WbDeviceTag tag) {
  (void)tag;
  return 0;
}

double wb_motor_get_force_feedback(WbDeviceTag tag) {
  (void)tag;
  return NAN;
}

void wb_motor_enable_torque_feedback(WbDeviceTag tag, int sampling_period) {
  (void)tag;
  (void)sampling_period;
  no_force_control("wb_motor_enable_torque_feedback");
}

void wb_motor_disable_torque_feedback(WbDeviceTag tag) {
  (void)tag;
}

int wb_motor_get_torque_feedback_sampling_period(WbDeviceTag tag) {
  (void)tag;
  return 0;
}

double wb_motor_get_torque_feedback(WbDeviceTag tag) {
  (void)tag;
  return NAN;
}

WbJointType wb_motor_get_type(WbDeviceTag tag) {
  Device *d = device(tag, KIND_ROTATIONAL_MOTOR, "wb_motor_get_type");
  return d ? WB_ROTATIONAL : WB_NODE_NO_NODE;
}

double wb_motor_get_target_position(WbDeviceTag tag) {
  Device *d = device(tag, KIND_ROTATIONAL_MOTOR, "wb_motor_get_target_position");
  return d ? d->target : NAN;
}

double wb_motor_get_min_position(WbDeviceTag tag) {
  return param(device(tag, KIND_ROTATIONAL_MOTOR, "wb_motor_get_min_position"), 1, NAN);
}

double wb_motor_get_max_position(WbDeviceTag tag) {
  return param(device(tag, KIND_ROTATIONAL_MOTOR, "wb_motor_get_max_position"), 2, NAN);
}

double wb_motor_get_velocity(WbDeviceTag tag) {
  Device *d = device(tag, KIND_ROTATIONAL_MOTOR, "wb_motor_get_velocity");
  return d ? d->velocity : NAN;
}

double wb_motor_get_max_velocity(WbDeviceTag tag) {
  return param(device(tag, KIND_ROTATIONAL_MOTOR, "wb_motor_get_max_velocity"), 0, NAN);
}

double wb_motor_get_acceleration(WbDeviceTag tag) {
  Device *d = device(tag, KIND_ROTATIONAL_MOTOR, "wb_motor_get_acceleration");
  return d ? d->acceleration : NAN;
}

double wb_motor_get_available_force(WbDeviceTag tag) {
  return param(device(tag, KIND_ROTATIONAL_MOTOR, "wb_motor_get_available_force"), 3, NAN);
}

double wb_motor_get_max_force(WbDeviceTag tag) {
  return param(device(tag, KIND_ROTATIONAL_MOTOR, "wb_motor_get_max_force"), 3, NAN);
}

double wb_motor_get_available_torque(WbDeviceTag tag) {
  return param(device(tag, KIND_ROTATIONAL_MOTOR, "wb_motor_get_available_torque"), 3, NAN);
}

double wb_motor_get_max_torque(WbDeviceTag tag) {
  return param(device(tag, KIND_ROTATIONAL_MOTOR, "wb_motor_get_max_torque"), 3, NAN);
}

double wb_motor_get_multiplier(WbDeviceTag tag) {
  return device(tag, KIND_ROTATIONAL_MOTOR, "wb_motor_get_multiplier") ? 1.0 : NAN;
}

WbDeviceTag wb_motor_get_brake(WbDeviceTag tag) {
  (void)tag;
  return 0;
}

WbDeviceTag wb_motor_get_position_sensor(WbDeviceTag tag) {
  return (WbDeviceTag)param(device(tag, KIND_ROTATIONAL_MOTOR, "wb_motor_get_position_sensor"), 4, 0);
}

/* ---- position sensors ---- */

void wb_position_sensor_enable(WbDeviceTag tag, int sampling_period) {
  enable(tag, KIND_POSITION_SENSOR, sampling_period, "wb_position_sensor_enable");
}

void wb_position_sensor_disable(WbDeviceTag tag) {
  enable(tag, KIND_POSITION_SENSOR, 0, "wb_position_sensor_disable");
}

int wb_position_sensor_get_sampling_period(WbDeviceTag tag) {
  return sampling_period(tag, KIND_POSITION_SENSOR, "wb_position_sensor_get_sampling_period");
}

double wb_position_sensor_get_value(WbDeviceTag tag) {
  return single_value(tag, KIND_POSITION_SENSOR, "wb_position_sensor_get_value", "wb_position_sensor_enable");
}

WbNodeType wb_position_sensor_get_type(WbDeviceTag tag) {
  return device(tag, KIND_POSITION_SENSOR, "wb_position_sensor_get_type") ? WB_ROTATIONAL : WB_NODE_NO_NODE;
}

WbDeviceTag wb_position_sensor_get_motor(WbDeviceTag tag) {
  return (WbDeviceTag)param(device(tag, KIND_POSITION_SENSOR, "wb_position_sensor_get_motor"), 0, 0);
}

WbDeviceTag wb_position_sensor_get_brake(WbDeviceTag tag) {
  (void)tag;
  return 0;
}

/* ---- distance sensors ---- */

void wb_distance_sensor_enable(WbDeviceTag tag, int sampling_period) {
  enable(tag, KIND_DISTANCE_SENSOR, sampling_period, "wb_distance_sensor_enable");
}

void wb_distance_sensor_disable(WbDeviceTag tag) {
  enable(tag, KIND_DISTANCE_SENSOR, 0, "wb_distance_sensor_disable");
}

int wb_distance_sensor_get_sampling_period(WbDeviceTag tag) {
  return sampling_period(tag, KIND_DISTANCE_SENSOR, "wb_distance_sensor_get_sampling_period");
}

double wb_distance_sensor_get_value(WbDeviceTag tag) {
  return single_value(tag, KIND_DISTANCE_SENSOR, "wb_distance_sensor_get_value", "wb_distance_sensor_enable");
}

double wb_distance_sensor_get_min_value(WbDeviceTag tag) {
  return param(device(tag, KIND_DISTANCE_SENSOR, "wb_distance_sensor_get_min_value"), 1, NAN);
}

double wb_distance_sensor_get_max_value(WbDeviceTag tag) {
  return param(device(tag, KIND_DISTANCE_SENSOR, "wb_distance_sensor_get_max_value"), 2, NAN);
}

double wb_distance_sensor_get_aperture(WbDeviceTag tag) {
  return param(device(tag, KIND_DISTANCE_SENSOR, "wb_distance_sensor_get_aperture"), 3, NAN);
}

int wb_distance_sensor_get_lookup_table_size(WbDeviceTag tag) {
  Device *d = device(tag, KIND_DISTANCE_SENSOR, "wb_distance_sensor_get_lookup_table_size");
  return d ? d->rows : 0;
}

const double *wb_distance_sensor_get_lookup_table(WbDeviceTag tag) {
  Device *d = device(tag, KIND_DISTANCE_SENSOR, "wb_distance_sensor_get_lookup_table");
  return d ? d->table : NULL;
}

WbDistanceSensorType wb_distance_sensor_get_type(WbDeviceTag tag) {
  return (WbDistanceSensorType)param(device(tag, KIND_DISTANCE_SENSOR, "wb_distance_sensor_get_type"), 0, 0);
}

/* ---- light sensors ---- */

void wb_light_sensor_enable(WbDeviceTag tag, int sampling_period) {
  enable(tag, KIND_LIGHT_SENSOR, sampling_period, "wb_light_sensor_enable");
}

void wb_light_sensor_disable(WbDeviceTag tag) {
  enable(tag, KIND_LIGHT_SENSOR, 0, "wb_light_sensor_disable");
}

int wb_light_sensor_get_sampling_period(WbDeviceTag tag) {
  return sampling_period(tag, KIND_LIGHT_SENSOR, "wb_light_sensor_get_sampling_period");
}

double wb_light_sensor_get_value(WbDeviceTag tag) {
  return single_value(tag, KIND_LIGHT_SENSOR, "wb_light_sensor_get_value", "wb_light_sensor_enable");
}

int wb_light_sensor_get_lookup_table_size(WbDeviceTag tag) {
  Device *d = device(tag, KIND_LIGHT_SENSOR, "wb_light_sensor_get_lookup_table_size");
  return d ? d->rows : 0;
}

const double *wb_light_sensor_get_lookup_table(WbDeviceTag tag) {
  Device *d = device(tag, KIND_LIGHT_SENSOR, "wb_light_sensor_get_lookup_table");
  return d ? d->table : NULL;
}

/* ---- LEDs ---- */

void wb_led_set(WbDeviceTag tag, int value) {
  Device *d = device(tag, KIND_LED, "wb_led_set");
  if (!d)
    return;
  d->led = value;
  queue(OP_LED_SET, tag, value);
}

int wb_led_get(WbDeviceTag tag) {
  Device *d = device(tag, KIND_LED, "wb_led_get");
  return d ? d->led : 0;
}

/* ---- cameras ---- */

void wb_camera_enable(WbDeviceTag tag, int sampling_period) {
  enable(tag, KIND_CAMERA, sampling_period, "wb_camera_enable");
}

void wb_camera_disable(WbDeviceTag tag) {
  enable(tag, KIND_CAMERA, 0, "wb_camera_disable");
}

int wb_camera_get_sampling_period(WbDeviceTag tag) {
  return sampling_period(tag, KIND_CAMERA, "wb_camera_get_sampling_period");
}

const unsigned char *wb_camera_get_image(WbDeviceTag tag) {
  Device *d = device(tag, KIND_CAMERA, "wb_camera_get_image");
  if (!d)
    return NULL;
  disabled_warning(d, "wb_camera_get_image", "wb_camera_enable");
  return d->image;
}

int wb_camera_get_width(WbDeviceTag tag) {
  return (int)param(device(tag, KIND_CAMERA, "wb_camera_get_width"), 0, 0);
}

int wb_camera_get_height(WbDeviceTag tag) {
  return (int)param(device(tag, KIND_CAMERA, "wb_camera_get_height"), 1, 0);
}

double wb_camera_get_fov(WbDeviceTag tag) {
  return param(device(tag, KIND_CAMERA, "wb_camera_get_fov"), 2, NAN);
}

double wb_camera_get_min_fov(WbDeviceTag tag) {
  return wb_camera_get_fov(tag);
}

double wb_camera_get_max_fov(WbDeviceTag tag) {
  return wb_camera_get_fov(tag);
}

void wb_camera_set_fov(WbDeviceTag tag, double fov) {
  (void)fov;
  if (device(tag, KIND_CAMERA, "wb_camera_set_fov"))
    fprintf(stderr, "Warning: wb_camera_set_fov(): the camera has no Zoom; its field of view stays.\n");
}

double wb_camera_get_exposure(WbDeviceTag tag) {
  return device(tag, KIND_CAMERA, "wb_camera_get_exposure") ? 1.0 : NAN;
}

void wb_camera_set_exposure(WbDeviceTag tag, double exposure) {
  (void)tag;
  (void)exposure;
}

double wb_camera_get_focal_length(WbDeviceTag tag) {
  return device(tag, KIND_CAMERA, "wb_camera_get_focal_length") ? 0.0 : NAN;
}

double wb_camera_get_focal_distance(WbDeviceTag tag) {
  return device(tag, KIND_CAMERA, "wb_camera_get_focal_distance") ? 0.0 : NAN;
}

double wb_camera_get_max_focal_distance(WbDeviceTag tag) {
  return wb_camera_get_focal_distance(tag);
}

double wb_camera_get_min_focal_distance(WbDeviceTag tag) {
  return wb_camera_get_focal_distance(tag);
}

void wb_camera_set_focal_distance(WbDeviceTag tag, double focal_distance) {
  (void)tag;
  (void)focal_distance;
}

double wb_camera_get_near(WbDeviceTag tag) {
  return param(device(tag, KIND_CAMERA, "wb_camera_get_near"), 3, NAN);
}

int wb_camera_save_image(WbDeviceTag tag, const char *filename, int quality) {
  (void)filename;
  (void)quality;
  if (device(tag, KIND_CAMERA, "wb_camera_save_image"))
    fprintf(stderr, "Warning: wb_camera_save_image(): not available in regatta (regatta render draws a camera's view).\n");
  return -1;
}

/* ---- devices regatta does not simulate yet: they exist, warn once, and read as a missing
   device does in Webots (no robot has them, so their tags are never valid). ---- */

#define SENSOR_WITHOUT_DEVICE(prefix, KIND)                                           \
  void wb_##prefix##_enable(WbDeviceTag tag, int sampling_period) {                   \
    enable(tag, KIND, sampling_period, "wb_" #prefix "_enable");                      \
  }                                                                                   \
  void wb_##prefix##_disable(WbDeviceTag tag) {                                       \
    enable(tag, KIND, 0, "wb_" #prefix "_disable");                                   \
  }                                                                                   \
  int wb_##prefix##_get_sampling_period(WbDeviceTag tag) {                            \
    return sampling_period(tag, KIND, "wb_" #prefix "_get_sampling_period");          \
  }

SENSOR_WITHOUT_DEVICE(gps, KIND_GPS)
SENSOR_WITHOUT_DEVICE(compass, KIND_COMPASS)
SENSOR_WITHOUT_DEVICE(inertial_unit, KIND_INERTIAL_UNIT)
SENSOR_WITHOUT_DEVICE(accelerometer, KIND_ACCELEROMETER)
SENSOR_WITHOUT_DEVICE(gyro, KIND_GYRO)
SENSOR_WITHOUT_DEVICE(touch_sensor, KIND_TOUCH_SENSOR)

const double *wb_gps_get_values(WbDeviceTag tag) {
  return triple(tag, KIND_GPS, "wb_gps_get_values", "wb_gps_enable");
}

double wb_gps_get_speed(WbDeviceTag tag) {
  Device *d = device(tag, KIND_GPS, "wb_gps_get_speed");
  return d ? d->values[3] : NAN;
}

const double *wb_gps_get_speed_vector(WbDeviceTag tag) {
  (void)tag;
  return NULL;
}

WbGpsCoordinateSystem wb_gps_get_coordinate_system(WbDeviceTag tag) {
  (void)tag;
  return WB_GPS_LOCAL_COORDINATE;
}

const char *wb_gps_convert_to_degrees_minutes_seconds(double decimal_degrees) {
  static char text[64];
  int degrees = (int)decimal_degrees;
  double minutes = (decimal_degrees - degrees) * 60.0;
  int whole_minutes = (int)minutes;
  double seconds = (minutes - whole_minutes) * 60.0;
  snprintf(text, sizeof text, "%d\xc2\xb0 %d\xe2\x80\xb2 %.2f\xe2\x80\xb3", degrees, whole_minutes, seconds);
  return text;
}

const double *wb_compass_get_values(WbDeviceTag tag) {
  return triple(tag, KIND_COMPASS, "wb_compass_get_values", "wb_compass_enable");
}

int wb_compass_get_lookup_table_size(WbDeviceTag tag) {
  Device *d = device(tag, KIND_COMPASS, "wb_compass_get_lookup_table_size");
  return d ? d->rows : 0;
}

const double *wb_compass_get_lookup_table(WbDeviceTag tag) {
  Device *d = device(tag, KIND_COMPASS, "wb_compass_get_lookup_table");
  return d ? d->table : NULL;
}

double wb_inertial_unit_get_noise(WbDeviceTag tag) {
  return param(device(tag, KIND_INERTIAL_UNIT, "wb_inertial_unit_get_noise"), 0, NAN);
}

const double *wb_inertial_unit_get_roll_pitch_yaw(WbDeviceTag tag) {
  return triple(tag, KIND_INERTIAL_UNIT, "wb_inertial_unit_get_roll_pitch_yaw", "wb_inertial_unit_enable");
}

const double *wb_inertial_unit_get_quaternion(WbDeviceTag tag) {
  (void)tag;
  return NULL;
}

const double *wb_accelerometer_get_values(WbDeviceTag tag) {
  return triple(tag, KIND_ACCELEROMETER, "wb_accelerometer_get_values", "wb_accelerometer_enable");
}

int wb_accelerometer_get_lookup_table_size(WbDeviceTag tag) {
  Device *d = device(tag, KIND_ACCELEROMETER, "wb_accelerometer_get_lookup_table_size");
  return d ? d->rows : 0;
}

const double *wb_accelerometer_get_lookup_table(WbDeviceTag tag) {
  Device *d = device(tag, KIND_ACCELEROMETER, "wb_accelerometer_get_lookup_table");
  return d ? d->table : NULL;
}

const double *wb_gyro_get_values(WbDeviceTag tag) {
  return triple(tag, KIND_GYRO, "wb_gyro_get_values", "wb_gyro_enable");
}

int wb_gyro_get_lookup_table_size(WbDeviceTag tag) {
  Device *d = device(tag, KIND_GYRO, "wb_gyro_get_lookup_table_size");
  return d ? d->rows : 0;
}

const double *wb_gyro_get_lookup_table(WbDeviceTag tag) {
  Device *d = device(tag, KIND_GYRO, "wb_gyro_get_lookup_table");
  return d ? d->table : NULL;
}

double wb_touch_sensor_get_value(WbDeviceTag tag) {
  return single_value(tag, KIND_TOUCH_SENSOR, "wb_touch_sensor_get_value", "wb_touch_sensor_enable");
}

const double *wb_touch_sensor_get_values(WbDeviceTag tag) {
  return triple(tag, KIND_TOUCH_SENSOR, "wb_touch_sensor_get_values", "wb_touch_sensor_enable");
}

int wb_touch_sensor_get_lookup_table_size(WbDeviceTag tag) {
  Device *d = device(tag, KIND_TOUCH_SENSOR, "wb_touch_sensor_get_lookup_table_size");
  return d ? d->rows : 0;
}

const double *wb_touch_sensor_get_lookup_table(WbDeviceTag tag) {
  Device *d = device(tag, KIND_TOUCH_SENSOR, "wb_touch_sensor_get_lookup_table");
  return d ? d->table : NULL;
}

WbTouchSensorType wb_touch_sensor_get_type(WbDeviceTag tag) {
  return (WbTouchSensorType)param(device(tag, KIND_TOUCH_SENSOR, "wb_touch_sensor_get_type"), 0, 0);
}

/* ---- emitters and receivers ---- */

int wb_emitter_send(WbDeviceTag tag, const void *data, int size) {
  Device *d = device(tag, KIND_EMITTER, "wb_emitter_send");
  if (!d || size < 0 || (size > 0 && !data))
    return 0;
  int buffer = (int)param(d, 3, -1);
  if (buffer >= 0 && d->sent + size > buffer)
    return 0; /* the buffer is full for this step */
  d->sent += size;
  queue_bytes(OP_EMITTER_SEND, tag, data, size);
  return 1;
}

int wb_emitter_get_buffer_size(WbDeviceTag tag) {
  Device *d = device(tag, KIND_EMITTER, "wb_emitter_get_buffer_size");
  if (!d)
    return -1;
  int buffer = (int)param(d, 3, -1);
  return buffer < 0 ? -1 : buffer - d->sent;
}

int wb_emitter_get_channel(WbDeviceTag tag) {
  Device *d = device(tag, KIND_EMITTER, "wb_emitter_get_channel");
  return d ? d->channel : -1;
}

void wb_emitter_set_channel(WbDeviceTag tag, int channel) {
  Device *d = device(tag, KIND_EMITTER, "wb_emitter_set_channel");
  if (!d)
    return;
  d->channel = channel;
  queue(OP_EMITTER_CHANNEL, tag, channel);
}

double wb_emitter_get_range(WbDeviceTag tag) {
  Device *d = device(tag, KIND_EMITTER, "wb_emitter_get_range");
  return d ? d->range : NAN;
}

void wb_emitter_set_range(WbDeviceTag tag, double range) {
  Device *d = device(tag, KIND_EMITTER, "wb_emitter_set_range");
  if (!d)
    return;
  double max_range = param(d, 4, -1);
  if (max_range >= 0 && (range < 0 || range > max_range)) {
    fprintf(stderr, "Warning: wb_emitter_set_range(): range %g beyond maxRange %g: using maxRange.\n", range, max_range);
    range = max_range;
  }
  d->range = range;
  queue(OP_EMITTER_RANGE, tag, range);
}

void wb_receiver_enable(WbDeviceTag tag, int sampling_period) {
  enable(tag, KIND_RECEIVER, sampling_period, "wb_receiver_enable");
}

void wb_receiver_disable(WbDeviceTag tag) {
  enable(tag, KIND_RECEIVER, 0, "wb_receiver_disable");
}

int wb_receiver_get_sampling_period(WbDeviceTag tag) {
  return sampling_period(tag, KIND_RECEIVER, "wb_receiver_get_sampling_period");
}

void wb_receiver_set_channel(WbDeviceTag tag, int channel) {
  Device *d = device(tag, KIND_RECEIVER, "wb_receiver_set_channel");
  if (!d)
    return;
  d->channel = channel;
  queue(OP_RECEIVER_CHANNEL, tag, channel);
}

int wb_receiver_get_channel(WbDeviceTag tag) {
  Device *d = device(tag, KIND_RECEIVER, "wb_receiver_get_channel");
  return d ? d->channel : -1;
}

int wb_receiver_get_queue_length(WbDeviceTag tag) {
  Device *d = device(tag, KIND_RECEIVER, "wb_receiver_get_queue_length");
  return d ? d->n_packets : 0;
}

static Packet *head(WbDeviceTag tag, const char *function) {
  Device *d = device(tag, KIND_RECEIVER, function);
  if (!d || d->n_packets == 0)
    return NULL;
  return &d->packets[d->first_packet];
}

void wb_receiver_next_packet(WbDeviceTag tag) {
  Device *d = device(tag, KIND_RECEIVER, "wb_receiver_next_packet");
  if (!d || d->n_packets == 0)
    return;
  free(d->packets[d->first_packet].data);
  d->first_packet++;
  d->n_packets--;
  if (d->n_packets == 0)
    d->first_packet = 0;
}

int wb_receiver_get_data_size(WbDeviceTag tag) {
  Packet *p = head(tag, "wb_receiver_get_data_size");
  return p ? p->size : -1;
}

const void *wb_receiver_get_data(WbDeviceTag tag) {
  Packet *p = head(tag, "wb_receiver_get_data");
  return p ? p->data : NULL;
}

double wb_receiver_get_signal_strength(WbDeviceTag tag) {
  Packet *p = head(tag, "wb_receiver_get_signal_strength");
  return p ? p->strength : NAN;
}

const double *wb_receiver_get_emitter_direction(WbDeviceTag tag) {
  Packet *p = head(tag, "wb_receiver_get_emitter_direction");
  return p ? p->direction : NULL;
}

/* ---- the keyboard: no window, no key ---- */

static int keyboard_period;

void wb_keyboard_enable(int sampling_period) {
  keyboard_period = sampling_period;
}

void wb_keyboard_disable(void) {
  keyboard_period = 0;
}

int wb_keyboard_get_sampling_period(void) {
  return keyboard_period;
}

int wb_keyboard_get_key(void) {
  return -1;
}

/* The supervisor's functions share this file's connection. */
#include "supervisor.c"
