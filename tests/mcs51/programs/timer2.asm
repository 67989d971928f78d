; Timer 2 (8052): 16-bit auto-reload from RCAP2, capture mode, counted while polled (a running
; timer touched only by one-cycle instructions, as in timers.asm).
	.area CSEG (ABS,CODE)
	.org 0
	ljmp start
	.org 0x30
start:	mov sp,#0x60
	mov rcap2h,#0xff
	mov rcap2l,#0xd0
	mov th2,#0xff
	mov tl2,#0xf0
	setb 0xca               ; TR2, auto-reload
	mov r7,#4
w0:	mov a,t2con
	jnb acc.7,w0             ; TF2
	clr 0xcf
	mov a,tl2
	mov r0,a
	djnz r7,w0
	mov t2con,#0x00
	mov tl2,#0x00
	mov th2,#0xff
	mov t2con,#0x01         ; capture mode: overflows to 0000h
	setb 0xca
	mov b,#20
w1:	mov a,t2con
	jb acc.7,w2
	djnz b,w1
w2:	mov a,tl2
	mov r1,a
	clr 0xca                ; TR2 off
	mov r2,th2
	mov r3,tl2
halt:	sjmp halt
