; The chip's own event on INT0 (Cpu51BoardTest): User_Timer_Clock unmasked, the chip started;
; the main loop in MUL (4 cycles) and SJMP (2). Machine cycles in brackets (docs/cpu.md).
	.area CSEG (ABS,CODE)
	.org 0
	ljmp start              ; [0,2)
	.org 0x03
	ljmp isr
	.org 0x30
start:	mov dptr,#0x8004        ; [2,4)
	mov a,#0xef             ; [4,5)
	movx @dptr,a            ; [5,7)   Int_Mask_Reg low byte: User_Timer_Clock unmasked
	mov ie,#0x81            ; [7,9)   EA, EX0; INT0 level-triggered
	mov dptr,#0x8008        ; [9,11)
	mov a,#0x01             ; [11,12)
	movx @dptr,a            ; [12,14) Mode_Reg1_S: Start_SPC3
loop:	mul ab                  ; [14 + 6k, 18 + 6k)
	sjmp loop               ; [18 + 6k, 20 + 6k)
isr:	mov dptr,#0x8002
	mov a,#0x10
	movx @dptr,a            ; Int_Ack_Reg bit 4: X/INT inactive
	clr ea                  ; one event is enough
	reti
