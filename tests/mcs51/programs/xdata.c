/* SDCC's large model: every variable in XDATA (MOVX @DPTR), a struct array, 32-bit and float
 * arithmetic from SDCC's library, a string copy through generic pointers (ucsim cross-check). */
#include <stdint.h>
#include <string.h>

struct sample {
  uint16_t raw;
  float scaled;
};

static struct sample samples[4];
static char text[16];
static float sum;
static int32_t mean;

void main(void) {
  uint8_t i;
  for (i = 0; i < 4; ++i) {
    samples[i].raw = (uint16_t)(i * 1234u + 77u);
    samples[i].scaled = samples[i].raw * 0.125f - 3.5f;
  }
  sum = 0.0f;
  for (i = 0; i < 4; ++i) sum += samples[i].scaled;
  mean = (int32_t)(sum / 4.0f);
  strcpy(text, "DO4 on 80C32");
  text[0] = (char)(text[0] + (char)(mean & 7));
  for (;;) {
  }
}
