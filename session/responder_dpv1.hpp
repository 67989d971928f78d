// The built-in user side's DPV1 part (VPC3+, docs/dpv1.md "The built-in user side"): a firmware's
// answers to MSAC_C1 Read / Write / Alarm_Ack and to one MSAC_C2 connection, written against the
// SAP list and buffer layout of dpv1.hpp only, as a driver would. The Responder calls it from its
// init (the layout, while Offline) and its ISR (FDL_Ind, Poll_End_Ind, User_Timer_Clock).
#pragma once

#include <cstdint>
#include <optional>
#include <vector>

#include "dpc31/bus_port.hpp"
#include "dpc31/pdu.hpp"

namespace dpc31 {

struct Dpv1Record {
  std::uint8_t slot = 0;
  std::uint8_t index = 0;
  pdu::Bytes data;  // a Read returns up to its length; a Write must bring exactly its length
  friend bool operator==(const Dpv1Record&, const Dpv1Record&) = default;
};

struct Dpv1UserConfig {
  std::vector<Dpv1Record> records;  // none: DPV1 off (no SAP list)
  // The firmware's working time: from taking an indication (IND cleared) to handing over its
  // response (Control = USER + RESP), as a busy wait of the ISR.
  std::uint64_t work_cycles = 0;
  std::uint8_t c2_sap = 40;  // the SAP of the one MSAC_C2 connection (modelled)
  // The class-1 master's station address (MasterConfig's default 2 unless told): Request_SA of
  // SAPs 51 and 50, so that MSAC_C1 from any other station gets RS (docs/dpv1.md).
  std::uint8_t c1_master = 2;
};

class Dpv1User {
 public:
  // Max_Length of the buffers: MSAC_C1 and the connection take a 240-byte record and the 4-byte
  // head; Alarm_Ack is 4 bytes; the resource manager takes an Initiate of up to 32 bytes.
  static constexpr std::uint8_t kRecordMax = 244, kAlarmMax = 4, kRmMax = 32;

  explicit Dpv1User(Dpv1UserConfig cfg) : cfg_(std::move(cfg)) {}

  // The SAP list (SAPs 51 and 50 for the class-1 master only and switched off until Data_Exchange,
  // 49 for anybody, and the connection's SAP switched off) and its buffers from segment `list`
  // on; writes R_FDL_SAP_List_Ptr.
  void init(BusPort& c, std::uint32_t list, std::uint32_t seg_shift);
  // The segments init() takes from `list` on.
  [[nodiscard]] static std::uint32_t segments(std::uint32_t seg_shift);
  // From the ISR on Go/Leave_Data_Exchange: MSAC_C1 (SAPs 51 and 50) is served in Data_Exchange
  // only; leaving it switches them off and frees their buffers (a response not collected too).
  void data_exchange(BusPort& c, bool in);
  // From the ISR with the Int_Reg it read.
  void serve(BusPort& c, std::uint16_t ir);
  // User_Timer_Clock is wanted while a connection is open or the resource manager's response
  // waits (their time-outs).
  [[nodiscard]] bool timer_wanted() const { return open_ || rm_waits_; }

  [[nodiscard]] const std::vector<Dpv1Record>& records() const { return cfg_.records; }
  std::vector<pdu::AlarmAck> alarm_acks;  // every Alarm_Ack taken
  std::uint32_t timeouts = 0;             // connections closed by their Send_Timeout
  std::uint32_t rm_withdrawn = 0;         // resource manager responses nobody collected

 private:
  enum Sap : std::uint8_t { c1, alarm, rm, connection, kSaps };
  struct Slot {
    std::uint8_t sap = 0;
    std::uint32_t entry = 0;   // its SAP-list entry
    std::uint32_t buffer = 0;  // indication and response buffer (one, as the Profichip driver)
    std::uint8_t segment = 0;
  };
  // The response to `req` on SAP `s`; nullopt: none (the buffer is freed, the master times out).
  std::optional<pdu::Bytes> answer(BusPort& c, Sap s, const pdu::Bytes& req);
  std::optional<pdu::Bytes> record(pdu::Function f, const pdu::Bytes& req);
  void close(BusPort& c);

  Dpv1UserConfig cfg_;
  Slot slots_[kSaps];
  std::uint32_t seg_shift_ = 3;
  bool open_ = false;
  bool closing_ = false;  // the connection's buffer holds a refused Initiate's Abort or negative
  std::uint16_t send_timeout_ = 0;  // 10 ms
  std::uint64_t activity_ = 0;      // the connection's last request stored or response sent
  // The resource manager's response waits for its poll since `rm_since_`, at most the Initiate's
  // Send_Timeout `rm_timeout_` (10 ms): then it is withdrawn and SAP 49 takes Initiates again.
  bool rm_waits_ = false;
  std::uint16_t rm_timeout_ = 0;
  std::uint64_t rm_since_ = 0;
};

}  // namespace dpc31
