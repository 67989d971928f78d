; AJMP and ACALL into every page of the first 2 KB (opcodes x1h), JMP @A+DPTR through a
; table, RETI outside an interrupt (a return that ends no level), MOVC A,@A+PC, DJNZ and
; CJNE on every register. Main program in page 4 (0400h..047Fh).
	.area CSEG (ABS,CODE)
	.org 0
	ljmp main
	.org 0x0080
p0s:	inc r2
	ret
	.org 0x00c0
p0j:	inc r3
	ajmp r0
	.org 0x0180
p1s:	inc r2
	ret
	.org 0x01c0
p1j:	inc r3
	ajmp r1
	.org 0x0280
p2s:	inc r2
	ret
	.org 0x02c0
p2j:	inc r3
	ajmp r2
	.org 0x0380
p3s:	inc r2
	ret
	.org 0x03c0
p3j:	inc r3
	ajmp r3
	.org 0x0480
p4s:	inc r2
	ret
	.org 0x04c0
p4j:	inc r3
	ajmp r4
	.org 0x0580
p5s:	inc r2
	ret
	.org 0x05c0
p5j:	inc r3
	ajmp r5
	.org 0x0680
p6s:	inc r2
	ret
	.org 0x06c0
p6j:	inc r3
	ajmp r6
	.org 0x0780
p7s:	inc r2
	ret
	.org 0x07c0
p7j:	inc r3
	ajmp r7
	.org 0x0400
main:	mov sp,#0x60
	acall p0s
	ajmp p0j
r0:
	acall p1s
	ajmp p1j
r1:
	acall p2s
	ajmp p2j
r2:
	acall p3s
	ajmp p3j
r3:
	acall p4s
	ajmp p4j
r4:
	acall p5s
	ajmp p5j
r5:
	acall p6s
	ajmp p6j
r6:
	acall p7s
	ajmp p7j
r7:
	lcall more
halt:	sjmp halt
	.org 0x0800
more:	mov dptr,#tbl
	mov r5,#0
jtl:	mov a,r5
	rl a
	jmp @a+dptr
tbl:	sjmp t0
	sjmp t1
	sjmp t2
	sjmp t3
t0:	inc r6
	sjmp tn
t1:	mov a,#0x11
	sjmp tn
t2:	mov b,#0x22
	sjmp tn
t3:	acall asreti
tn:	inc r5
	cjne r5,#4,jtl
	mov a,#2
	movc a,@a+pc
	sjmp pc1
	.db 0x5a, 0xa5, 0x3c
pc1:	mov r7,a
	mov r0,#3
d0:	djnz r0,d0
	mov r0,#0x40
c0:	inc r0
	cjne r0,#0x42,c0
	mov r1,#3
d1:	djnz r1,d1
	mov r1,#0x41
c1:	inc r1
	cjne r1,#0x43,c1
	mov r2,#3
d2:	djnz r2,d2
	mov r2,#0x42
c2:	inc r2
	cjne r2,#0x44,c2
	mov r3,#3
d3:	djnz r3,d3
	mov r3,#0x43
c3:	inc r3
	cjne r3,#0x45,c3
	mov r4,#3
d4:	djnz r4,d4
	mov r4,#0x44
c4:	inc r4
	cjne r4,#0x46,c4
	mov r5,#3
d5:	djnz r5,d5
	mov r5,#0x45
c5:	inc r5
	cjne r5,#0x47,c5
	mov r6,#3
d6:	djnz r6,d6
	mov r6,#0x46
c6:	inc r6
	cjne r6,#0x48,c6
	mov r7,#3
d7:	djnz r7,d7
	mov r7,#0x47
c7:	inc r7
	cjne r7,#0x49,c7
	mov r0,#0x30
	mov @r0,#7
ci0:	inc @r0
	cjne @r0,#9,ci0
	mov r1,#0x31
	mov @r1,#1
ci1:	dec @r1
	cjne @r1,#0xfe,ci1
	mov 0x32,#4
dd:	djnz 0x32,dd
	mov a,#5
ca:	dec a
	cjne a,0x33,ca
	ret
asreti:	mov a,#0x33
	reti
