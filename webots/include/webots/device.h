/* regatta's Webots controller API: devices in general (written from Webots' published reference). */
#ifndef WB_DEVICE_H
#define WB_DEVICE_H

#include "nodes.h"
#include "types.h"

#ifdef __cplusplus
extern "C" {
#endif

const char *wb_device_get_name(WbDeviceTag device);
const char *wb_device_get_model(WbDeviceTag device);
WbNodeType wb_device_get_node_type(WbDeviceTag device);
/* Deprecated in Webots, kept for older controllers. */
WbNodeType wb_device_get_type(WbDeviceTag device);

#ifdef __cplusplus
}
#endif

#endif
