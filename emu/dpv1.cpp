// The DP state machine's DPV1 part on the VPC3+ (VPC3+C chapter 7, docs/dpv1.md): the checks of
// DPV1_Status_1..3 in Set_Prm, Set_Ext_Prm on SAP 53, and the answers of the SAP list framed.
// Decisions where the manual is silent: docs/decisions.md ("DPV1").
#include "dpc31/dpv1.hpp"

#include <fmt/format.h>

#include <string_view>

#include "dp_sm.hpp"

namespace dpc31 {

using fdl::Frame;
using fdl::Response;

// VPC3+C p.53: a Set_Prm with DPV1_Enable carries DPV1_Status_1..3 (bytes 7-9). The reasons the
// ASIC refuses it with Prm_Fault, or nullptr.
const char* DpStateMachine::dpv1_prm_fault(const pdu::SetPrm& prm) const {
  if (prm.user_prm.size() < 3) return "DPV1_Enable without DPV1_Status_2 and _3";
  const std::uint8_t s1 = prm.status(1), s2 = prm.status(2), s3 = prm.status(3);
  const bool check_reserved =
      (regs_.latch(RegId::Mode_Reg2) & fields::Mode_Reg2::No_Check_Prm_Reserved) == 0;
  if (check_reserved &&
      ((s1 & dpv1::status1::Reserved) != 0 || (s2 & dpv1::status2::Reserved) != 0 ||
       (s3 & dpv1::status3::Reserved) != 0))
    return "reserved DPV1_Status bits";
  // "If the extensions are used, the bit Spec_Clear_Mode in Mode Register 0 serves as
  // Fail_Safe_required ... If the DP-Slave requires Fail_Safe but the DP-Master doesn't the
  // Prm_Fault bit is set."
  if (regs_.mode0(fields::Mode_Reg0::Spec_Clear_Mode) && (s1 & dpv1::status1::Fail_Safe) == 0)
    return "Fail_Safe required (Spec_Clear_Mode) but not set by the master";
  // "If redundancy should be supported, the PrmCmd_Supported bit in Mode Register 0 must be set."
  if ((s3 & dpv1::status3::PrmCmd) != 0 && !regs_.mode0(fields::Mode_Reg0::PrmCmd_Supported))
    return "PrmCmd but PrmCmd_Supported not set";
  return nullptr;
}

// Set_Ext_Prm (SAP 53): with Set_Ext_Prm_Supported, from the locking master, in Wait_Cfg before a
// Chk_Cfg; into the Prm buffer through the Aux buffer as Set_Prm, then New_Ext_Prm_Data, which
// the User_Prm_Data_(Not_)Okay reads answer. Another master is ignored in every state, as its
// Set_Prm and Chk_Cfg are (DPC31 p.28), before the state is looked at (docs/decisions.md).
std::optional<Frame> DpStateMachine::set_ext_prm(const Frame& req) {
  const auto refuse = [&](std::string_view why, Response code) {
    sig_.log(LogLevel::info, "Set_Ext_Prm from {}: {} ({})", req.sa, why,
             refusal_on_line(req, code == Response::RS ? "RS" : "RR"));
    return short_answer(req, code);
  };
  if (regs_.id() != Profile::vpc3plus || !regs_.mode0(fields::Mode_Reg0::Set_Ext_Prm_Supported)) {
    ++counters_.unknown_sap;
    return refuse("SAP 53 not supported", Response::RS);
  }
  if (locked_by_another(req.sa)) {
    ++counters_.not_allowed;
    sig_.log(LogLevel::info, "Set_Ext_Prm from {}: not the locking master: ignored", req.sa);
    return fdl::sc();
  }
  const char* not_now = nullptr;
  if (s_.state != DpState::Wait_Cfg || s_.cfg.pending) {
    not_now = "not between Set_Prm and Chk_Cfg";
  } else if (s_.prm.pending) {  // in Wait_Cfg only a Set_Ext_Prm's (a Set_Prm leaves it)
    not_now = "an earlier Set_Ext_Prm waits for its verdict";
  }
  if (not_now != nullptr) {
    ++counters_.not_allowed;
    return refuse(not_now, Response::RS);
  }
  // An empty one is refused as a data unit of the wrong length is (Get_Cfg with data, Rd_Inp:
  // "no resource", DPC31 p.33), and as an empty Chk_Cfg.
  if (req.du.empty()) {
    ++counters_.no_resource;
    return refuse("no data", Response::RR);
  }
  if (!receive_via_aux(fields::R_Aux_Buf_Sel::Set_Prm, RegId::R_Prm_Buf_Ptr, RegId::R_Len_Prm_Data,
                       req.du)) {
    ++counters_.no_resource;
    return refuse(fmt::format("{} bytes, longer than the Aux buffer", req.du.size()), Response::RR);
  }
  sig_.emit(BlockEvent::Kind::ext_prm);
  ext_prm_accepted();
  return fdl::sc();
}

// The Prm buffer holds a Set_Ext_Prm: the user's verdict is asked with New_Ext_Prm_Data.
void DpStateMachine::ext_prm_accepted() {
  s_.prm.arrived();
  s_.ext_prm = true;
  irq_.raise(irq::New_Ext_Prm_Data);
}

// The SAP list's verdict as a telegram: RS and RR as for the DP SAPs, SC, or the user's response
// from our SAP to the master's.
Frame DpStateMachine::sap_list_answer(const Frame& req, const SapListAnswer& a) {
  using Kind = SapListAnswer::Kind;
  switch (a.kind) {
    case Kind::unknown:
      ++counters_.unknown_sap;
      sig_.log(LogLevel::info, "DSAP {} from {}: not served ({})", fdl::sap_number(*req.dsap),
               req.sa, refusal_on_line(req, "RS"));
      return short_answer(req, Response::RS);
    case Kind::refused:
      ++counters_.not_allowed;
      return short_answer(req, Response::RS);
    case Kind::no_buffer:
      ++counters_.no_resource;
      return short_answer(req, Response::RR);
    case Kind::sc:
      return fdl::sc();
    case Kind::response:
      break;
  }
  return fdl::make_frame(req.sa, s_.station, a.fc, a.du, req.ssap, req.dsap);
}

}  // namespace dpc31
