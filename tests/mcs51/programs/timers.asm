; Timers 0 and 1 in modes 0..3, polled (no interrupts): TL/TH read back while they run, so each
; instruction's cycles and the instant a timer starts counting are compared. A running timer is
; touched only by one-cycle instructions: s51 lets a multi-cycle instruction act after its first
; cycle, the manual at the end of its last (docs/cpu.md).
	.area CSEG (ABS,CODE)
	.org 0
	ljmp start
	.org 0x30
start:	mov sp,#0x60
	mov tmod,#0x00          ; mode 0: 13 bits
	mov th0,#0xff
	mov tl0,#0x10
	setb tr0
	mov a,tl0
w0:	mov a,tcon
	jnb acc.5,w0
	mov a,tl0
	mov r0,a
	mov a,th0
	mov r1,a
	clr tr0
	clr tf0
	mov tmod,#0x11          ; mode 1 on both
	mov th1,#0xff
	mov tl1,#0xe0
	mov th0,#0xff
	mov tl0,#0xc0
	setb tr1
	setb tr0
w1:	mov a,tcon
	jnb acc.7,w1
	mov a,tl0
	mov r2,a
	mov a,tl1
	mov r3,a
	clr tf1
	clr tr1
	clr tr0
	mov tmod,#0x22          ; mode 2: reload from TH
	mov th0,#0xf0
	mov tl0,#0xf0
	clr tf0
	mov r4,#3
	setb tr0
w2:	mov a,tcon
	jnb acc.5,w2
	clr tf0
	mov a,tl0
	djnz r4,w2
	clr tr0
	mov tmod,#0x03          ; mode 3: TL0 under TR0, TH0 under TR1 with TF1
	mov tl0,#0xf8
	mov th0,#0xfc
	setb tr0
	setb tr1
w3:	mov a,tcon
	jnb acc.7,w3
	mov a,tl0
	mov r5,a
	mov a,th0
	mov r6,a
	clr tr0
	clr tr1
	jbc tf0,w4
w4:	mov b,tl0
	mov tmod,#0x10
	mov a,#7
	mul ab
	mov r7,a
halt:	sjmp halt
