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

import sigrokdecode as srd

# Telegram layout (EN 50170 / IEC 61158-3-3): a character is 11 bits (start,
# 8 data LSB first, even parity, stop); FCS is the sum of DA .. the last data
# unit byte, modulo 256; ED = 16h.
SD1, SD2, SD3, SD4, SC, ED = 0x10, 0x68, 0xA2, 0xDC, 0xE5, 0x16
BITS_PER_CHAR = 11
TSYN_BITS = 33          # idle bit times before a request (the receiver's sync)
BROADCAST = 127

# The PROFIBUS baud rates: a measured character length snaps to one of them.
RATES = (9600, 19200, 31250, 45450, 93750, 187500, 500000, 1500000, 3000000,
         6000000, 12000000)
# The usual slot time (bit times) of a DP master per rate, used unless the
# 'slot_time' option names one.
DEFAULT_SLOT = {9600: 100, 19200: 100, 31250: 100, 45450: 100, 93750: 100,
                187500: 100, 500000: 200, 1500000: 300, 3000000: 400,
                6000000: 600, 12000000: 1000}

SD_NAMES = {SD1: 'SD1', SD2: 'SD2', SD3: 'SD3', SD4: 'SD4', SC: 'SC'}
REQ_FC = {0x3: 'SDA_low', 0x4: 'SDN_low', 0x5: 'SDA_high', 0x6: 'SDN_high',
          0x7: 'DDB', 0x9: 'FDL_Status', 0xC: 'SRD_low', 0xD: 'SRD_high',
          0xE: 'Ident', 0xF: 'LSAP_Status'}
# Requests that ask for an answer (the others are sent and not acknowledged).
REPLY_FC = (0x3, 0x5, 0x9, 0xC, 0xD, 0xE, 0xF)
RES_FC = {0x0: 'OK', 0x1: 'UE', 0x2: 'RR', 0x3: 'RS', 0x8: 'DL', 0x9: 'NR',
          0xA: 'DH', 0xC: 'RDL', 0xD: 'RDH'}
STATION_TYPE = ('slave', 'master not ready', 'master ready',
                'master in ring')
DP_SAPS = {49: 'MSAC_C2_Initiate', 50: 'MSAC_C1_Alarm', 51: 'MSAC_C1',
           53: 'Set_Ext_Prm', 55: 'Set_Slave_Add', 56: 'Rd_Inp',
           57: 'Rd_Outp', 58: 'Global_Control', 59: 'Get_Cfg',
           60: 'Slave_Diag', 61: 'Set_Prm', 62: 'Chk_Cfg'}
DPV1_FUNCS = {0x5E: 'Read', 0x5F: 'Write', 0x5C: 'Alarm_Ack',
              0x57: 'Initiate', 0x58: 'Abort', 0x51: 'Data_Transport',
              0x48: 'Idle', 0x56: 'Resource_Manager'}
ERROR_CLASS = {0xA: 'application', 0xB: 'access', 0xC: 'resource'}
ERROR_CODE_1 = {0xA0: 'read error', 0xA1: 'write error',
                0xA2: 'module failure', 0xA8: 'version conflict',
                0xA9: 'feature not supported', 0xB0: 'invalid index',
                0xB1: 'write length error', 0xB2: 'invalid slot',
                0xB3: 'type conflict', 0xB4: 'invalid area',
                0xB5: 'state conflict', 0xB6: 'access denied',
                0xB7: 'invalid range', 0xB8: 'invalid parameter',
                0xB9: 'invalid type', 0xC0: 'read constrain conflict',
                0xC1: 'write constrain conflict', 0xC2: 'resource busy',
                0xC3: 'resource unavailable'}
ERROR_DECODE = {128: 'DPV1', 254: 'FMS', 255: 'HART'}
ALARM_TYPES = {1: 'Diagnostic', 2: 'Process', 3: 'Pull', 4: 'Plug',
               5: 'Status', 6: 'Update'}
GC_BITS = ((5, 'Sync'), (4, 'Unsync'), (3, 'Freeze'), (2, 'Unfreeze'),
           (1, 'Clear_Data'))

(A_TELEGRAM, A_SD, A_LE, A_ADDR, A_FC, A_SAP, A_DATA, A_FCS, A_ED,
 A_SERVICE, A_DPV1, A_BYTES, A_IDLE, A_TSDR, A_ERROR, A_WARNING) = range(16)


def hx(v):
    return '%02Xh' % v


class Char:
    '''One UART character: first sample of its start bit, value, error.'''
    def __init__(self, ss, es, rxtx, value, error):
        self.ss, self.es, self.rxtx = ss, es, rxtx
        self.value, self.error = value, error


class Telegram:
    def __init__(self, first, idle):
        self.chars = [first]
        self.idle = idle            # (ss, es, bit times, exact) before it
        self.need = None            # the length its SD (and LE) give
        self.errors = []            # (ss, es, text)
        self.truncated = False

    def bytes(self):
        return [c.value for c in self.chars]


class Decoder(srd.Decoder):
    api_version = 3
    id = 'profibus_dp'
    name = 'PROFIBUS DP'
    longname = 'PROFIBUS DP (FDL, DP and DPV1)'
    desc = 'PROFIBUS DP telegrams, services and bus timing.'
    license = 'gplv2+'
    inputs = ['uart']
    outputs = []
    tags = ['Embedded/industrial']
    options = (
        {'id': 'baudrate', 'desc': 'Baud rate (0: from the characters)',
         'default': 0},
        {'id': 'slot_time', 'desc': 'Slot time in bit times (0: the usual '
         'for the rate)', 'default': 0},
    )
    annotations = (
        ('telegram', 'Telegram'),
        ('sd', 'Start delimiter'),
        ('le', 'Length'),
        ('addr', 'Address'),
        ('fc', 'Function code'),
        ('sap', 'Service access point'),
        ('data', 'Data unit'),
        ('fcs', 'Frame check sequence'),
        ('ed', 'End delimiter'),
        ('service', 'DP service'),
        ('dpv1', 'DPV1 PDU'),
        ('bytes', 'Telegram bytes'),
        ('idle', 'Idle time (TSYN)'),
        ('tsdr', 'Station delay (TSDR)'),
        ('error', 'Error'),
        ('warning', 'Timing warning'),
    )
    annotation_rows = (
        ('telegrams', 'Telegrams', (A_TELEGRAM,)),
        ('fields', 'Fields', (A_SD, A_LE, A_ADDR, A_FC, A_SAP, A_DATA, A_FCS,
                              A_ED)),
        ('services', 'Services', (A_SERVICE, A_DPV1)),
        ('raw', 'Bytes', (A_BYTES,)),
        ('timing', 'Timing', (A_IDLE, A_TSDR)),
        ('errors', 'Errors', (A_ERROR, A_WARNING)),
    )

    def __init__(self):
        self.reset()

    def reset(self):
        self.samplerate = None
        self.baud = None
        self.bit = None             # samples per bit
        self.tg = None              # the telegram being received
        self.last_end = None        # end of the last character on the bus
        self.line_end = [None, None]  # ... on rx and on tx
        self.collided = None        # (line, end) of the last colliding char
        self.char_error = [None, None]
        self.request = None         # the last request that wants an answer
        self.answered = True

    def start(self):
        self.out_ann = self.register(srd.OUTPUT_ANN)

    def metadata(self, key, value):
        if key == srd.SRD_CONF_SAMPLERATE:
            self.samplerate = value

    def putx(self, ss, es, cls, texts):
        self.put(int(ss), int(es), self.out_ann, [cls, texts])

    def set_baud(self, ss, es):
        if self.bit is not None or not self.samplerate:
            return
        baud = self.options['baudrate']
        if baud <= 0:
            # The uart decoder's frame spans 11 bits (to within a sample or
            # two): the nearest PROFIBUS rate is the bus's.
            measured = self.samplerate * BITS_PER_CHAR / max(es - ss, 1)
            baud = min(RATES, key=lambda r: abs(r - measured) / r)
        self.baud = baud
        self.bit = self.samplerate / baud
        slot = self.options['slot_time']
        self.slot = slot if slot > 0 else DEFAULT_SLOT.get(baud, 100)

    def bits(self, samples):
        return samples / self.bit

    def gap(self, ss, end):
        '''Bit times from `end`, a character's computed (fractional) end, to
        sample `ss`, never below 0: a start bit right after a stop bit lies
        within one sample of its end, either side (docs/waveforms.md).'''
        return max(0.0, self.bits(ss - end))

    def decode(self, ss, es, data):
        ptype, rxtx, pdata = data
        if ptype == 'PARITY ERROR':
            self.char_error[rxtx] = self.char_error[rxtx] or 'parity error'
        elif ptype == 'INVALID STOPBIT':
            self.char_error[rxtx] = self.char_error[rxtx] or 'stop bit error'
        elif ptype == 'INVALID STARTBIT':
            self.char_error[rxtx] = 'start bit error'
        elif ptype == 'FRAME':
            error, self.char_error[rxtx] = self.char_error[rxtx], None
            if error == 'start bit error':
                self.glitch(ss, es)
                return
            self.set_baud(ss, es)
            if self.bit is None:
                return
            self.char(Char(ss, es, rxtx, pdata[0], error))
        elif ptype == 'IDLE' and self.tg is not None and self.bit:
            if self.bits(es - self.last_end) >= TSYN_BITS:
                self.cut(es)

    def glitch(self, ss, es):
        # A start bit that is gone by its sample point: the receiver counts
        # it and drops the telegram it was in.
        self.putx(ss, es, A_ERROR, ['Start bit error (glitch)', 'Start bit',
                                    'SB'])
        if self.tg is not None:
            self.tg.errors.append((ss, es, 'start bit error'))

    def cut(self, at):
        '''A telegram that stopped short: a gap of TSYN inside it.'''
        self.tg.truncated = True
        self.finish()

    def char(self, c):
        end = c.ss + BITS_PER_CHAR * self.bit
        other_end = self.line_end[1 - c.rxtx]
        self.line_end[c.rxtx] = end
        if self.collides(c, other_end):
            self.collided = (c.rxtx, end)
            self.last_end = max(self.last_end, end)
            return
        gap = None
        if self.last_end is not None:
            gap = self.gap(c.ss, self.last_end)
        tg = self.tg
        if tg is not None and (gap >= TSYN_BITS or c.rxtx != tg.chars[0].rxtx):
            self.cut(c.ss)
            tg = None
        self.last_end = end
        if tg is None:
            if gap is None:
                idle = (0, c.ss, self.bits(c.ss), False)
            else:
                idle = (c.ss - gap * self.bit, c.ss, gap, True)
            self.tg = Telegram(c, idle)
            tg = self.tg
        else:
            tg.chars.append(c)
        if c.error:
            tg.errors.append((c.ss, self.last_end, '%s in byte %d' %
                              (c.error, len(tg.chars))))
        n, b = len(tg.chars), tg.bytes()
        if n == 1:
            tg.need = {SD1: 6, SD3: 14, SD4: 3, SC: 1}.get(b[0])
            if b[0] == SD2:
                tg.need = None
            elif tg.need is None:
                tg.need = 1     # not a start delimiter: one byte of noise
        elif n == 2 and b[0] == SD2:
            tg.need = b[1] + 6
        if tg.need is not None and n >= tg.need:
            self.finish()

    def collides(self, c, other_end):
        '''A character that starts while the other line's last one is still
        on (a late answer inside the next request: one bus cannot carry both),
        and the characters back to back after it, are annotated and dropped;
        the telegram already on the bus goes on uncut.'''
        if self.tg is not None and self.tg.chars[0].rxtx == c.rxtx:
            return False
        lines = ('RxD', 'TxD')
        if other_end is not None and c.ss < other_end:
            text = 'Collision: %s on %s while %s is sending' % (
                hx(c.value), lines[c.rxtx], lines[1 - c.rxtx])
        elif self.collided is not None and self.collided[0] == c.rxtx and \
                self.bits(c.ss - self.collided[1]) < TSYN_BITS:
            text = 'Collision: %s on %s, the rest of a collided telegram' % (
                hx(c.value), lines[c.rxtx])
        else:
            return False
        self.putx(c.ss, c.ss + BITS_PER_CHAR * self.bit, A_ERROR,
                  [text, 'Collision'])
        return True

    # --- one whole telegram ------------------------------------------------

    def finish(self):
        tg, self.tg = self.tg, None
        b, cs = tg.bytes(), tg.chars
        ss = cs[0].ss
        es = cs[-1].ss + BITS_PER_CHAR * self.bit
        end = lambda i: cs[i].ss + BITS_PER_CHAR * self.bit
        field = lambda i, j, cls, texts: self.putx(cs[i].ss, end(j), cls, texts)
        self.putx(ss, es, A_BYTES, [' '.join('%02X' % v for v in b)])
        info = self.fields(tg, b, field)
        if tg.truncated:
            tg.errors.append((ss, es, 'truncated after %d bytes' % len(b)))
        for ess, ees, text in tg.errors:
            self.putx(ess, ees, A_ERROR, [text[0].upper() + text[1:]])
        kind, summary, service, wants_answer, da, sa = info
        if tg.errors:
            summary = 'Broken telegram: %s: %s' % (tg.errors[0][2], summary)
            kind = 'broken'
        # The gap before the telegram first, so a listing reads in bus order.
        self.timing(tg, kind, ss, es, wants_answer, da, sa, service)
        self.putx(ss, es, A_TELEGRAM, [summary, summary.split(':')[0]])
        if service:
            self.putx(ss, es, A_SERVICE, [service])

    def fields(self, tg, b, field):
        '''Annotates the fields; returns (kind, summary, service, wants an
        answer, DA, SA).'''
        sd = b[0]
        # An answer's service is its request's, while that request waits for
        # one (not after another telegram: a token, the next request).
        req = None if self.answered else self.request
        if sd == SC:
            field(0, 0, A_SD, ['SC (short acknowledge)', 'SC'])
            service = req[2] if req else ''
            return ('response', 'SC short acknowledge' +
                    (' (%s)' % service if service else ''), service, False,
                    None, None)
        if sd not in SD_NAMES:
            tg.errors.append((tg.chars[0].ss, tg.chars[0].es,
                              'not a start delimiter: %s' % hx(sd)))
            return ('noise', 'Noise %s' % hx(sd), '', False, None, None)
        field(0, 0, A_SD, ['%s (%s)' % (SD_NAMES[sd], hx(sd)),
                           SD_NAMES[sd]])
        pos = 1
        if sd == SD2:
            if len(b) < 4:
                return ('broken', 'SD2 telegram', '', False, None, None)
            le, ler = b[1], b[2]
            field(1, 1, A_LE, ['LE %d' % le, 'LE'])
            field(2, 2, A_LE, ['LEr %d' % ler, 'LEr'])
            if le != ler:
                tg.errors.append((tg.chars[2].ss, tg.chars[2].es,
                                  'LE %d but LEr %d' % (le, ler)))
            if not 3 <= le <= 249:
                tg.errors.append((tg.chars[1].ss, tg.chars[1].es,
                                  'LE %d out of range 3..249' % le))
            if b[3] != SD2:
                tg.errors.append((tg.chars[3].ss, tg.chars[3].es,
                                  'SD2 not repeated: %s' % hx(b[3])))
            field(3, 3, A_SD, ['SD2 (repeated)', 'SD2'])
            pos = 4
        if len(b) < pos + 2:
            return ('broken', '%s telegram' % SD_NAMES[sd], '', False, None,
                    None)
        da, sa = b[pos], b[pos + 1]
        field(pos, pos, A_ADDR, ['DA %d%s' % (da & 0x7F, ' +SAP' if da & 0x80
                                               else ''), 'DA'])
        field(pos + 1, pos + 1, A_ADDR, ['SA %d%s' % (sa & 0x7F, ' +SAP' if
                                                     sa & 0x80 else ''), 'SA'])
        if sd == SD4:
            return ('token', 'Token %d -> %d' % (sa, da), 'Token', False,
                    None, None)
        if len(b) < pos + 3:
            return ('broken', '%s telegram' % SD_NAMES[sd], '', False, None,
                    None)
        fc = b[pos + 2]
        request = bool(fc & 0x40)
        code = fc & 0x0F
        if request:
            name = REQ_FC.get(code, 'function %X' % code)
            fcb = ' FCB=%d FCV=%d' % ((fc >> 5) & 1, (fc >> 4) & 1)
            field(pos + 2, pos + 2, A_FC, ['FC %s request %s%s' % (hx(fc),
                                           name, fcb), name])
        else:
            name = RES_FC.get(code, 'response %X' % code)
            field(pos + 2, pos + 2, A_FC, ['FC %s response %s (%s)' % (
                hx(fc), name, STATION_TYPE[(fc >> 4) & 3]), name])
        # The data unit: DA .. before FCS for SD2, 8 bytes for SD3, none for SD1.
        du_end = {SD1: pos + 3, SD3: pos + 11}.get(sd, 1 + (b[1] if sd == SD2
                                                          else 0) + 3)
        if len(b) < du_end + 2:
            summary = '%s %s %d -> %d' % ('Request' if request else
                                          'Response', name, sa & 0x7F,
                                          da & 0x7F)
            return ('broken', summary, '', False, da & 0x7F, sa & 0x7F)
        fcs = sum(b[pos:du_end]) & 0xFF
        field(du_end, du_end, A_FCS, ['FCS %s ok' % hx(b[du_end]), 'FCS']
              if b[du_end] == fcs else ['FCS %s, expected %s' %
                                        (hx(b[du_end]), hx(fcs)), 'FCS!'])
        if b[du_end] != fcs:
            tg.errors.append((tg.chars[du_end].ss, tg.chars[du_end].es,
                              'FCS %s, expected %s' % (hx(b[du_end]), hx(fcs))))
        field(du_end + 1, du_end + 1, A_ED, ['ED', 'E'] if b[du_end + 1] == ED
              else ['ED %s, expected 16h' % hx(b[du_end + 1]), 'ED!'])
        if b[du_end + 1] != ED:
            tg.errors.append((tg.chars[du_end + 1].ss, tg.chars[du_end + 1].es,
                              'ED %s, expected 16h' % hx(b[du_end + 1])))
        du = pos + 3
        dsap = ssap = None
        if da & 0x80 and du < du_end:
            dsap = b[du] & 0x3F
            field(du, du, A_SAP, ['DSAP %d' % dsap, 'DSAP'])
            du += 1
        if sa & 0x80 and du < du_end:
            ssap = b[du] & 0x3F
            field(du, du, A_SAP, ['SSAP %d' % ssap, 'SSAP'])
            du += 1
        if du < du_end:
            field(du, du_end - 1, A_DATA, ['Data ' + ' '.join(
                '%02X' % v for v in b[du:du_end]), 'Data'])
        sap = dsap if request else ssap
        da7, sa7 = da & 0x7F, sa & 0x7F
        if request:
            service = self.request_service(code, sap, da7, b[du:du_end])
        else:
            service = req[2] if req and req[0] == sa7 and req[1] == da7 \
                else ''
        if sap is not None and (sap <= 51) and du < du_end:
            self.dpv1(tg, du, du_end, b, request)
        summary = '%s %s %d -> %d%s' % ('Request' if request else 'Response',
                                        name, sa7, da7, (': ' + service) if
                                        service and service != name else '')
        wants = request and code in REPLY_FC and da7 != BROADCAST
        return ('request' if request else 'response', summary, service,
                wants, da7, sa7)

    def request_service(self, code, sap, da, du):
        if sap is None:
            if code in (0xC, 0xD):
                return 'Data_Exchange'
            return REQ_FC.get(code, '')
        if sap <= 48:
            return 'MSAC_C2 (SAP %d)' % sap
        name = DP_SAPS.get(sap, 'SAP %d' % sap)
        if sap == 58 and du:
            cmds = [n for bit, n in GC_BITS if du[0] & (1 << bit)]
            name += ' ' + ('+'.join(cmds) if cmds else '(none)')
            if len(du) > 1:
                name += ' group %s' % hx(du[1])
        return name

    def dpv1(self, tg, du, du_end, b, request):
        '''A DPV1 PDU on SAP 0..51: function number, then its fields.'''
        f = b[du]
        name = DPV1_FUNCS.get(f & 0x7F, 'function %s' % hx(f & 0x7F))
        pdu = b[du:du_end]
        put = lambda texts: self.putx(tg.chars[du].ss, tg.chars[du_end - 1].ss
                                      + BITS_PER_CHAR * self.bit, A_DPV1,
                                      texts)
        if f & 0x80:
            if len(pdu) < 4:
                put(['%s negative response, too short (%d bytes)' % (
                    name, len(pdu)), name + '-'])
                return
            dec, ec1, ec2 = pdu[1], pdu[2], pdu[3]
            cls = ERROR_CLASS.get(ec1 >> 4, 'class %X' % (ec1 >> 4))
            what = ERROR_CODE_1.get(ec1, 'code %X' % (ec1 & 0xF))
            put(['%s negative response: Error_Decode %s (%s), Error_Code_1 '
                 '%s (%s: %s), Error_Code_2 %s' % (
                     name, hx(dec), ERROR_DECODE.get(dec, 'reserved'),
                     hx(ec1), cls, what, hx(ec2)), name + '-'])
            return
        dir_ = 'request' if request else 'response'
        text = '%s %s' % (name, dir_)
        if f in (0x5E, 0x5F, 0x51) and len(pdu) >= 4:
            text += ': Slot %d, Index %d, Length %d' % (pdu[1], pdu[2],
                                                        pdu[3])
            if len(pdu) > 4:
                text += ', Data ' + ' '.join('%02X' % v for v in pdu[4:])
        elif f == 0x5C and len(pdu) >= 4:
            text += ': Slot %d, Alarm_Type %d (%s), Seq_Nr %d' % (
                pdu[1], pdu[2], ALARM_TYPES.get(pdu[2], 'manufacturer' if
                                                32 <= pdu[2] <= 126 else
                                                'reserved'), pdu[3] >> 3)
        elif f == 0x57 and request and len(pdu) >= 12:
            text += ': Send_Timeout %d x 10 ms, Features %02X%02X, ' \
                    'Profile_Ident %02X%02X' % ((pdu[4] << 8) | pdu[5],
                                                pdu[6], pdu[7], pdu[10],
                                                pdu[11])
        elif f == 0x57 and not request and len(pdu) >= 8:
            text += ': Max_Len_Data_Unit %d, Features %02X%02X, ' \
                    'Profile_Ident %02X%02X' % (pdu[1], pdu[2], pdu[3],
                                                pdu[6], pdu[7])
        elif f == 0x56 and len(pdu) >= 4:
            # The resource manager's answer on SAP 49: the connection's SAP
            # and its Send_Timeout (docs/capture.md, profibus.dpv1.sap).
            text += ': Connection SAP %d, Send_Timeout %d x 10 ms' % (
                pdu[1], (pdu[2] << 8) | pdu[3])
        elif f == 0x58 and len(pdu) >= 3:
            text += ': Subnet %d, Instance %d, Reason_Code %d' % (
                pdu[1], (pdu[2] >> 4) & 3, pdu[2] & 0xF)
        put([text, name])

    # --- the bus timing ----------------------------------------------------

    def timing(self, tg, kind, ss, es, wants_answer, da, sa, service):
        idle_ss, idle_es, idle, exact = tg.idle
        req = self.request
        answers = kind == 'response' and req is not None and \
            not self.answered
        if answers:
            # TSDR: from the end of the request's last stop bit to the first
            # start bit of its answer; later than the slot time is too late.
            tsdr = self.gap(ss, req[3])
            self.putx(req[3], ss, A_TSDR, ['TSDR %.1f bit times' % tsdr,
                                           'TSDR %.0f' % tsdr])
            if tsdr > self.slot:
                self.putx(req[3], ss, A_WARNING, [
                    'Late answer: TSDR %.1f > slot time %d bit times' %
                    (tsdr, self.slot), 'Late'])
            self.answered = True
            return
        if req is not None and not self.answered:
            self.putx(req[3], ss, A_WARNING, [
                'No answer: the next telegram came after %.1f bit times' %
                self.gap(ss, req[3]), 'No answer'])
        self.answered = True
        self.putx(idle_ss, idle_es, A_IDLE, [
            'Idle %s%.1f bit times' % ('' if exact else '>= ', idle),
            'Idle %.0f' % idle])
        # One sample of slack: both ends are where the decoder saw the edge.
        if kind in ('request', 'token') and exact and \
                idle + 1 / self.bit < TSYN_BITS:
            self.putx(idle_ss, idle_es, A_WARNING, [
                'Idle %.1f < TSYN (33 bit times): a receiver ignores it' %
                idle, 'TSYN'])
        if wants_answer:
            self.request = (da, sa, service, es)
            self.answered = False
