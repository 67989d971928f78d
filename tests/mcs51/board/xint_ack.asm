; The 80C32 with the chip at XDATA 8000h (Cpu51BoardTest): unmask User_Timer_Clock, raise it by
; writing Int_Req_Reg (the SPC3's test write), take the INT0 interrupt (level) from X/INT and
; acknowledge it in the routine. Machine cycles in brackets (docs/cpu.md, "MOVX timing").
	.area CSEG (ABS,CODE)
	.org 0
	ljmp start              ; [0,2)
	.org 0x03
	ljmp isr                ; [17,19)
	.org 0x30
start:	mov dptr,#0x8004        ; [2,4)
	mov a,#0xef             ; [4,5)
	movx @dptr,a            ; [5,7)   Int_Mask_Reg low byte: User_Timer_Clock unmasked
	mov ie,#0x81            ; [7,9)   EA, EX0; IT0 = 0: INT0 level-triggered
	mov dptr,#0x8000        ; [9,11)
	mov a,#0x10             ; [11,12)
	movx @dptr,a            ; [12,14) Int_Req_Reg bit 4: X/INT active, INT0 sampled low in 13
	nop                     ; [14,15) polled
	nop                     ; after the call
	sjmp .                  ; (the call is [15,17))
isr:	mov dptr,#0x8002        ; [19,21)
	mov a,#0x10             ; [21,22)
	movx @dptr,a            ; [22,24) Int_Ack_Reg bit 4: X/INT inactive
	reti
