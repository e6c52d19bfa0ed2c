/* Obstacle avoidance for the e-puck: each wheel's speed is a weighted sum of the eight
   proximity sensors (the near sensors on one side slow the wheel on the other), as a
   Braitenberg vehicle. */
#include <stdio.h>
#include <webots/distance_sensor.h>
#include <webots/led.h>
#include <webots/motor.h>
#include <webots/robot.h>

#define TIME_STEP 32
#define MAX_SPEED 6.28

int main(int argc, char **argv) {
  wb_robot_init();
  const char *names[8] = {"ps0", "ps1", "ps2", "ps3", "ps4", "ps5", "ps6", "ps7"};
  WbDeviceTag sensors[8];
  for (int i = 0; i < 8; i++) {
    sensors[i] = wb_robot_get_device(names[i]);
    wb_distance_sensor_enable(sensors[i], TIME_STEP);
  }
  WbDeviceTag left = wb_robot_get_device("left wheel motor");
  WbDeviceTag right = wb_robot_get_device("right wheel motor");
  wb_motor_set_position(left, INFINITY);
  wb_motor_set_position(right, INFINITY);
  wb_motor_set_velocity(left, 0.0);
  wb_motor_set_velocity(right, 0.0);
  /* Sensors 0–2 look right and ahead, 5–7 left and ahead. */
  const double weights_left[8] = {-1.3, -1.0, -0.6, 0.0, 0.0, 0.6, 1.0, 1.3};
  const double weights_right[8] = {1.3, 1.0, 0.6, 0.0, 0.0, -0.6, -1.0, -1.3};
  /* The front LED blinks once a second. */
  WbDeviceTag front = wb_robot_get_device("led9");
  int steps = 0;
  while (wb_robot_step(TIME_STEP) != -1) {
    if (steps % 16 == 0)
      wb_led_set(front, !wb_led_get(front));
    double l = 0.5 * MAX_SPEED, r = 0.5 * MAX_SPEED;
    for (int i = 0; i < 8; i++) {
      double v = wb_distance_sensor_get_value(sensors[i]);
      if (v != v)
        v = 0.0;
      double x = (v - 70.0) / 1000.0;
      if (x < 0.0)
        x = 0.0;
      l += weights_left[i] * x * MAX_SPEED;
      r += weights_right[i] * x * MAX_SPEED;
    }
    if (l > MAX_SPEED) l = MAX_SPEED;
    if (l < -MAX_SPEED) l = -MAX_SPEED;
    if (r > MAX_SPEED) r = MAX_SPEED;
    if (r < -MAX_SPEED) r = -MAX_SPEED;
    wb_motor_set_velocity(left, l);
    wb_motor_set_velocity(right, r);
    if (++steps % 625 == 0)
      printf("t = %.3f s: ps0 %.1f, ps7 %.1f, led9 %d\n", wb_robot_get_time(), wb_distance_sensor_get_value(sensors[0]),
             wb_distance_sensor_get_value(sensors[7]), wb_led_get(front));
  }
  wb_robot_cleanup();
  return 0;
}
