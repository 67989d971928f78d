/* plugin.c -- an example firmware as a run-time plug-in (dpc31/dpc31_firmware.h): the same
 * objects as the built-in one, and the descriptor exported under the well-known symbol.
 * DPC31_PLUGIN_FIRMWARE names the descriptor (firmware/CMakeLists.txt). */
#include "firmware.h"

extern const dpc31_firmware DPC31_PLUGIN_FIRMWARE;
DPC31_FIRMWARE_EXPORT(DPC31_PLUGIN_FIRMWARE);
