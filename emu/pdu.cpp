// The DP / DPV1 data units of include/dpc31/pdu.hpp: parse and build, each in one place.
#include "dpc31/pdu.hpp"

#include <algorithm>

namespace dpc31::pdu {

namespace {

std::uint16_t be16(View b, std::size_t i) {
  return static_cast<std::uint16_t>(b[i] << 8 | b[i + 1]);
}
// Every build sizes its vector once and fills it: growing one (insert, push_back) makes GCC 12
// at -O3 report false -Warray-bounds errors (issue 17).
std::size_t put16(Bytes& out, std::size_t i, std::uint16_t v) {
  out[i] = static_cast<std::uint8_t>(v >> 8);
  out[i + 1] = static_cast<std::uint8_t>(v);
  return i + 2;
}
std::size_t put(Bytes& out, std::size_t i, View bytes) {
  std::copy(bytes.begin(), bytes.end(), out.begin() + static_cast<std::ptrdiff_t>(i));
  return i + bytes.size();
}
// Bytes i, i + 1, ... of `du` into `fields`, in order.
template <typename... F>
void get_bytes(View du, std::size_t i, F&... fields) {
  ((fields = du[i++]), ...);
}
// `fields` into out[i], out[i + 1], ...; the index after them.
template <typename... F>
std::size_t put_bytes(Bytes& out, std::size_t i, F... fields) {
  ((out[i++] = fields), ...);
  return i;
}
bool has(View du, Function f) { return !du.empty() && du[0] == static_cast<std::uint8_t>(f); }

// Chk_Cfg identifier bytes (EN 50170): general format bits 5..4 00 special, 01 input,
// 10 output, 11 both; bits 3..0 length - 1; bit 6 words. Special format: bits 3..0 the
// manufacturer bytes, bits 7..6 00 none, 01 an input, 10 an output, 11 both length bytes
// (output first).
constexpr std::uint8_t kDirection = 0x30, kInput = 0x10, kOutput = 0x20, kWords = 0x40,
                       kLength = 0x0F, kLengthByteWords = 0x40, kLengthByteLength = 0x3F;

std::uint16_t len_of(std::uint8_t b, bool words_bit) {
  const auto n = static_cast<std::uint16_t>((b & kLength) + 1);
  return (b & (words_bit ? kWords : 0)) != 0 ? static_cast<std::uint16_t>(2 * n) : n;
}
std::uint16_t special_len(std::uint8_t b) {
  const auto n = static_cast<std::uint16_t>((b & kLengthByteLength) + 1);
  return (b & kLengthByteWords) != 0 ? static_cast<std::uint16_t>(2 * n) : n;
}

}  // namespace

// --- Set_Prm ---

View SetPrm::user_data() const {
  const std::size_t skip = dpv1() ? 3 : 1;
  return user_prm.size() <= skip ? View{} : View(user_prm).subspan(skip);
}

std::optional<SetPrm> SetPrm::parse(View du) {
  if (du.size() < kStandard) return std::nullopt;
  SetPrm p;
  get_bytes(du, 0, p.station_status, p.wd_fact1, p.wd_fact2, p.min_tsdr);
  p.ident = be16(du, 4);
  p.group_ident = du[6];
  p.user_prm.assign(du.begin() + kStandard, du.end());
  return p;
}

Bytes SetPrm::build() const {
  Bytes out(kStandard + user_prm.size());
  put16(out, put_bytes(out, 0, station_status, wd_fact1, wd_fact2, min_tsdr), ident);
  out[6] = group_ident;
  put(out, kStandard, user_prm);
  return out;
}

// --- Slave_Diag ---

std::optional<SlaveDiag> SlaveDiag::parse(View du) {
  if (du.size() < kStandard) return std::nullopt;
  SlaveDiag d;
  get_bytes(du, 0, d.station_status_1, d.station_status_2, d.station_status_3, d.master_add);
  d.ident = be16(du, 4);
  for (std::size_t i = kStandard; i < du.size();) {
    const auto kind = static_cast<Kind>(du[i] >> 6);
    // Device- and identifier-related blocks give their length (header included) in bits 5..0;
    // a channel-related block is always 3 bytes.
    const std::size_t n = kind == Kind::channel ? 3 : du[i] & 0x3F;
    if (n == 0 || i + n > du.size()) return std::nullopt;
    d.blocks.push_back({kind, Bytes(du.begin() + static_cast<std::ptrdiff_t>(i),
                                    du.begin() + static_cast<std::ptrdiff_t>(i + n))});
    i += n;
  }
  return d;
}

Bytes SlaveDiag::build() const {
  std::size_t n = kStandard;
  for (const Block& b : blocks) n += b.bytes.size();
  Bytes out(n);
  std::size_t i = put16(
      out, put_bytes(out, 0, station_status_1, station_status_2, station_status_3, master_add),
      ident);
  for (const Block& b : blocks) i = put(out, i, b.bytes);
  return out;
}

std::optional<Dpv1DiagBlock> Dpv1DiagBlock::parse(const SlaveDiag::Block& b) {
  if (b.kind != SlaveDiag::Kind::device || b.bytes.size() < kHeader) return std::nullopt;
  Dpv1DiagBlock d;
  d.status = (b.bytes[1] & kStatusFlag) != 0;
  d.type = static_cast<std::uint8_t>(b.bytes[1] & ~kStatusFlag);
  d.slot = b.bytes[2];
  d.specifier = b.bytes[3];
  d.data.assign(b.bytes.begin() + kHeader, b.bytes.end());
  return d;
}

SlaveDiag::Block Dpv1DiagBlock::build() const {
  Bytes bytes(kHeader + data.size());
  bytes[0] = static_cast<std::uint8_t>((kHeader + data.size()) & 0x3F);
  bytes[1] = static_cast<std::uint8_t>(type | (status ? kStatusFlag : 0));
  bytes[2] = slot;
  bytes[3] = specifier;
  put(bytes, kHeader, data);
  return {SlaveDiag::Kind::device, std::move(bytes)};
}

// --- Chk_Cfg ---

std::optional<Cfg> Cfg::parse(View du) {
  Cfg c;
  for (std::size_t i = 0; i < du.size();) {
    Module m;
    const std::uint8_t id = du[i];
    std::size_t n = 1;
    if ((id & kDirection) != 0) {  // general format
      const std::uint16_t len = len_of(id, true);
      if ((id & kInput) != 0) m.inputs = len;
      if ((id & kOutput) != 0) m.outputs = len;
    } else {
      // Special format: bits 7..6 01 an input length byte, 10 an output one, 11 both (output
      // first), then bits 3..0 bytes of manufacturer data (chip-facts.md section 8, EN 50170).
      const bool out = (id & 0x80) != 0, in = (id & 0x40) != 0;
      const std::size_t lens = (out ? 1 : 0) + (in ? 1 : 0);
      n = 1 + lens + (id & kLength);
      if (i + n > du.size()) return std::nullopt;
      std::size_t k = i + 1;
      if (out) m.outputs = special_len(du[k++]);
      if (in) m.inputs = special_len(du[k]);
    }
    m.bytes.assign(du.begin() + static_cast<std::ptrdiff_t>(i),
                   du.begin() + static_cast<std::ptrdiff_t>(i + n));
    c.modules.push_back(std::move(m));
    i += n;
  }
  return c;
}

Bytes Cfg::build() const {
  std::size_t n = 0;
  for (const Module& m : modules) n += m.bytes.size();
  Bytes out(n);
  std::size_t i = 0;
  for (const Module& m : modules) i = put(out, i, m.bytes);
  return out;
}

std::uint16_t Cfg::input_bytes() const {
  std::uint16_t n = 0;
  for (const Module& m : modules) n = static_cast<std::uint16_t>(n + m.inputs);
  return n;
}
std::uint16_t Cfg::output_bytes() const {
  std::uint16_t n = 0;
  for (const Module& m : modules) n = static_cast<std::uint16_t>(n + m.outputs);
  return n;
}

// --- DPV1 ---

std::optional<Function> function_of(View du) {
  if (du.empty()) return std::nullopt;
  const auto f = static_cast<std::uint8_t>(du[0] & ~kErrorBit);
  for (const Function k :
       {Function::Idle, Function::Data_Transport, Function::Resource_Manager, Function::Initiate,
        Function::Abort, Function::Alarm_Ack, Function::Read, Function::Write}) {
    if (f == static_cast<std::uint8_t>(k)) return k;
  }
  return std::nullopt;
}
bool is_negative(View du) { return !du.empty() && (du[0] & kErrorBit) != 0; }

std::optional<Record> Record::parse(View du, Function f, bool with_data) {
  if (du.size() < 4 || !has(du, f)) return std::nullopt;
  Record r{f, du[1], du[2], du[3], {}};
  if (!with_data) {
    if (du.size() != 4) return std::nullopt;
    return r;
  }
  if (du.size() != 4u + du[3]) return std::nullopt;
  r.data.assign(du.begin() + 4, du.end());
  return r;
}

Bytes Record::build() const {
  Bytes out(4 + data.size());
  out[0] = static_cast<std::uint8_t>(function);
  out[1] = slot;
  out[2] = index;
  out[3] = length;
  put(out, 4, data);
  return out;
}

Record read_request(std::uint8_t slot, std::uint8_t index, std::uint8_t length) {
  return {Function::Read, slot, index, length, {}};
}
Record write_request(std::uint8_t slot, std::uint8_t index, Bytes data) {
  const auto n = static_cast<std::uint8_t>(data.size());
  return {Function::Write, slot, index, n, std::move(data)};
}

std::optional<AlarmAck> AlarmAck::parse(View du) {
  if (du.size() != 4 || !has(du, Function::Alarm_Ack)) return std::nullopt;
  return AlarmAck{du[1], du[2], du[3]};
}
Bytes AlarmAck::build() const {
  return {static_cast<std::uint8_t>(Function::Alarm_Ack), slot, alarm_type, specifier};
}

std::optional<ErrorResponse> ErrorResponse::parse(View du) {
  if (du.size() != 4 || !is_negative(du)) return std::nullopt;
  const std::optional<Function> f = function_of(du);
  if (!f) return std::nullopt;
  return ErrorResponse{*f, du[1], du[2], du[3]};
}
Bytes ErrorResponse::build() const {
  return {static_cast<std::uint8_t>(static_cast<std::uint8_t>(function) | kErrorBit), error_decode,
          error_code_1, error_code_2};
}

namespace {
// Add_Addr_Param's S_Type, S_Len, D_Type, D_Len; before it the fixed fields.
constexpr std::size_t kAddrHead = 4, kInitiateReqHead = kInitiateReqFixed - kAddrHead,
                      kInitiateResHead = kInitiateResFixed - kAddrHead;
}  // namespace

std::optional<Initiate> Initiate::parse(View du, bool response) {
  const std::size_t head = response ? kInitiateResHead : kInitiateReqHead;
  if (du.size() < head + kAddrHead || !has(du, Function::Initiate)) return std::nullopt;
  Initiate p;
  p.response = response;
  std::size_t i = 1;
  if (response) {
    p.max_len_data_unit = du[i++];
  } else {
    i += 3;  // reserved
    p.send_timeout = be16(du, i);
    i += 2;
  }
  p.features_supported = be16(du, i);
  p.profile_features_supported = be16(du, i + 2);
  p.profile_ident_number = be16(du, i + 4);
  i += 6;
  p.s_type = du[i];
  const std::size_t s_len = du[i + 1];
  p.d_type = du[i + 2];
  const std::size_t d_len = du[i + 3];
  i += kAddrHead;
  if (du.size() != i + s_len + d_len) return std::nullopt;
  p.s_addr.assign(du.begin() + static_cast<std::ptrdiff_t>(i),
                  du.begin() + static_cast<std::ptrdiff_t>(i + s_len));
  p.d_addr.assign(du.begin() + static_cast<std::ptrdiff_t>(i + s_len), du.end());
  return p;
}

Bytes Initiate::build() const {
  Bytes out((response ? kInitiateResHead : kInitiateReqHead) + kAddrHead + s_addr.size() +
            d_addr.size());
  out[0] = static_cast<std::uint8_t>(Function::Initiate);
  std::size_t i = 1;
  if (response) {
    out[i++] = max_len_data_unit;
  } else {
    i = put16(out, i + 3, send_timeout);  // after 3 reserved bytes (0)
  }
  i = put16(out, i, features_supported);
  i = put16(out, i, profile_features_supported);
  i = put16(out, i, profile_ident_number);
  out[i] = s_type;
  out[i + 1] = static_cast<std::uint8_t>(s_addr.size());
  out[i + 2] = d_type;
  out[i + 3] = static_cast<std::uint8_t>(d_addr.size());
  put(out, put(out, i + kAddrHead, s_addr), d_addr);
  return out;
}

Initiate initiate_request(std::uint16_t send_timeout) {
  Initiate req;
  req.send_timeout = send_timeout;
  req.features_supported = Features_DPV1_RW;
  req.s_type = req.d_type = Addr_Type_API_SCL;
  req.s_addr = req.d_addr = Bytes(kAddrLenAPISCL, 0x00);
  return req;
}

std::optional<Abort> initiate_abort(View req) {
  const auto abort = [](std::uint8_t reason) {
    return Abort{0, Abort_Instance_MSAC_C2, reason, 0};
  };
  const std::size_t head = kInitiateReqFixed;
  if (req.size() < head) return abort(Abort_IA);  // not even its Add_Addr_Param's head
  const std::uint8_t s_type = req[12], s_len = req[13], d_type = req[14], d_len = req[15];
  if ((s_type == Addr_Type_API_SCL && s_len != kAddrLenAPISCL) ||
      (d_type == Addr_Type_API_SCL && d_len != kAddrLenAPISCL))
    return abort(Abort_FE);
  if (req.size() < kInitiateReqMin || req.size() < head + s_len + d_len) return abort(Abort_IA);
  return std::nullopt;
}

std::optional<Abort> Abort::parse(View du) {
  if (du.size() != 4 || !has(du, Function::Abort)) return std::nullopt;
  return Abort{du[1], static_cast<std::uint8_t>((du[2] >> 4) & 0x3),
               static_cast<std::uint8_t>(du[2] & 0x0F), du[3]};
}
Bytes Abort::build() const {
  return {static_cast<std::uint8_t>(Function::Abort), subnet,
          static_cast<std::uint8_t>((instance & 0x3) << 4 | (reason_code & 0x0F)),
          additional_detail};
}

std::optional<Idle> Idle::parse(View du) {
  if (du.size() != 2 || !has(du, Function::Idle)) return std::nullopt;
  return Idle{};
}
Bytes Idle::build() const { return {static_cast<std::uint8_t>(Function::Idle), 0x00}; }

std::optional<ResourceManager> ResourceManager::parse(View du) {
  if (du.size() != 4 || !has(du, Function::Resource_Manager)) return std::nullopt;
  return ResourceManager{du[1], be16(du, 2)};
}
Bytes ResourceManager::build() const {
  Bytes out = {static_cast<std::uint8_t>(Function::Resource_Manager), sap, 0, 0};
  put16(out, 2, send_timeout);
  return out;
}

}  // namespace dpc31::pdu
