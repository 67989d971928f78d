/*
 * dp_slave.h -- the example's DP-slave driver for the VPC3+ in serial mode: one output and one
 * input byte, parameters and configuration checked by the application. Built in one of two
 * configurations, as such drivers are:
 *   interrupt-driven (default)  X/INT unmasked for the events it serves, dp_isr() serves them;
 *   DP_POLLING                  every interrupt masked, dp_poll() from the main loop reads the
 *                               interrupt requests (Int_Req_Reg) and serves them the same way.
 */
#ifndef EXAMPLE_DP_SLAVE_H
#define EXAMPLE_DP_SLAVE_H

#include <stdint.h>

typedef struct dp_app {
  uint16_t ident;
  const uint8_t* cfg; /* the Chk_Cfg bytes the module accepts (also its Read_Cfg) */
  uint8_t cfg_len;
  uint8_t prm_len; /* the whole Set_Prm telegram it accepts */
  /* New outputs (one byte); returns the inputs to hand over next. */
  uint8_t (*exchange)(uint8_t outputs);
} dp_app;

/* main()'s set-up: reset pulse, ASIC check (a wrong chip is a fatal error: the driver stops in a
 * loop, as on the board), registers, buffers, start. */
void dp_init(uint8_t station_address, const dp_app* app);
/* One look at the interrupt requests (DP_POLLING). */
void dp_poll(void);
/* The X/INT interrupt service routine (interrupt-driven). */
void dp_isr(void);

#endif /* EXAMPLE_DP_SLAVE_H */
