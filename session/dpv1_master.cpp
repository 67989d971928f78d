// The built-in master's DPV1 side (dpv1_master.hpp).
#include "dpv1_master.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <stdexcept>

#include "dpc31/dp.hpp"
#include "dpc31/hex.hpp"
#include "dpc31/names.hpp"
#include "vocabulary.hpp"

namespace dpc31 {

namespace {
using pdu::Function;
}  // namespace

constexpr std::array<std::string_view, 8> kOutcomeNames = {"positive",      "negative", "refused",
                                                           "no answer",     "timeout",  "malformed",
                                                           "no connection", "aborted"};
static_assert(kOutcomeNames.size() == static_cast<std::size_t>(Dpv1Answer::Outcome::aborted) + 1,
              "a new value: name it here");

std::string outcome_name(Dpv1Answer::Outcome o) { return std::string(name_of(o, kOutcomeNames)); }

std::string answer_summary(const Dpv1Answer& a) {
  const std::string polls = fmt::format("after {} poll{}", a.polls, a.polls == 1 ? "" : "s");
  switch (a.outcome) {
    case Dpv1Answer::Outcome::positive:
      if (a.du.empty()) return fmt::format("SC {}", polls);  // Abort: no response PDU
      [[fallthrough]];
    case Dpv1Answer::Outcome::malformed:
      if (a.du.empty() && a.last) {  // a data response of no data: its FC names it
        return fmt::format("malformed {} without data {}",
                           response_name(fdl::response_code(a.last->fc)), polls);
      }
      return fmt::format("{}{} {}", a.outcome == Dpv1Answer::Outcome::malformed ? "malformed " : "",
                         hex_bytes(a.du, " ", 16), polls);
    case Dpv1Answer::Outcome::negative:
      return fmt::format("negative {} {}", hex_bytes(a.du, " ", 4), polls);
    case Dpv1Answer::Outcome::no_connection:
      return "no connection, nothing sent";
    case Dpv1Answer::Outcome::aborted:
      return fmt::format("aborted {} (instance {}, reason {}) {}", hex_bytes(a.du, " ", 4),
                         a.abort->instance, a.abort->reason_code, polls);
    default:
      return fmt::format("{} {}", outcome_name(a.outcome), polls);
  }
}

std::uint64_t Dpv1Master::cycles_10ms(std::uint32_t units) const {
  return std::uint64_t{units} * chip_.clock_hz() / 100;
}

void Dpv1Master::take(Dpv1Answer& a, const Exchange& ex) {
  a.last = ex.answer;
  if (!ex.answer) {
    a.end = last_end_ = ex.wait_end;  // docs/timing.md, "The master's wait"
    a.outcome = Dpv1Answer::Outcome::no_answer;
    return;
  }
  a.end = last_end_ = ex.answer_end;
  if (!ex.answer->du.empty() || ex.answer->sd == fdl::SC) {
    a.outcome = Dpv1Answer::Outcome::positive;
    return;
  }
  // An answer without data: the slave's refusal (RS, RR, ...), or a data response (DL, DH) that
  // carries none, which is no DPV1 response (docs/dpv1.md, "Outcomes").
  const fdl::Response r = fdl::response_code(ex.answer->fc);
  a.outcome = r == fdl::Response::DL || r == fdl::Response::DH ? Dpv1Answer::Outcome::malformed
                                                               : Dpv1Answer::Outcome::refused;
}

std::string dpv1_refused(const Chip& chip, std::string_view what) {
  if (chip.profile().id == Profile::vpc3plus) return {};
  return fmt::format("{} need a vpc3plus, not a {}: {}", what, profile_name(chip.profile().id),
                     kDpv1OnVpc3plusOnly);
}

Dpv1Master::Dpv1Master(const Chip& chip, DpMaster& m, Dpv1Rules r) : chip_(chip), m_(m), rules_(r) {
  if (std::string why = dpv1_refused(chip, "DPV1 services"); !why.empty())
    throw std::invalid_argument("Dpv1Master: " + why);
}

Dpv1Answer Dpv1Master::no_connection() const {
  Dpv1Answer a;
  a.outcome = Dpv1Answer::Outcome::no_connection;
  // The master acts on an answer at its last stop bit's sample, before the line's end that
  // stamps the previous outcome: a service asked after it is not stamped before it.
  a.start = a.end = std::max(chip_.cycle(), last_end_);
  return a;
}

Dpv1Answer Dpv1Master::transfer(std::uint8_t dsap, std::uint8_t ssap, pdu::Bytes req,
                                std::uint64_t timeout, std::optional<std::uint64_t> since) {
  Dpv1Answer a;
  std::uint32_t sent = 0;               // polls sent
  std::optional<std::size_t> kept_end;  // history() after the last poll kept
  Exchange ex = m_.acyclic(dsap, ssap, std::move(req));
  a.start = since.value_or(ex.request_start);  // the first try's: the time-out counts from it
  ex = m_.retry(std::move(ex), rules_.retries);
  for (;;) {
    take(a, ex);
    if (a.outcome != Dpv1Answer::Outcome::positive) return a;
    if (!ex.answer->du.empty()) {  // the response (classified by the caller)
      a.du = ex.answer->du;
      return a;
    }
    // SC: the slave is still working. Past the time-out the master gives up instead of polling
    // again (the standard's response time-out).
    if (ex.request.du.empty()) ++a.polls;  // the request's own SC is not a poll's
    if (a.end - a.start >= timeout) {
      a.outcome = Dpv1Answer::Outcome::timeout;
      return a;
    }
    const std::size_t before = m_.history().size();
    ex = m_.retry(m_.acyclic(dsap, ssap, {}), rules_.retries);
    if (polled) {
      polled();
    } else if (++sent == kKeptPolls) {
      kept_end = m_.history().size();
    } else if (kept_end) {  // the polls between the kept ones and this one forgotten
      m_.forget_exchanges(*kept_end, before);
    }
  }
}

void Dpv1Master::classify(Dpv1Answer& a, Function f, bool positive_ok) {
  if (a.outcome != Dpv1Answer::Outcome::positive) return;
  if (const auto e = pdu::ErrorResponse::parse(a.du); e && e->function == f) {
    a.error = e;
    a.outcome = Dpv1Answer::Outcome::negative;
  } else if (!positive_ok) {
    a.outcome = Dpv1Answer::Outcome::malformed;
  }
}

void Dpv1Master::take_abort(Dpv1Answer& a, std::uint8_t sap) {
  if (a.outcome != Dpv1Answer::Outcome::positive) return;
  a.abort = pdu::Abort::parse(a.du);
  if (!a.abort) return;
  a.outcome = Dpv1Answer::Outcome::aborted;
  if (c2_sap_ == sap) c2_sap_.reset();  // the slave closed the connection
}

Dpv1Answer Dpv1Master::read(std::uint8_t slot, std::uint8_t index, std::uint8_t length) {
  Dpv1Answer a =
      transfer(sap::MSAC_C1, sap::MSAC_C1, pdu::read_request(slot, index, length).build(),
               cycles_10ms(rules_.c1_response_timeout));
  const auto r = pdu::Record::parse(a.du, Function::Read, true);
  classify(a, Function::Read, r && r->slot == slot && r->index == index && r->length <= length);
  return a;
}

Dpv1Answer Dpv1Master::write(std::uint8_t slot, std::uint8_t index, pdu::Bytes data) {
  const auto n = static_cast<std::uint8_t>(data.size());
  Dpv1Answer a =
      transfer(sap::MSAC_C1, sap::MSAC_C1, pdu::write_request(slot, index, std::move(data)).build(),
               cycles_10ms(rules_.c1_response_timeout));
  const auto r = pdu::Record::parse(a.du, Function::Write, false);
  classify(a, Function::Write, r && r->slot == slot && r->index == index && r->length == n);
  return a;
}

Dpv1Answer Dpv1Master::alarm_ack(const pdu::AlarmAck& ack, std::uint8_t dsap) {
  Dpv1Answer a = transfer(dsap, sap::MSAC_C1, ack.build(), cycles_10ms(rules_.c1_response_timeout));
  classify(a, Function::Alarm_Ack, pdu::AlarmAck::parse(a.du) == ack);
  return a;
}

Dpv1Answer Dpv1Master::initiate(const pdu::Initiate& req) {
  const std::uint64_t timeout = cycles_10ms(req.send_timeout);
  Dpv1Answer rm = transfer(sap::MSAC_C2_RM, rules_.c2_ssap, req.build(), timeout);
  const auto immediate = pdu::ResourceManager::parse(rm.du);
  classify(rm, Function::Initiate, immediate.has_value());
  if (rm.outcome != Dpv1Answer::Outcome::positive) return rm;
  // The resource manager's immediate response names the connection's SAP and the slave's
  // Send_Timeout: the Initiate response is polled for there, within the connection's (the
  // larger one) from the Initiate's first start bit.
  const std::uint16_t send_timeout = std::max(req.send_timeout, immediate->send_timeout);
  Dpv1Answer a = transfer(immediate->sap, rules_.c2_ssap, {}, cycles_10ms(send_timeout), rm.start);
  a.polls += rm.polls;
  take_abort(a, immediate->sap);  // the slave refused the Initiate (the Profichip driver's Abort)
  classify(a, Function::Initiate, pdu::Initiate::parse(a.du, true).has_value());
  if (a.outcome == Dpv1Answer::Outcome::positive) {  // else an open connection stays open
    c2_sap_ = immediate->sap;
    c2_timeout_ = send_timeout;
  }
  return a;
}

Dpv1Answer Dpv1Master::on_connection(Function f, pdu::Bytes req, bool with_data) {
  if (!c2_sap_) return no_connection();
  const pdu::Bytes sent = req;
  Dpv1Answer a = transfer(*c2_sap_, rules_.c2_ssap, std::move(req), cycles_10ms(c2_timeout_));
  bool ok = false;
  if (f == Function::Idle) {
    ok = pdu::Idle::parse(a.du).has_value();
  } else if (const auto r = pdu::Record::parse(a.du, f, with_data)) {
    ok = r->slot == sent[1] && r->index == sent[2];
  }
  take_abort(a, *c2_sap_);
  classify(a, f, ok);
  return a;
}

Dpv1Answer Dpv1Master::c2_read(std::uint8_t slot, std::uint8_t index, std::uint8_t length) {
  return on_connection(Function::Read, pdu::read_request(slot, index, length).build(), true);
}
Dpv1Answer Dpv1Master::c2_write(std::uint8_t slot, std::uint8_t index, pdu::Bytes data) {
  return on_connection(Function::Write, pdu::write_request(slot, index, std::move(data)).build(),
                       false);
}
Dpv1Answer Dpv1Master::c2_transport(std::uint8_t slot, std::uint8_t index, pdu::Bytes data) {
  const auto n = static_cast<std::uint8_t>(data.size());
  return on_connection(
      Function::Data_Transport,
      pdu::Record{Function::Data_Transport, slot, index, n, std::move(data)}.build(), true);
}
Dpv1Answer Dpv1Master::c2_idle() {
  return on_connection(Function::Idle, pdu::Idle{}.build(), false);
}

Dpv1Answer Dpv1Master::c2_abort(const pdu::Abort& abort) {
  if (!c2_sap_) return no_connection();
  Dpv1Answer a;
  Exchange ex = m_.acyclic(*c2_sap_, rules_.c2_ssap, abort.build());
  a.start = ex.request_start;  // the first try's
  ex = m_.retry(std::move(ex), rules_.retries);
  take(a, ex);
  // The Abort has no response: only SC is its acknowledgement.
  if (a.outcome == Dpv1Answer::Outcome::positive && ex.answer->sd != fdl::SC)
    a.outcome = Dpv1Answer::Outcome::refused;
  if (a.outcome == Dpv1Answer::Outcome::positive) c2_sap_.reset();
  return a;
}

}  // namespace dpc31
