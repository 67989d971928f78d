// The built-in master's DPV1 side (docs/dpv1.md, "The master's side"): MSAC_C1 as a class-1
// master (Read / Write / Alarm_Ack on SAP 51) and MSAC_C2 as a class-2 master (Initiate on SAP 49,
// then Read / Write / Data_Transport / Idle on the connection's SAP, Abort). A layer on
// DpMaster's public API only (acyclic, retry): each service sends its request, polls (an SRD
// without data, same SAPs, a new FCB each) while the slave answers SC, and returns the positive
// or negative response parsed with pdu.hpp, with the cycles of the exchange. The rules (retries,
// the response time-out) are EN 50170 / IEC 61158-6's, with the values of docs/decisions.md.
#pragma once

#include <cstdint>
#include <functional>
#include <optional>
#include <string>
#include <string_view>

#include "dp_master.hpp"
#include "dpc31/dp.hpp"
#include "dpc31/pdu.hpp"

namespace dpc31 {

struct Dpv1Rules {
  // A request or poll without any answer within the slot time is sent again, unchanged (same
  // FCB), this often (the FDL's max_retry_limit) before the service fails with no_answer.
  std::uint32_t retries = 1;
  // The response time-out from the request's first start bit: the GSD's C1_Response_Timeout
  // (10 ms units); MSAC_C2 uses the connection's Send_Timeout instead. 100 = 1 s.
  std::uint16_t c1_response_timeout = 100;
  // The class-2 master's own SAP (SSAP of every MSAC_C2 telegram; modelled).
  std::uint8_t c2_ssap = 48;
};

struct Dpv1Answer {
  enum class Outcome : std::uint8_t {
    positive,   // the response of the request's function
    negative,   // function | 80h, Error_Decode, Error_Code_1, Error_Code_2
    refused,    // an FDL answer without data that is not SC (RS, RR, UE...)
    no_answer,  // a request or poll stayed unanswered after its retries
    timeout,    // still SC when the response time-out ran out
    malformed,  // data that is neither the positive nor the negative response
    // MSAC_C2 without an open connection: nothing sent (the master has no SAP to send it to)
    no_connection,
    // the slave's Abort PDU (58h) in place of an MSAC_C2 response: the connection is gone
    aborted,
  };
  Outcome outcome = Outcome::no_answer;
  pdu::Bytes du;                            // the response's data unit as received
  std::optional<pdu::ErrorResponse> error;  // negative
  std::optional<pdu::Abort> abort;          // aborted: the slave's Instance and Reason_Code
  std::optional<fdl::Frame> last;           // the last answer on the wire
  std::uint32_t polls = 0;                  // polls answered SC before the response
  // The request's first start bit, and the outcome's cycle (docs/dpv1.md, "The outcome's
  // cycle"): the last answer's last stop bit; no_answer: where the master's wait ended after the
  // last try (Exchange::wait_end, docs/timing.md "The master's wait"); no_connection: both the
  // cycle the service was asked for, never before the previous service's outcome cycle.
  std::uint64_t start = 0;
  std::uint64_t end = 0;
};

// The DPV1 services' refusal on a chip without DPV1 (the scenario parser's, Python's and
// Dpv1Master's words).
inline constexpr std::string_view kDpv1OnVpc3plusOnly =
    "DPV1 is modelled on the VPC3+ only (the DPC31's is not modelled; the SPC3 has none)";

[[nodiscard]] std::string outcome_name(Dpv1Answer::Outcome o);
// "5E 00 01 04 11 22 33 44 after 2 polls", "negative 80 B0 00", "timeout after 40 polls",
// "malformed DL without data after 0 polls" ...
[[nodiscard]] std::string answer_summary(const Dpv1Answer& a);

// "" on a VPC3+, else why WHAT ("DPV1 services", "records") are refused on `chip`, every door's
// words: "DPV1 services need a vpc3plus, not a dpc31: DPV1 is modelled on the VPC3+ only (...)".
[[nodiscard]] std::string dpv1_refused(const Chip& chip, std::string_view what);

class Dpv1Master {
 public:
  // On another chip than the VPC3+ std::invalid_argument ("Dpv1Master: " and dpv1_refused's
  // words): its services are refused before anything is sent (docs/dpv1.md).
  Dpv1Master(const Chip& chip, DpMaster& m, Dpv1Rules r = {});

  // MSAC_C1: Read / Write from SAP 51 to SAP 51, Alarm_Ack from SAP 51 to the slave's SAP 50 or
  // 51 (`dsap`; the standard allows both). Another `dsap` is sent as given, for a bench that
  // tests a wrong SAP (the scenario and Python refuse it: kAlarmSap).
  Dpv1Answer read(std::uint8_t slot, std::uint8_t index, std::uint8_t length);
  Dpv1Answer write(std::uint8_t slot, std::uint8_t index, pdu::Bytes data);
  Dpv1Answer alarm_ack(const pdu::AlarmAck& ack, std::uint8_t dsap = sap::MSAC_C1_Alarm);

  // MSAC_C2. initiate sends the Initiate request to SAP 49 and polls it until the resource
  // manager's immediate response (56h: the connection's SAP, the slave's Send_Timeout), then
  // polls the connection's SAP for the Initiate response; positive: the connection is open
  // (c2_sap()), its Send_Timeout the larger of the request's and the resource manager's (the
  // slave's minimum: the Profichip driver runs the connection on that larger one); otherwise the
  // connection open before, if any, stays open. A service the slave answers with an Abort PDU
  // is `aborted`, and the master forgets that SAP's connection.
  Dpv1Answer initiate(const pdu::Initiate& req);
  Dpv1Answer c2_read(std::uint8_t slot, std::uint8_t index, std::uint8_t length);
  Dpv1Answer c2_write(std::uint8_t slot, std::uint8_t index, pdu::Bytes data);
  Dpv1Answer c2_transport(std::uint8_t slot, std::uint8_t index, pdu::Bytes data);
  Dpv1Answer c2_idle();
  // Abort: one SRD, answered SC; only then is the connection closed on our side. Refused (RS,
  // RR) or unanswered, the slave may still hold it: it stays known, and the Abort may be sent
  // again.
  Dpv1Answer c2_abort(const pdu::Abort& a);
  [[nodiscard]] std::optional<std::uint8_t> c2_sap() const { return c2_sap_; }
  // The open connection's Send_Timeout (10 ms units) the master times its services out on.
  [[nodiscard]] std::uint16_t c2_send_timeout() const { return c2_timeout_; }

  [[nodiscard]] const Dpv1Rules& rules() const { return rules_; }
  Dpv1Rules& rules() { return rules_; }

  // Called after each poll of a service, its exchange the newest of the master's history(): the
  // scenario runner reports it there and forgets what it reported. Unset, the master keeps a
  // service's request, its first kKeptPolls polls and its newest in history(), and forgets the
  // polls between, so a long time-out keeps the history flat (Dpv1Answer::polls counts them all).
  std::function<void()> polled;
  static constexpr std::uint32_t kKeptPolls = 16;

 private:
  // Sends `req` from `ssap` to `dsap`, polls while SC until `timeout` cycles after `since` (the
  // cycle the service began; unset: this request's first start bit).
  Dpv1Answer transfer(std::uint8_t dsap, std::uint8_t ssap, pdu::Bytes req, std::uint64_t timeout,
                      std::optional<std::uint64_t> since = std::nullopt);
  // The positive response is of `f` and parses as `ok` says, or the negative one of `f`.
  static void classify(Dpv1Answer& a, pdu::Function f, bool positive_ok);
  // An Abort PDU from `sap` in place of the response: aborted, and that SAP's connection gone.
  void take_abort(Dpv1Answer& a, std::uint8_t sap);
  Dpv1Answer on_connection(pdu::Function f, pdu::Bytes req, bool with_data);
  // MSAC_C2 without an open connection: at the current cycle, nothing sent.
  [[nodiscard]] Dpv1Answer no_connection() const;
  // Fills the answer's last answer, end and outcome from one exchange: no_answer, refused (not
  // SC and no data), else positive (the caller looks further).
  void take(Dpv1Answer& a, const Exchange& ex);
  [[nodiscard]] std::uint64_t cycles_10ms(std::uint32_t units) const;

  const Chip& chip_;
  DpMaster& m_;
  Dpv1Rules rules_;
  std::optional<std::uint8_t> c2_sap_;
  std::uint16_t c2_timeout_ = 0;  // the connection's Send_Timeout (10 ms)
  std::uint64_t last_end_ = 0;    // the last outcome's cycle (no_connection is not before it)
};

}  // namespace dpc31
