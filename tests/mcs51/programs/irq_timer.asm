; Timer 0 interrupts, the routine reloading the timer (mode 1), the main program in MUL and DIV
; (4 cycles) so the overflow falls in an instruction's earlier cycles (docs/cpu.md: the one
; sampling difference to s51 is the last cycle).
	.area CSEG (ABS,CODE)
	.org 0
	ljmp start
	.org 0x0b
	ljmp t0isr
	.org 0x30
start:	mov sp,#0x60
	mov tmod,#0x01
	mov th0,#0xff
	mov tl0,#0xc2
	mov ie,#0x82
	setb tr0
	mov r6,#40
	mov b,#3
loop:	mov a,r6
	mul ab
	mul ab
	div ab
	mul ab
	djnz r6,loop
	clr ea
halt:	sjmp halt
t0isr:	clr tr0                 ; reloaded while stopped (see timers.asm)
	push acc
	push psw
	mov th0,#0xff
	mov tl0,#0xc0
	setb tr0
	inc r7
	mov a,r7
	add a,0x40
	mov 0x40,a
	pop psw
	pop acc
	reti
