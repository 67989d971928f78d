##
## This file is part of the libsigrokdecode project.
##
## Copyright (C) 2026 The dpc31emu authors
##
## This program is free software; you can redistribute it and/or modify
## it under the terms of the GNU General Public License as published by
## the Free Software Foundation; either version 2 of the License, or
## (at your option) any later version.
##
## This program is distributed in the hope that it will be useful,
## but WITHOUT ANY WARRANTY; without even the implied warranty of
## MERCHANTABILITY or FITNESS FOR A PARTICULAR PURPOSE.  See the
## GNU General Public License for more details.
##
## You should have received a copy of the GNU General Public License
## along with this program; if not, see <http://www.gnu.org/licenses/>.
##

'''
This decoder stacks on top of the 'uart' PD and decodes PROFIBUS DP
telegrams (the FDL layer of EN 50170 / IEC 61158-3-3 and the DP and DPV1
services above it): SD1, SD2, SD3, SD4 (token) and SC (short
acknowledge), DA/SA with the SAP extension bit, FC (request/response,
FCB/FCV, response codes), DSAP/SSAP and the DP service they mean, the
DPV1 PDUs (MSAC_C1/MSAC_C2 Read, Write, Alarm_Ack, Initiate, Abort,
Data_Transport, Idle and negative responses), the FCS and end delimiter,
and the bus timing: the idle time before each request (TSYN), the slave's
answer delay (TSDR) and answers later than the slot time.

Set up the UART decoder for PROFIBUS: 8 data bits, even parity, 1 stop
bit, the bus's baud rate. PROFIBUS is half duplex: connect the bus
(RS-485 receiver output) to RX; a capture with the master's and the
slave's lines apart (a slave's RxD and TxD) goes to RX and TX, and both
are decoded as one bus.
'''

from .pd import Decoder
