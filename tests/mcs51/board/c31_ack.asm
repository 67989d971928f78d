; The DPC31's internal C31 (Cpu51Board::C31, docs/dpc31.md "The C31"), linked at 0000h and put
; into the chip's code area at 1000h: unmask User_Timer_Clock in the C31's Int_Mask_Reg, raise it
; by writing Int_Req_Reg, take INT0 (level) from the C31's interrupt controller and acknowledge
; it; then rewrite the operand of an instruction of its own in the chip's RAM, run it, and store
; the result in the user area. Machine cycles in brackets (docs/cpu.md, "MOVX timing").
	.area CSEG (ABS,CODE)
	.org 0
	ljmp start              ; [0,2)
	.org 0x03
	ljmp isr                ; [17,19)
	.org 0x30
start:	mov dptr,#0x0004        ; [2,4)
	mov a,#0xef             ; [4,5)
	movx @dptr,a            ; [5,7)   Int_Mask_Reg low byte: User_Timer_Clock unmasked
	mov ie,#0x81            ; [7,9)   EA, EX0; IT0 = 0: INT0 level-triggered
	mov dptr,#0x0000        ; [9,11)
	mov a,#0x10             ; [11,12)
	movx @dptr,a            ; [12,14) Int_Req_Reg bit 4: the C31's interrupt, INT0 sampled low in 13
	nop                     ; [14,15) polled; the call is [15,17)
	mov dptr,#0x1000+patch+1 ; [26,28) the operand of `patch` in the chip's RAM (1047h)
	mov a,#0x77             ; [28,29)
	movx @dptr,a            ; [29,31)
patch:	mov a,#0x00             ; [31,32) fetched from the chip's RAM: A = 77h
	mov dptr,#0x08a0        ; [32,34)
	movx @dptr,a            ; [34,36) the user area's first byte
	sjmp .
isr:	mov dptr,#0x0002        ; [19,21)
	mov a,#0x10             ; [21,22)
	movx @dptr,a            ; [22,24) Int_Ack_Reg bit 4: the C31's interrupt inactive
	reti                    ; [24,26)
