; --trace-cpu's idle and interrupt lines (BridgeCpu.idle_timer_trace): timer 0 in mode 2
; overflows every 10 machine cycles and wakes the CPU from idle; its routine is a RETI. Machine
; cycles in brackets (docs/cpu.md: an instruction acts at the end of its last cycle, a flag is
; sampled at S5P2 and polled in the next cycle, the call is a 2-cycle LCALL; in idle the
; peripherals run).
	.area CSEG (ABS,CODE)
	.org 0
	ljmp start              ; [0,2)
	.org 0x0b
	reti                    ; [24,26), [34,36), ...
	.org 0x30
start:	mov tmod,#0x02          ; [2,4)   timer 0: 8-bit auto-reload
	mov th0,#0xf6           ; [4,6)
	mov tl0,#0xf6           ; [6,8)
	mov ie,#0x82            ; [8,10)  EA, ET0
	setb tr0                ; [10,11) counts from cycle 11: F7h in 11, ..., 00h (TF0) in 20
loop:	orl pcon,#0x01          ; [11,13), [28,30), ... idle from 13 on
	sjmp loop               ; [26,28), [36,38), ... after each RETI
