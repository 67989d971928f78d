-- PROFIBUS FDL (IEC 61158-4-3 data link layer) dissector for Wireshark / tshark 4.0+, for
-- pcapng captures with link type 257 (LINKTYPE_PROFIBUS_DL): every packet is one telegram, SD to
-- ED, without a pseudo-header. dpc31emu writes such captures (docs/capture.md).
--
--   tshark -X lua_script:lib/capture/profibus_dl.lua -r capture.pcapng
--   wireshark -X lua_script:lib/capture/profibus_dl.lua capture.pcapng
--
-- or copy this file into the personal Lua plugin folder (Help > About > Folders).
--
-- Wireshark 4.0 has no wiretap encapsulation for link type 257: such packets arrive with
-- WTAP_ENCAP_UNKNOWN (0), shared with every other link type Wireshark does not know. The
-- dissector registers there and takes a packet only if it starts with a start delimiter (10h,
-- 68h, A2h, DCh, E5h), unless the preference profibus.all_unknown_encap is set (then it takes
-- every packet of an unknown link type, and malformed starts are reported too). Should a later
-- Wireshark define wtap_encaps.PROFIBUS_DL / PROFIBUS, the dissector registers there as well.
--
-- Malformed telegrams never raise a Lua error: every problem is an expert info, and what could
-- be parsed is shown.

-- Loaded twice (plugin folder and -X lua_script): the first copy stays, the second does nothing.
local created, p = pcall(Proto, "profibus", "PROFIBUS FDL")
if not created then return end

local SD1, SD2, SD3, SD4, SC, ED = 0x10, 0x68, 0xA2, 0xDC, 0xE5, 0x16
local BROADCAST = 127

local sd_names = {
  [SD1] = "SD1", [SD2] = "SD2", [SD3] = "SD3", [SD4] = "SD4", [SC] = "SC",
}
local sd_long = {
  [SD1] = "SD1, no data field",
  [SD2] = "SD2, variable data field",
  [SD3] = "SD3, fixed data field",
  [SD4] = "SD4, token",
  [SC] = "SC, short acknowledge",
}
local function_names = {
  [0x3] = "SDA_low", [0x4] = "SDN_low", [0x5] = "SDA_high", [0x6] = "SDN_high", [0x7] = "DDB",
  [0x9] = "FDL_Status", [0xC] = "SRD_low", [0xD] = "SRD_high", [0xE] = "Ident",
  [0xF] = "LSAP_Status",
}
local function_long = {
  [0x3] = "SDA_low (send data with acknowledge, low priority)",
  [0x4] = "SDN_low (send data with no acknowledge, low priority)",
  [0x5] = "SDA_high (send data with acknowledge, high priority)",
  [0x6] = "SDN_high (send data with no acknowledge, high priority)",
  [0x7] = "DDB (send and request data, multicast)",
  [0x9] = "FDL_Status (request FDL status with reply)",
  [0xC] = "SRD_low (send and request data, low priority)",
  [0xD] = "SRD_high (send and request data, high priority)",
  [0xE] = "Ident (request ident with reply)",
  [0xF] = "LSAP_Status (request LSAP status with reply)",
}
local response_names = {
  [0x0] = "OK", [0x1] = "UE", [0x2] = "RR", [0x3] = "RS", [0x8] = "DL", [0x9] = "NR",
  [0xA] = "DH", [0xC] = "RDL", [0xD] = "RDH",
}
local response_long = {
  [0x0] = "OK (positive acknowledgement)",
  [0x1] = "UE (user error)",
  [0x2] = "RR (no resource)",
  [0x3] = "RS (no service activated)",
  [0x8] = "DL (response data low)",
  [0x9] = "NR (no response data)",
  [0xA] = "DH (response data high)",
  [0xC] = "RDL (data not received, response data low)",
  [0xD] = "RDH (data not received, response data high)",
}
local station_types = {
  [0] = "Slave",
  [1] = "Master not ready",
  [2] = "Master ready to enter the token ring",
  [3] = "Master in the token ring",
}
-- DP services by the slave's SAP (the DSAP of a request, the SSAP of its response).
local dp_saps = {
  [49] = "MSAC_C2_Initiate", [50] = "MSAC_C1_Alarm", [51] = "MSAC_C1", [53] = "Set_Ext_Prm",
  [55] = "Set_Slave_Add", [56] = "Rd_Inp", [57] = "Rd_Outp", [58] = "Global_Control",
  [59] = "Get_Cfg", [60] = "Slave_Diag", [61] = "Set_Prm", [62] = "Chk_Cfg",
}

-- DPV1 (IEC 61158-6 type 3, MSAC_C1 / MSAC_C2) data units on the slave's SAPs 0..51: the
-- function number, then per function the fields below (dpc31/pdu.hpp declares the same).
local dpv1_functions = {
  [0x48] = "Idle", [0x51] = "Data_Transport", [0x56] = "Resource_Manager", [0x57] = "Initiate",
  [0x58] = "Abort", [0x5C] = "Alarm_Ack", [0x5E] = "Read", [0x5F] = "Write",
}
local dpv1_error_decode = { [0x80] = "DPV1", [0xFE] = "FMS", [0xFF] = "HART" }
local dpv1_error_classes = { [0xA] = "application", [0xB] = "access", [0xC] = "resource" }
local dpv1_error_codes = {
  [0xA] = { [0] = "read error", [1] = "write error", [2] = "module failure",
            [8] = "version conflict", [9] = "feature not supported" },
  [0xB] = { [0] = "invalid index", [1] = "write length error", [2] = "invalid slot",
            [3] = "type conflict", [4] = "invalid area", [5] = "state conflict",
            [6] = "access denied", [7] = "invalid range", [8] = "invalid parameter",
            [9] = "invalid type" },
  [0xC] = { [0] = "read constrain conflict", [1] = "write constrain conflict",
            [2] = "resource busy", [3] = "resource unavailable" },
}
local dpv1_alarm_types = {
  [1] = "Diagnosis", [2] = "Process", [3] = "Pull", [4] = "Plug", [5] = "Status", [6] = "Update",
}
local dpv1_specifiers = {
  [0] = "no further differentiation", [1] = "appears", [2] = "disappears",
  [3] = "disappears, other errors remain",
}
local dpv1_instances = { [0] = "FDL", [1] = "MSAC_C2", [2] = "user" }

local f = {
  dpv1_function = ProtoField.uint8("profibus.dpv1.function", "DPV1 function", base.HEX,
                                   dpv1_functions, 0x7F),
  dpv1_negative = ProtoField.bool("profibus.dpv1.negative", "Negative response", 8, nil, 0x80),
  dpv1_slot = ProtoField.uint8("profibus.dpv1.slot", "Slot_Number", base.DEC),
  dpv1_index = ProtoField.uint8("profibus.dpv1.index", "Index", base.DEC),
  dpv1_length = ProtoField.uint8("profibus.dpv1.length", "Length", base.DEC),
  dpv1_data = ProtoField.bytes("profibus.dpv1.data", "Data"),
  dpv1_error_decode = ProtoField.uint8("profibus.dpv1.error_decode", "Error_Decode", base.HEX,
                                       dpv1_error_decode),
  dpv1_error_code_1 = ProtoField.uint8("profibus.dpv1.error_code_1", "Error_Code_1", base.HEX),
  dpv1_error_class = ProtoField.uint8("profibus.dpv1.error_class", "Error class", base.DEC,
                                      dpv1_error_classes, 0xF0),
  dpv1_error_code = ProtoField.uint8("profibus.dpv1.error_code", "Error code", base.DEC, nil,
                                     0x0F),
  dpv1_error_code_2 = ProtoField.uint8("profibus.dpv1.error_code_2", "Error_Code_2", base.HEX),
  dpv1_alarm_type = ProtoField.uint8("profibus.dpv1.alarm_type", "Alarm_Type", base.DEC,
                                     dpv1_alarm_types),
  dpv1_specifier = ProtoField.uint8("profibus.dpv1.specifier", "Specifier", base.HEX),
  dpv1_seq_nr = ProtoField.uint8("profibus.dpv1.seq_nr", "Seq_Nr", base.DEC, nil, 0xF8),
  dpv1_add_ack = ProtoField.bool("profibus.dpv1.add_ack", "Add_Ack", 8, nil, 0x04),
  dpv1_spec = ProtoField.uint8("profibus.dpv1.spec", "Specifier", base.DEC, dpv1_specifiers,
                               0x03),
  dpv1_send_timeout = ProtoField.uint16("profibus.dpv1.send_timeout", "Send_Timeout (10 ms)",
                                        base.DEC),
  dpv1_max_len = ProtoField.uint8("profibus.dpv1.max_len_data_unit", "Max_Len_Data_Unit",
                                  base.DEC),
  dpv1_features = ProtoField.uint16("profibus.dpv1.features_supported", "Features_Supported",
                                    base.HEX),
  dpv1_profile_features = ProtoField.uint16("profibus.dpv1.profile_features_supported",
                                            "Profile_Features_Supported", base.HEX),
  dpv1_profile_ident = ProtoField.uint16("profibus.dpv1.profile_ident_number",
                                         "Profile_Ident_Number", base.HEX),
  dpv1_s_type = ProtoField.uint8("profibus.dpv1.s_type", "S_Type", base.HEX),
  dpv1_s_len = ProtoField.uint8("profibus.dpv1.s_len", "S_Len", base.DEC),
  dpv1_d_type = ProtoField.uint8("profibus.dpv1.d_type", "D_Type", base.HEX),
  dpv1_d_len = ProtoField.uint8("profibus.dpv1.d_len", "D_Len", base.DEC),
  dpv1_s_addr = ProtoField.bytes("profibus.dpv1.s_addr", "S_Addr"),
  dpv1_d_addr = ProtoField.bytes("profibus.dpv1.d_addr", "D_Addr"),
  dpv1_subnet = ProtoField.uint8("profibus.dpv1.subnet", "Subnet", base.DEC),
  dpv1_instance = ProtoField.uint8("profibus.dpv1.instance", "Instance", base.DEC,
                                   dpv1_instances, 0x30),
  dpv1_reason = ProtoField.uint8("profibus.dpv1.reason_code", "Reason_Code", base.DEC, nil, 0x0F),
  dpv1_detail = ProtoField.uint8("profibus.dpv1.additional_detail", "Additional_Detail",
                                 base.HEX),
  dpv1_rm_sap = ProtoField.uint8("profibus.dpv1.sap", "Connection SAP", base.DEC),
  sd = ProtoField.uint8("profibus.sd", "Start delimiter", base.HEX, sd_long),
  le = ProtoField.uint8("profibus.le", "Length (LE)", base.DEC),
  ler = ProtoField.uint8("profibus.ler", "Length repeated (LEr)", base.DEC),
  sd_rep = ProtoField.uint8("profibus.sd_repeat", "Start delimiter repeated", base.HEX),
  da = ProtoField.uint8("profibus.da", "Destination address (DA)", base.DEC, nil, 0x7F),
  da_ext = ProtoField.bool("profibus.da.ext", "DSAP present (address extension)", 8, nil, 0x80),
  sa = ProtoField.uint8("profibus.sa", "Source address (SA)", base.DEC, nil, 0x7F),
  sa_ext = ProtoField.bool("profibus.sa.ext", "SSAP present (address extension)", 8, nil, 0x80),
  fc = ProtoField.uint8("profibus.fc", "Frame control (FC)", base.HEX),
  fc_reserved = ProtoField.uint8("profibus.fc.reserved", "Reserved", base.DEC, nil, 0x80),
  fc_request = ProtoField.bool("profibus.fc.request", "Request", 8,
                               {"Request", "Response / acknowledgement"}, 0x40),
  fc_fcb = ProtoField.uint8("profibus.fc.fcb", "Frame count bit (FCB)", base.DEC, nil, 0x20),
  fc_fcv = ProtoField.uint8("profibus.fc.fcv", "Frame count bit valid (FCV)", base.DEC, nil, 0x10),
  fc_function = ProtoField.uint8("profibus.fc.function", "Function", base.HEX, function_long, 0x0F),
  fc_station = ProtoField.uint8("profibus.fc.station_type", "Station type", base.DEC,
                                station_types, 0x30),
  fc_response = ProtoField.uint8("profibus.fc.response", "Response", base.HEX, response_long, 0x0F),
  dsap = ProtoField.uint8("profibus.dsap", "Destination SAP (DSAP)", base.DEC, nil, 0x3F),
  dsap_ext = ProtoField.bool("profibus.dsap.ext", "Further extension", 8, nil, 0x80),
  dsap_seg = ProtoField.bool("profibus.dsap.segment", "Segment address", 8, nil, 0x40),
  ssap = ProtoField.uint8("profibus.ssap", "Source SAP (SSAP)", base.DEC, nil, 0x3F),
  ssap_ext = ProtoField.bool("profibus.ssap.ext", "Further extension", 8, nil, 0x80),
  ssap_seg = ProtoField.bool("profibus.ssap.segment", "Segment address", 8, nil, 0x40),
  du = ProtoField.bytes("profibus.du", "Data unit (DU)"),
  du_len = ProtoField.uint8("profibus.du_len", "DU length", base.DEC),
  fcs = ProtoField.uint8("profibus.fcs", "Frame check sequence (FCS)", base.HEX),
  fcs_ok = ProtoField.bool("profibus.fcs_ok", "FCS good"),
  ed = ProtoField.uint8("profibus.ed", "End delimiter (ED)", base.HEX),
  service = ProtoField.string("profibus.service", "Service"),
}
p.fields = f

local e = {
  empty = ProtoExpert.new("profibus.empty", "Empty frame", expert.group.MALFORMED,
                          expert.severity.ERROR),
  unknown_sd = ProtoExpert.new("profibus.unknown_sd", "Unknown start delimiter",
                               expert.group.MALFORMED, expert.severity.ERROR),
  truncated = ProtoExpert.new("profibus.truncated", "Frame truncated", expert.group.MALFORMED,
                              expert.severity.ERROR),
  le_mismatch = ProtoExpert.new("profibus.le_mismatch", "LE and LEr differ",
                                expert.group.MALFORMED, expert.severity.ERROR),
  bad_le = ProtoExpert.new("profibus.bad_le", "LE outside 4..249", expert.group.MALFORMED,
                           expert.severity.ERROR),
  bad_sd_rep = ProtoExpert.new("profibus.bad_sd_repeat", "Repeated start delimiter is not 68h",
                               expert.group.MALFORMED, expert.severity.ERROR),
  bad_fcs = ProtoExpert.new("profibus.bad_fcs", "Bad FCS", expert.group.CHECKSUM,
                            expert.severity.ERROR),
  bad_ed = ProtoExpert.new("profibus.bad_ed", "End delimiter is not 16h", expert.group.MALFORMED,
                           expert.severity.ERROR),
  trailing = ProtoExpert.new("profibus.trailing", "Bytes after the end of the frame",
                             expert.group.MALFORMED, expert.severity.ERROR),
  bad_sap = ProtoExpert.new("profibus.bad_sap", "Address extension problem",
                            expert.group.MALFORMED, expert.severity.ERROR),
  reserved = ProtoExpert.new("profibus.reserved", "Reserved value", expert.group.PROTOCOL,
                             expert.severity.WARN),
  internal = ProtoExpert.new("profibus.internal", "Dissector error", expert.group.MALFORMED,
                             expert.severity.ERROR),
  dpv1_short = ProtoExpert.new("profibus.dpv1.short", "DPV1 data unit too short",
                               expert.group.MALFORMED, expert.severity.ERROR),
  char_error = ProtoExpert.new("profibus.char_error", "Character error", expert.group.MALFORMED,
                               expert.severity.ERROR),
}
p.experts = e

p.prefs.all_unknown_encap = Pref.bool("Claim all packets of unknown link types", false,
  "Dissect every packet with an unknown encapsulation (Wireshark 4.0 maps link type 257 to " ..
  "it), not only those starting with a PROFIBUS start delimiter")

-- Request services seen so far, to name the responses: first pass only, kept per frame.
local last_request = {}   -- "master>slave" -> service of the last request
local last_any = nil      -- service of the last request that expects an answer (for SC)
local response_service = {} -- frame number -> service name

function p.init()
  last_request = {}
  last_any = nil
  response_service = {}
end

local function hex2(v) return string.format("%02Xh", v) end

-- Parses one telegram; `tree` is the protocol subtree. Returns the Info text.
-- A DPV1 data unit in tvb[from, to): its fields under `tree`; returns a summary for the Info
-- column. Too short for its function: an expert info, the fields that are there.
local function dpv1(tvb, tree, from, to, is_request)
  local b0 = tvb(from, 1):uint()
  local fn = bit.band(b0, 0x7F)
  local name = dpv1_functions[fn] or ("function " .. hex2(fn))
  local item = tree:add(f.dpv1_function, tvb(from, 1))
  item:add(f.dpv1_negative, tvb(from, 1))
  local at = from + 1
  -- The next n bytes as field pf; their value, or nil past the end.
  local function field(pf, n)
    if at + n > to then return nil end
    local fi = item:add(pf, tvb(at, n))
    at = at + n
    return n <= 4 and tvb(at - n, n):uint() or true, fi
  end
  local function short()
    item:add_proto_expert_info(e.dpv1_short, name .. ": the data unit ends at byte " .. (to - from))
  end
  local function rest(pf)
    if at < to then item:add(pf, tvb(at, to - at)) end
    at = to
  end
  if bit.band(b0, 0x80) ~= 0 then
    if at + 3 > to then short(); return "DPV1 " .. name .. " negative" end
    item:add(f.dpv1_error_decode, tvb(at, 1))
    local code = tvb(at + 1, 1):uint()
    local ec = item:add(f.dpv1_error_code_1, tvb(at + 1, 1))
    ec:add(f.dpv1_error_class, tvb(at + 1, 1))
    local ci = ec:add(f.dpv1_error_code, tvb(at + 1, 1))
    local cls = bit.rshift(code, 4)
    local text = dpv1_error_codes[cls] and dpv1_error_codes[cls][bit.band(code, 0x0F)]
    if text then ci:append_text(" (" .. text .. ")") end
    item:add(f.dpv1_error_code_2, tvb(at + 2, 1))
    return string.format("DPV1 %s negative %s%s", name, hex2(code), text and (" " .. text) or "")
  end
  if fn == 0x5E or fn == 0x5F or fn == 0x51 then
    local s = field(f.dpv1_slot, 1); local i = field(f.dpv1_index, 1)
    local l = field(f.dpv1_length, 1)
    if not l then short(); return "DPV1 " .. name end
    rest(f.dpv1_data)
    return string.format("DPV1 %s slot %d index %d length %d", name, s, i, l)
  elseif fn == 0x5C then
    local s = field(f.dpv1_slot, 1); field(f.dpv1_alarm_type, 1)
    local sp, sp_item = field(f.dpv1_specifier, 1)
    if not sp then short(); return "DPV1 " .. name end
    sp_item:add(f.dpv1_seq_nr, tvb(at - 1, 1)); sp_item:add(f.dpv1_add_ack, tvb(at - 1, 1))
    sp_item:add(f.dpv1_spec, tvb(at - 1, 1))
    return string.format("DPV1 %s slot %d", name, s)
  elseif fn == 0x57 then
    if is_request then
      at = at + 3  -- reserved
      field(f.dpv1_send_timeout, 2)
    else
      field(f.dpv1_max_len, 1)
    end
    field(f.dpv1_features, 2); field(f.dpv1_profile_features, 2)
    if not field(f.dpv1_profile_ident, 2) then short(); return "DPV1 " .. name end
    field(f.dpv1_s_type, 1); local sl = field(f.dpv1_s_len, 1)
    field(f.dpv1_d_type, 1); local dl = field(f.dpv1_d_len, 1)
    if not (sl and dl) then short(); return "DPV1 " .. name end
    if (sl > 0 and not field(f.dpv1_s_addr, sl)) or (dl > 0 and not field(f.dpv1_d_addr, dl)) then
      short()
    end
    return "DPV1 " .. name .. (is_request and " request" or " response")
  elseif fn == 0x58 then
    field(f.dpv1_subnet, 1)
    if at + 2 > to then short(); return "DPV1 " .. name end
    item:add(f.dpv1_instance, tvb(at, 1)); item:add(f.dpv1_reason, tvb(at, 1))
    at = at + 1
    field(f.dpv1_detail, 1)
    return "DPV1 " .. name
  elseif fn == 0x56 then
    field(f.dpv1_rm_sap, 1)
    if not field(f.dpv1_send_timeout, 2) then short() end
    return "DPV1 " .. name
  end
  rest(f.dpv1_data)
  return "DPV1 " .. name
end

local function parse(tvb, pinfo, tree)
  local len = tvb:len()
  if len == 0 then
    tree:add_proto_expert_info(e.empty)
    return "empty frame"
  end
  local sd = tvb(0, 1):uint()
  local sd_item = tree:add(f.sd, tvb(0, 1))
  if sd_names[sd] == nil then
    sd_item:add_proto_expert_info(e.unknown_sd, "Unknown start delimiter " .. hex2(sd))
    if len > 1 then tree:add(f.du, tvb(1)) end
    return "unknown start delimiter " .. hex2(sd)
  end

  local function truncated(need)
    tree:add_proto_expert_info(e.truncated, string.format(
      "Frame truncated: %s needs %d bytes, %d present", sd_names[sd], need, len))
  end
  local function trailing(frame_len)
    if len > frame_len then
      tree:add_tvb_expert_info(e.trailing, tvb(frame_len), string.format(
        "%d byte(s) after the end of the frame", len - frame_len))
    end
  end

  if sd == SC then
    trailing(1)
    local svc = pinfo.visited and response_service[pinfo.number] or last_any
    if not pinfo.visited then
      if svc then response_service[pinfo.number] = svc end
      last_any = nil -- one SC answers the request just before it, once
    end
    if svc then tree:add(f.service, svc .. " response"):set_generated() end
    return "SC short acknowledge" .. (svc and (" (" .. svc .. ")") or "")
  end

  local pos = 1      -- first byte of DA
  local body = 0     -- DA .. last DU byte
  if sd == SD4 then
    body = 2
  elseif sd == SD1 then
    body = 3
  elseif sd == SD3 then
    body = 3 + 8
  else -- SD2: LE LEr SD
    if len < 2 then truncated(4); return "SD2 truncated" end
    local le = tvb(1, 1):uint()
    local le_item = tree:add(f.le, tvb(1, 1))
    if le < 4 or le > 249 then
      le_item:add_proto_expert_info(e.bad_le, string.format("LE %d outside 4..249", le))
    end
    if len < 3 then truncated(le + 6); return "SD2 truncated" end
    local ler = tvb(2, 1):uint()
    local ler_item = tree:add(f.ler, tvb(2, 1))
    if ler ~= le then
      ler_item:add_proto_expert_info(e.le_mismatch, string.format("LE %d, LEr %d", le, ler))
    end
    if len < 4 then truncated(le + 6); return "SD2 truncated" end
    local rep_item = tree:add(f.sd_rep, tvb(3, 1))
    if tvb(3, 1):uint() ~= SD2 then
      rep_item:add_proto_expert_info(e.bad_sd_rep, "Repeated start delimiter " ..
        hex2(tvb(3, 1):uint()) .. " is not 68h")
    end
    pos = 4
    body = le
  end

  local need = pos + body + (sd == SD4 and 0 or 2)
  local info = sd_names[sd]

  -- DA and SA
  if len < pos + 2 then truncated(need); return info .. " truncated" end
  local da_byte, sa_byte = tvb(pos, 1):uint(), tvb(pos + 1, 1):uint()
  local da, sa = bit.band(da_byte, 0x7F), bit.band(sa_byte, 0x7F)
  local da_item = tree:add(f.da, tvb(pos, 1))
  if da == BROADCAST then da_item:append_text(" (broadcast)") end
  if sd ~= SD4 then tree:add(f.da_ext, tvb(pos, 1)) end
  local sa_item = tree:add(f.sa, tvb(pos + 1, 1))
  if sd ~= SD4 then tree:add(f.sa_ext, tvb(pos + 1, 1)) end
  pinfo.cols.src = tostring(sa)
  pinfo.cols.dst = tostring(da)
  local route = string.format("%d → %d", sa, da)

  if sd == SD4 then
    if bit.band(da_byte, 0x80) ~= 0 or bit.band(sa_byte, 0x80) ~= 0 then
      da_item:add_proto_expert_info(e.reserved, "Address extension bit in a token")
    end
    trailing(3)
    if not pinfo.visited then last_any = nil end -- an SC after a token answers no request
    tree:add(f.service, "Token"):set_generated()
    return "SD4 token " .. route
  end

  -- FC
  if len < pos + 3 or body < 3 then
    if body < 3 then return info .. " " .. route .. ": LE too small for FC" end
    truncated(need); return info .. " " .. route .. " truncated"
  end
  local fc = tvb(pos + 2, 1):uint()
  local fc_range = tvb(pos + 2, 1)
  local fc_item = tree:add(f.fc, fc_range)
  local fc_tree = fc_item
  if bit.band(fc, 0x80) ~= 0 then
    fc_tree:add(f.fc_reserved, fc_range):add_proto_expert_info(e.reserved, "FC bit 7 is set")
  end
  local is_request = bit.band(fc, 0x40) ~= 0
  fc_tree:add(f.fc_request, fc_range)
  local code = bit.band(fc, 0x0F)
  local code_name
  if is_request then
    fc_tree:add(f.fc_fcb, fc_range)
    fc_tree:add(f.fc_fcv, fc_range)
    local fi = fc_tree:add(f.fc_function, fc_range)
    code_name = function_names[code]
    if code_name == nil then
      fi:add_proto_expert_info(e.reserved, "Reserved request function " .. hex2(code))
      code_name = "function " .. hex2(code)
    end
    fc_item:append_text(string.format(": %s, FCB %d, FCV %d", code_name,
      bit.band(bit.rshift(fc, 5), 1), bit.band(bit.rshift(fc, 4), 1)))
  else
    fc_tree:add(f.fc_station, fc_range)
    local ri = fc_tree:add(f.fc_response, fc_range)
    code_name = response_names[code]
    if code_name == nil then
      ri:add_proto_expert_info(e.reserved, "Reserved response code " .. hex2(code))
      code_name = "response " .. hex2(code)
    end
    fc_item:append_text(string.format(": %s, %s", code_name,
      station_types[bit.band(bit.rshift(fc, 4), 3)]))
  end

  -- DSAP, SSAP, DU: bytes pos+3 .. pos+body-1 (as far as present)
  local du_start = pos + 3
  local du_end = math.min(pos + body, len)  -- exclusive
  local dsap, ssap
  local function sap(field, ext_field, seg_field, at, slave_side, label)
    local b = tvb(at, 1):uint()
    local item = tree:add(field, tvb(at, 1))
    local n = bit.band(b, 0x3F)
    if slave_side then
      if dp_saps[n] then item:append_text(" (" .. dp_saps[n] .. ")") end
    elseif n == 62 then
      item:append_text(" (DP master)")
    end
    item:add(ext_field, tvb(at, 1))
    item:add(seg_field, tvb(at, 1))
    if bit.band(b, 0x80) ~= 0 then
      item:add_proto_expert_info(e.bad_sap, label .. " announces a further extension (unsupported)")
    end
    return n
  end
  if bit.band(da_byte, 0x80) ~= 0 then
    if du_start < du_end then
      dsap = sap(f.dsap, f.dsap_ext, f.dsap_seg, du_start, is_request, "DSAP")
      du_start = du_start + 1
    elseif sd == SD1 or body <= 3 then
      da_item:add_proto_expert_info(e.bad_sap, "DSAP announced, but the frame has no data field")
    end
  end
  if bit.band(sa_byte, 0x80) ~= 0 then
    if du_start < du_end then
      ssap = sap(f.ssap, f.ssap_ext, f.ssap_seg, du_start, not is_request, "SSAP")
      du_start = du_start + 1
    elseif sd == SD1 or du_start >= pos + body then
      sa_item:add_proto_expert_info(e.bad_sap, "SSAP announced, but the frame has no room for it")
    end
  end
  local dpv1_info
  if du_start < du_end then
    tree:add(f.du, tvb(du_start, du_end - du_start))
    -- DPV1 on the slave's SAPs 0..51 (MSAC_C1 50, 51; MSAC_C2 49 and its connections)
    local slave_sap = is_request and dsap or ssap
    if slave_sap ~= nil and slave_sap <= 51 then
      dpv1_info = dpv1(tvb, tree, du_start, du_end, is_request)
    end
  end
  if du_start <= pos + body then
    tree:add(f.du_len, math.max(0, pos + body - du_start)):set_generated()
  end

  -- Service name
  local svc
  if is_request then
    if code == 0x9 then
      svc = "FDL_Status"
    elseif dsap ~= nil then
      svc = dp_saps[dsap] or ("SAP " .. dsap)
    elseif code == 0xC or code == 0xD then
      svc = "Data_Exchange"
    else
      svc = code_name
    end
    if not pinfo.visited then
      last_request[sa .. ">" .. da] = svc
      -- SDN expects no answer; everything else may be acknowledged with SC.
      if code ~= 0x4 and code ~= 0x6 then last_any = svc else last_any = nil end
    end
    tree:add(f.service, svc .. " request"):set_generated()
    info = string.format("%s request %s  %s", svc, route, code_name)
  else
    if pinfo.visited then
      svc = response_service[pinfo.number]
    else
      svc = last_request[da .. ">" .. sa]
      if ssap ~= nil and (svc == nil or svc ~= (dp_saps[ssap] or ("SAP " .. ssap))) then
        svc = dp_saps[ssap] or ("SAP " .. ssap)
      end
      response_service[pinfo.number] = svc
      last_request[da .. ">" .. sa] = nil
      last_any = nil
    end
    if svc then tree:add(f.service, svc .. " response"):set_generated() end
    info = string.format("%s response %s  %s", svc or "FDL", route, code_name)
  end

  if dpv1_info then info = info .. "  " .. dpv1_info end

  -- FCS and ED
  local fcs_at = pos + body
  if len < fcs_at + 1 then truncated(need); return info .. " (truncated)" end
  local sum = 0
  for i = pos, fcs_at - 1 do sum = sum + tvb(i, 1):uint() end
  sum = sum % 256
  local fcs = tvb(fcs_at, 1):uint()
  local fcs_item = tree:add(f.fcs, tvb(fcs_at, 1))
  local ok = fcs == sum
  fcs_item:add(f.fcs_ok, tvb(fcs_at, 1), ok):set_generated()
  if ok then
    fcs_item:append_text(" [correct]")
  else
    fcs_item:append_text(string.format(" [incorrect, should be %02Xh]", sum))
    fcs_item:add_proto_expert_info(e.bad_fcs, string.format("Bad FCS %02Xh, sum of DA..DU is %02Xh",
      fcs, sum))
    info = info .. " [bad FCS]"
  end
  if len < fcs_at + 2 then truncated(need); return info .. " (truncated)" end
  local ed_item = tree:add(f.ed, tvb(fcs_at + 1, 1))
  if tvb(fcs_at + 1, 1):uint() ~= ED then
    ed_item:add_proto_expert_info(e.bad_ed, "End delimiter " .. hex2(tvb(fcs_at + 1, 1):uint()) ..
      " is not 16h")
    info = info .. " [bad ED]"
  end
  trailing(fcs_at + 2)
  return info
end

local data_dissector = Dissector.get("data")
-- epb_flags bit 31: the writer read a character with a parity, start or stop bit error, which no
-- byte shows (docs/capture.md).
local symbol_error = Field.new("frame.packet_flags_symbol_error")

function p.dissector(tvb, pinfo, tree)
  local len = tvb:len()
  if not p.prefs.all_unknown_encap and (len == 0 or sd_names[tvb(0, 1):uint()] == nil) then
    -- Not ours (another unknown link type): what Wireshark shows without this dissector.
    pinfo.cols.protocol = "UNKNOWN"
    pinfo.cols.info = "WTAP_ENCAP = 0"
    data_dissector:call(tvb, pinfo, tree)
    return len
  end
  pinfo.cols.protocol = "PROFIBUS"
  local sub = tree:add(p, tvb())
  local ok, info = pcall(parse, tvb, pinfo, sub)
  if not ok then
    sub:add_proto_expert_info(e.internal, "Dissector error: " .. tostring(info))
    info = "dissector error"
  end
  local broken = symbol_error()
  if broken and broken.value then
    sub:add_proto_expert_info(e.char_error, "A character with a parity, start or stop bit error " ..
      "(pcapng symbol error): every receiver discards the telegram")
  end
  pinfo.cols.info = info
  if len > 0 then sub:append_text(", " .. (sd_names[tvb(0, 1):uint()] or "?")) end
  return len
end

local wtap_table = DissectorTable.get("wtap_encap")
wtap_table:add(0, p) -- WTAP_ENCAP_UNKNOWN: link type 257 in Wireshark 4.0
local encap = wtap_encaps and (wtap_encaps.PROFIBUS_DL or wtap_encaps.PROFIBUS)
if encap then wtap_table:add(encap, p) end
