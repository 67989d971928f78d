// The VPC3+'s SAP list (VPC3+C chapter 7, pp. 54-56; docs/dpv1.md): requests to the SAPs 0-51 a
// firmware lists at R_FDL_SAP_List_Ptr are checked against their entry (Request_SA,
// Request_SSAP, Service_Supported: RS on a mismatch), stored in a free indication buffer (RR when
// there is none) and handed to the user with USER + IND and FDL_Ind; a request or poll is
// answered SC until the user sets RESP (with USER) in the response buffer, then with the response,
// after which RESP and USER are cleared, Response_Sent set and Poll_End_Ind raised. The list is
// served once a Set_Prm with DPV1_Enable has been accepted (p.54).
#pragma once

#include <cstdint>
#include <string_view>
#include <vector>

#include "dpc31/fdl.hpp"
#include "irq.hpp"
#include "regfile.hpp"
#include "signals.hpp"

namespace dpc31 {

// What the SAP list makes of a request; the DP state machine frames it.
struct SapListAnswer {
  enum class Kind : std::uint8_t {
    unknown,    // not a listed SAP (or DPV1 off): RS, as for any SAP the chip does not serve
    refused,    // SA / SSAP / service mismatch, or the SAP not activated: RS
    no_buffer,  // no free indication buffer, or the data do not fit it: RR
    sc,         // taken (or a poll) with no response ready: SC
    response,   // the user's response buffer
  };
  Kind kind = Kind::unknown;
  std::uint8_t fc = 0;  // response: the FC the user wrote into the header
  std::vector<std::uint8_t> du;
};

// A refusal as it goes on the line, for the log: `code` (RS, RR) answers an SRD to us; an SDN, a
// broadcast or another function gets no answer (docs/dpv1.md: "SDN requests are not answered").
[[nodiscard]] std::string_view refusal_on_line(const fdl::Frame& req, std::string_view code);

class SapList {
 public:
  struct State {
    bool enabled = false;        // DPV1_Enable of the last Set_Prm the ASIC accepted
    bool sending = false;        // a response buffer is on the wire
    std::uint32_t entry = 0;     // its SAP-list entry (RAM address)
    std::uint32_t response = 0;  // its header (RAM address)
  };

  SapList(RegisterFile& regs, InterruptController& irq, const Signals& sig)
      : regs_(regs), irq_(irq), sig_(sig) {}
  void reset() { s_ = State{}; }
  void enable(bool on) { s_.enabled = on; }
  [[nodiscard]] bool enabled() const { return s_.enabled; }

  // A request (SRD or SDN, not broadcast) to SAP `dsap` <= 51, acted on now.
  SapListAnswer request(const fdl::Frame& req);
  void response_sent();  // our answer's last stop bit is out
  // The two steps after the checks (the lockstep's adapter replays them from the block events
  // sap_ind and sap_srd): the data into the first free indication buffer of the entry (false:
  // RR), and the SRD's answer from the entry's response buffer.
  bool indicate(std::uint32_t entry, const fdl::Frame& req);
  SapListAnswer answer(std::uint32_t entry);

 private:
  friend struct BlockAccess;
  [[nodiscard]] std::uint32_t find(std::uint8_t sap);  // the entry's address, 0: none
  std::uint32_t segment(std::uint8_t ptr) const {
    return std::uint32_t{ptr} << regs_.segment_shift();
  }
  // The buffer at segment `ptr`, the entry's pointer at `field` (Ind_Buf_Ptr0/1, Resp_Buf_Ptr);
  // one over the registers is logged (RegisterFile::note_buffer).
  std::uint32_t buffer(std::uint32_t entry, std::uint32_t field, std::uint8_t ptr);
  // The entry's first indication buffer with none of USER, IND, RESP, INUSE; 0: none.
  [[nodiscard]] std::uint32_t free_buffer(std::uint32_t entry);
  bool store(std::uint32_t buf, const fdl::Frame& req);

  RegisterFile& regs_;
  InterruptController& irq_;
  const Signals& sig_;
  State s_;
};

}  // namespace dpc31
