// The SAP list (VPC3+C pp. 54-56, docs/dpv1.md). Where the manual is silent the choices are in
// docs/decisions.md ("DPV1"): the list is read at every request, 00h pointers switch off, data
// longer than Max_Length get RR, the response needs RESP and USER, its FC is the header's.
#include "sap_list.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <string>

#include "dpc31/chip.hpp"
#include "dpc31/dpv1.hpp"

namespace dpc31 {

namespace {

namespace e = dpv1::entry;
namespace h = dpv1::header;

// The most entries a list can hold: one per SAP 0-51.
constexpr std::uint32_t kMaxEntries = 52;
// The longest response data unit: LE 249 less DA, SA, FC, DSAP, SSAP.
constexpr std::size_t kMaxResponse = fdl::kMaxLe - 5;

bool service_allowed(std::uint8_t code, fdl::Function fn) {
  const bool srd = fn == fdl::Function::SRD_low || fn == fdl::Function::SRD_high;
  const bool high = fn == fdl::Function::SRD_high || fn == fdl::Function::SDN_high;
  switch (code) {
    case dpv1::service::All:
    case dpv1::service::SDN_SRD_LH:
      return true;
    case dpv1::service::SDN_L:
      return !srd && !high;
    case dpv1::service::SDN_H:
      return !srd && high;
    case dpv1::service::SDN_LH:
      return !srd;
    case dpv1::service::SRD_L:
      return srd && !high;
    case dpv1::service::SRD_H:
      return srd && high;
    case dpv1::service::SRD_LH:
      return srd;
    default:  // SDA, DDB, undefined: the chip serves no such request on a listed SAP
      return false;
  }
}

// Request_SA / Request_SSAP: 7Fh lets everybody in (bit 7 is not compared: modelled).
bool matches(std::uint8_t wanted, std::uint8_t got) {
  const auto w = static_cast<std::uint8_t>(wanted & fdl::kAddressMask);
  return w == e::kAll || w == got;
}

}  // namespace

std::string_view refusal_on_line(const fdl::Frame& req, std::string_view code) {
  if (req.da == fdl::kBroadcast) return "broadcast: no answer";
  switch (fdl::request_function(req.fc)) {
    case fdl::Function::SRD_low:
    case fdl::Function::SRD_high:
      return code;
    case fdl::Function::SDN_low:
    case fdl::Function::SDN_high:
      return "SDN: no answer";
    default:  // a function the DP slave does not serve (the DP_Mode = 0 refusal)
      return "no answer";
  }
}

std::uint32_t SapList::find(std::uint8_t sap) {
  const std::uint8_t ptr = regs_.cell(RegId::R_FDL_SAP_List_Ptr);
  if (ptr == 0) return 0;  // no list (modelled, as R_SSA_Buf_Ptr = 00h switches SAP55 off)
  std::uint32_t a = segment(ptr);
  regs_.note_buffer(RegId::R_FDL_SAP_List_Ptr, a, e::kBytes);
  for (std::uint32_t i = 0; i < kMaxEntries; ++i, a += e::kBytes) {
    const std::uint8_t b0 = regs_.ram_read(a + e::Sap);
    if (b0 == e::kEndOfList) return 0;
    if ((b0 & e::SAP_Number) == sap) return a;
  }
  return 0;
}

std::uint32_t SapList::buffer(std::uint32_t entry, std::uint32_t field, std::uint8_t ptr) {
  const std::uint32_t buf = segment(ptr);
  if (regs_.over_registers(buf)) {
    const char* name = field == e::Ind_Buf_Ptr0   ? "Ind_Buf_Ptr[0]"
                       : field == e::Ind_Buf_Ptr1 ? "Ind_Buf_Ptr[1]"
                                                  : "Resp_Buf_Ptr";
    regs_.note_buffer(
        fmt::format("SAP {}'s {}", regs_.ram_read(entry + e::Sap) & e::SAP_Number, name), ptr, buf);
  }
  return buf;
}

SapListAnswer SapList::request(const fdl::Frame& req) {
  using Kind = SapListAnswer::Kind;
  if (!s_.enabled || !req.dsap) return {};
  const std::uint8_t sap = fdl::sap_number(*req.dsap);
  const std::uint32_t entry = find(sap);
  if (entry == 0) return {};
  const fdl::Function fn = fdl::request_function(req.fc);
  const char* refused = nullptr;
  if (!matches(regs_.ram_read(entry + e::Request_SA), req.sa)) refused = "Request_SA differs";
  if (!matches(regs_.ram_read(entry + e::Request_SSAP),
               req.ssap ? fdl::sap_number(*req.ssap) : fdl::kAddressMask))
    refused = "Request_SSAP differs";
  if (!service_allowed(regs_.ram_read(entry + e::Service_Supported), fn))
    refused = "service not in Service_Supported";
  const std::uint8_t ind0 = regs_.ram_read(entry + e::Ind_Buf_Ptr0);
  if (ind0 == 0) refused = "Ind_Buf_Ptr[0] = 00h: SAP not activated";
  if (refused != nullptr) {
    sig_.log(LogLevel::info, "SAP {} from {}: {} ({})", sap, req.sa, refused,
             refusal_on_line(req, "RS"));
    return {Kind::refused, 0, {}};
  }
  const bool srd = fn == fdl::Function::SRD_low || fn == fdl::Function::SRD_high;
  // A request without data is a poll: "Polling telegrams do not produce interrupts."
  if (!req.du.empty()) {
    sig_.emit(BlockEvent::Kind::sap_ind, static_cast<std::uint16_t>(entry),
              static_cast<std::uint8_t>(req.du.size()));
    if (!indicate(entry, req)) {
      // The two causes of p.56's RR: no buffer free, or the data longer than the free one.
      const std::uint32_t buf = free_buffer(entry);
      const std::string why =
          buf == 0 ? fmt::format("no free indication buffer for {} bytes", req.du.size())
                   : fmt::format("{} bytes, more than Max_Length {}", req.du.size(),
                                 regs_.ram_read(buf + h::Max_Length));
      sig_.log(LogLevel::info, "SAP {} from {}: {} ({})", sap, req.sa, why,
               refusal_on_line(req, "RR"));
      return {Kind::no_buffer, 0, {}};
    }
  }
  if (!srd) return {Kind::sc, 0, {}};
  sig_.emit(BlockEvent::Kind::sap_srd, static_cast<std::uint16_t>(entry));
  return answer(entry);
}

std::uint32_t SapList::free_buffer(std::uint32_t entry) {
  const std::uint8_t ind0 = regs_.ram_read(entry + e::Ind_Buf_Ptr0);
  const std::uint8_t ind1 = regs_.ram_read(entry + e::Ind_Buf_Ptr1);
  // Ind_Buf_Ptr[1] = 00h or the same buffer (the Profichip driver's MSAC_C1 SAPs): one buffer.
  for (const std::uint32_t field : {e::Ind_Buf_Ptr0, e::Ind_Buf_Ptr1}) {
    const std::uint8_t p = field == e::Ind_Buf_Ptr0 ? ind0 : ind1;
    if (p == 0 || (field == e::Ind_Buf_Ptr1 && ind1 == ind0)) continue;
    const std::uint32_t buf = buffer(entry, field, p);
    if ((regs_.ram_read(buf + h::Control) & (h::USER | h::IND | h::RESP | h::INUSE)) == 0)
      return buf;
  }
  return 0;
}

bool SapList::indicate(std::uint32_t entry, const fdl::Frame& req) {
  // The first free buffer takes it, or nothing does.
  const std::uint32_t buf = free_buffer(entry);
  if (buf == 0 || !store(buf, req)) return false;
  irq_.raise(irq::FDL_Ind);
  return true;
}

// The telegram into a free buffer: INUSE while the chip fills it, then USER + IND.
bool SapList::store(std::uint32_t buf, const fdl::Frame& req) {
  if (req.du.size() > regs_.ram_read(buf + h::Max_Length)) return false;
  regs_.ram_write(buf + h::Control, h::INUSE);
  for (std::size_t i = 0; i < req.du.size(); ++i)
    regs_.ram_write(buf + h::kBytes + static_cast<std::uint32_t>(i), req.du[i]);
  regs_.ram_write(buf + h::Length, static_cast<std::uint8_t>(req.du.size()));
  regs_.ram_write(buf + h::Function_Code, req.fc);
  regs_.ram_write(buf + h::Control, h::USER | h::IND);
  return true;
}

// SC until the user has put a response into the response buffer (RESP with USER).
SapListAnswer SapList::answer(std::uint32_t entry) {
  using Kind = SapListAnswer::Kind;
  const std::uint8_t rp = regs_.ram_read(entry + e::Resp_Buf_Ptr);
  if (rp == 0) return {Kind::sc, 0, {}};
  const std::uint32_t buf = buffer(entry, e::Resp_Buf_Ptr, rp);
  if ((regs_.ram_read(buf + h::Control) & (h::USER | h::RESP)) != (h::USER | h::RESP))
    return {Kind::sc, 0, {}};
  const std::size_t len = std::min<std::size_t>(
      {regs_.ram_read(buf + h::Length), regs_.ram_read(buf + h::Max_Length), kMaxResponse});
  SapListAnswer a{Kind::response,
                  static_cast<std::uint8_t>(regs_.ram_read(buf + h::Function_Code) &
                                            ~(fdl::kFcRequest | fdl::kExtension)),
                  std::vector<std::uint8_t>(len)};
  for (std::size_t i = 0; i < len; ++i)
    a.du[i] = regs_.ram_read(buf + h::kBytes + static_cast<std::uint32_t>(i));
  s_.sending = true;
  s_.entry = entry;
  s_.response = buf;
  return a;
}

// "The Poll_End_Ind interrupt is set after the Response-Buffer is sent. Also bits RESP and USER
// are cleared." Response_Sent: "1 = Response sent".
void SapList::response_sent() {
  if (!s_.sending) return;
  sig_.emit(BlockEvent::Kind::sap_sent);
  s_.sending = false;
  regs_.ram_write(
      s_.response + h::Control,
      static_cast<std::uint8_t>(regs_.ram_read(s_.response + h::Control) & ~(h::RESP | h::USER)));
  regs_.ram_write(s_.entry + e::Sap,
                  static_cast<std::uint8_t>(regs_.ram_read(s_.entry + e::Sap) | e::Response_Sent));
  irq_.raise(irq::Poll_End_Ind);
}

}  // namespace dpc31
