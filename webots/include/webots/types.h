/* regatta's Webots controller API: basic types (written from Webots' published reference). */
#ifndef WB_TYPES_H
#define WB_TYPES_H

#include <math.h> /* INFINITY, which controllers pass to wb_motor_set_position */
#include <stdbool.h>

#ifdef __cplusplus
extern "C" {
#endif

/* A device of the robot: 0 means "no device". */
typedef unsigned short WbDeviceTag;

typedef struct WbNodeStructPrivate *WbNodeRef;
typedef struct WbFieldStructPrivate *WbFieldRef;
typedef struct WbProtoInfoStructPrivate *WbProtoRef;

typedef const unsigned char *WbImageRef;

#ifdef __cplusplus
}
#endif

#endif
