/* Integer work the way SDCC compiles it for the 80C32: 16- and 32-bit arithmetic (its library
 * calls), arrays in internal RAM, function pointers, a CRC and a sort (ucsim cross-check). */
#include <stdint.h>

static uint8_t data[12];
static uint16_t crc;
static uint32_t acc32;

static uint16_t crc16_step(uint16_t c, uint8_t b) {
  uint8_t i;
  c ^= (uint16_t)b << 8;
  for (i = 0; i < 8; ++i) c = (c & 0x8000u) ? (uint16_t)((c << 1) ^ 0x1021u) : (uint16_t)(c << 1);
  return c;
}

static uint8_t add(uint8_t a, uint8_t b) __reentrant { return (uint8_t)(a + b); }
static uint8_t mix(uint8_t a, uint8_t b) __reentrant { return (uint8_t)((a ^ b) * 3u); }

void main(void) {
  uint8_t i, j, t;
  uint8_t (*op[2])(uint8_t, uint8_t) __reentrant = {add, mix};
  for (i = 0; i < sizeof data; ++i) data[i] = (uint8_t)(i * 37u + 11u);
  for (i = 0; i < sizeof data; ++i) data[i] = op[i & 1](data[i], i);
  for (i = 1; i < sizeof data; ++i) { /* insertion sort */
    t = data[i];
    for (j = i; j > 0 && data[j - 1] > t; --j) data[j] = data[j - 1];
    data[j] = t;
  }
  crc = 0xFFFFu;
  for (i = 0; i < sizeof data; ++i) crc = crc16_step(crc, data[i]);
  acc32 = 1;
  for (i = 0; i < 6; ++i) acc32 = acc32 * 7u + crc / (uint16_t)(i + 1) - (uint32_t)data[i] * 1000u;
  for (;;) {
  }
}
