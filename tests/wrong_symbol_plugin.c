/* Libraries that export a plug-in's entry name as the wrong kind of symbol, as one not built from
 * our headers may (another language, a wrong file): a host refuses each with one line, exit 2,
 * and never reads data as the descriptor's pointer or calls data (tests/bad_input_test.cpp,
 * BadInput.PluginEntrySymbolsOfTheWrongKindAreRefused), one per macro (tests/CMakeLists.txt):
 *   FW_INT    dpc31_firmware_descriptor is an int (4 bytes of data), not a pointer
 *   FW_FUNC   dpc31_firmware_descriptor is a function
 *   RTL_INT   dpc31_rtl_model_get (dpc31 cosim --rtl-model) is an int, not a function */
#define EXPORT __attribute__((visibility("default")))

#if defined(FW_INT)
EXPORT int dpc31_firmware_descriptor = 5;
#elif defined(FW_FUNC)
EXPORT int dpc31_firmware_descriptor(void);
int dpc31_firmware_descriptor(void) { return 5; }
#elif defined(RTL_INT)
EXPORT int dpc31_rtl_model_get = 0;
#endif
