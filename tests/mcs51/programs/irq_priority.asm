; The two priority levels: a high timer 1 routine sets the low requests TF0, IE0 and IE1 (edge
; mode); after its RETI and one instruction they are called in polling order, one at a time;
; a low routine is preempted by the high timer 1 overflow (in a MUL's earlier cycle).
	.area CSEG (ABS,CODE)
	.org 0
	ljmp start
	.org 0x03
	ljmp ie0isr
	.org 0x0b
	ljmp t0isr
	.org 0x13
	ljmp ie1isr
	.org 0x1b
	ljmp t1isr
	.org 0x40
start:	mov sp,#0x70
	mov tcon,#0x05          ; IT0, IT1: edge-triggered, flags latched
	mov tmod,#0x10          ; timer 1 mode 1, timer 0 stopped
	mov ip,#0x08            ; PT1 high
	mov th1,#0xff
	mov tl1,#0xe2
	mov ie,#0x8f
	setb tr1
	mov b,#5
main:	mov a,r0
	mul ab
	mul ab
	mul ab
	mov a,r0
	cjne a,#3,main
	clr ea
halt:	sjmp halt
t1isr:	clr tr1
	inc 0x30
	mov a,0x30
	cjne a,#1,t1b
	setb tf0
	setb ie0
	setb ie1
t1b:	reti
ie0isr:	inc r0
	mov 0x31,r0
	reti
t0isr:	inc r0
	mov 0x32,r0
	reti
ie1isr:	inc r0
	mov 0x33,r0
	mov th1,#0xff           ; a high overflow during this low routine
	mov tl1,#0xf8
	setb tr1
	mov a,#9
	mul ab
	mul ab
	mul ab
	mul ab
	mov 0x34,r0
	reti
