/* regatta's Webots controller API: the robot (written from Webots' published reference).
   Compiled against regatta's controller library: the controller runs in lock-step with
   regatta's simulation, and every call keeps Webots' documented meaning. */
#ifndef WB_ROBOT_H
#define WB_ROBOT_H

#define WB_USING_C_API
#include "types.h"
#include "nodes.h"

#ifdef __cplusplus
extern "C" {
#endif

typedef enum { WB_MODE_SIMULATION = 0, WB_MODE_CROSS_COMPILATION, WB_MODE_REMOTE_CONTROL } WbRobotMode;

typedef enum {
  WB_EVENT_QUIT = -1,
  WB_EVENT_NO_EVENT = 0,
  WB_EVENT_MOUSE_CLICK = 1,
  WB_EVENT_MOUSE_MOVE = 2,
  WB_EVENT_KEYBOARD = 4,
  WB_EVENT_JOYSTICK_BUTTON = 8,
  WB_EVENT_JOYSTICK_AXIS = 16,
  WB_EVENT_JOYSTICK_POV = 32
} WbUserInputEvent;

int wb_robot_init(void);
void wb_robot_cleanup(void);
int wb_robot_step(int duration);
int wb_robot_step_begin(int duration);
int wb_robot_step_end(void);
WbUserInputEvent wb_robot_wait_for_user_input_event(WbUserInputEvent event_type, int timeout);

const char *wb_robot_get_name(void);
const char *wb_robot_get_model(void);
const char *wb_robot_get_custom_data(void);
void wb_robot_set_custom_data(const char *data);
WbRobotMode wb_robot_get_mode(void);
void wb_robot_set_mode(WbRobotMode mode, const char *arg);
bool wb_robot_get_synchronization(void);
bool wb_robot_get_supervisor(void);
const char *wb_robot_get_project_path(void);
const char *wb_robot_get_world_path(void);
double wb_robot_get_basic_time_step(void);
double wb_robot_get_time(void);
const char *wb_robot_get_urdf(const char *prefix);

WbDeviceTag wb_robot_get_device(const char *name);
int wb_robot_get_number_of_devices(void);
WbDeviceTag wb_robot_get_device_by_index(int index);

void wb_robot_battery_sensor_enable(int sampling_period);
void wb_robot_battery_sensor_disable(void);
int wb_robot_battery_sensor_get_sampling_period(void);
double wb_robot_battery_sensor_get_value(void);

void wb_robot_task_new(void (*task)(void *), void *param);
void *wb_robot_mutex_new(void);
void wb_robot_mutex_lock(void *mutex);
void wb_robot_mutex_unlock(void *mutex);
void wb_robot_mutex_delete(void *mutex);

const char *wb_robot_get_data(void); /* deprecated */
void wb_robot_set_data(const char *data); /* deprecated */

#ifdef __cplusplus
}
#endif

#endif
