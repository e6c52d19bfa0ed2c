/* regatta's Webots controller API: emitters (written from Webots' published reference). */
#ifndef WB_EMITTER_H
#define WB_EMITTER_H

#include "types.h"

#ifdef __cplusplus
extern "C" {
#endif

#define WB_CHANNEL_BROADCAST -1

int wb_emitter_send(WbDeviceTag tag, const void *data, int size);
int wb_emitter_get_buffer_size(WbDeviceTag tag);
int wb_emitter_get_channel(WbDeviceTag tag);
void wb_emitter_set_channel(WbDeviceTag tag, int channel);
double wb_emitter_get_range(WbDeviceTag tag);
void wb_emitter_set_range(WbDeviceTag tag, double range);

#ifdef __cplusplus
}
#endif

#endif
