// The built-in user side's DPV1 part (responder_dpv1.hpp).
#include "responder_dpv1.hpp"

#include <algorithm>
#include <iterator>

#include "dpc31/chip.hpp"
#include "dpc31/dp.hpp"
#include "dpc31/dpv1.hpp"

namespace dpc31 {

namespace {
namespace en = dpv1::entry;
namespace hd = dpv1::header;
using pdu::Function;
constexpr std::uint8_t kFcResponse = 0x08;  // DL, as the Profichip driver writes it
constexpr std::uint8_t kMaxLen[] = {Dpv1User::kRecordMax, Dpv1User::kAlarmMax, Dpv1User::kRmMax,
                                    Dpv1User::kRecordMax};
constexpr unsigned kSlots = std::size(kMaxLen);
// The layout in segments of `seg` bytes: the SAP list (its entries and the end mark), then the
// slots' buffers in order; slot `s`'s buffer starts `slot_offset(s)` segments in, and
// slot_offset(kSlots) is the whole (the one place of this arithmetic: segments() and init()).
constexpr std::uint32_t slot_offset(unsigned s, std::uint32_t seg) {
  std::uint32_t n = (kSlots * en::kBytes + 1 + seg - 1) / seg;
  for (unsigned k = 0; k < s; ++k) n += (hd::kBytes + kMaxLen[k] + seg - 1) / seg;
  return n;
}
}  // namespace

std::uint32_t Dpv1User::segments(std::uint32_t seg_shift) {
  static_assert(kSlots == kSaps);
  return slot_offset(kSlots, 1u << seg_shift);
}

void Dpv1User::init(BusPort& c, std::uint32_t list, std::uint32_t seg_shift) {
  seg_shift_ = seg_shift;
  const std::uint8_t saps[kSaps] = {sap::MSAC_C1, sap::MSAC_C1_Alarm, sap::MSAC_C2_RM, cfg_.c2_sap};
  for (unsigned s = 0; s < kSaps; ++s) {
    Slot& sl = slots_[s];
    sl.sap = saps[s];
    sl.entry = (list << seg_shift) + s * en::kBytes;
    sl.segment = static_cast<std::uint8_t>(list + slot_offset(s, 1u << seg_shift));
    sl.buffer = std::uint32_t{sl.segment} << seg_shift;
    // The connection's SAP stays off (Ind_Buf_Ptr0 00h) until an Initiate opens it, MSAC_C1's
    // until Data_Exchange.
    const std::uint8_t ind = s == rm ? sl.segment : 0;
    // MSAC_C1 is the class-1 master's only: a stray request from another station would take
    // the one buffer, and the C1 buffer has no time-out that frees it.
    const std::uint8_t sa = s == c1 || s == alarm ? cfg_.c1_master : en::kAll;
    // MSAC_C1 and MSAC_C2 are SRD services: an SDN would take the one buffer with a request
    // whose response nobody polls for, so the chip refuses it (Service_Supported SRD low / high).
    const std::uint8_t e[en::kBytes] = {sl.sap, sa,   en::kAll,  dpv1::service::SRD_LH,
                                        ind,    0x00, sl.segment};
    c.write_block(sl.entry, e);
    c.write(sl.buffer + hd::Control, 0x00);
    c.write(sl.buffer + hd::Max_Length, kMaxLen[s]);
  }
  c.write(slots_[kSaps - 1].entry + en::kBytes, en::kEndOfList);
  c.write(static_cast<std::uint32_t>(
              find_reg(c.chip().profile(), RegId::R_FDL_SAP_List_Ptr)->read_addr),
          static_cast<std::uint8_t>(list));
}

void Dpv1User::data_exchange(BusPort& c, bool in) {
  for (const Sap s : {c1, alarm}) {
    const Slot& sl = slots_[s];
    c.write(sl.entry + en::Ind_Buf_Ptr0, in ? sl.segment : 0x00);
    if (!in) c.write(sl.buffer + hd::Control, 0x00);
  }
}

void Dpv1User::close(BusPort& c) {
  const Slot& k = slots_[connection];
  c.write(k.entry + en::Ind_Buf_Ptr0, 0x00);
  c.write(k.buffer + hd::Control, 0x00);
  open_ = closing_ = false;
}

std::optional<pdu::Bytes> Dpv1User::record(Function f, const pdu::Bytes& req) {
  const std::optional<pdu::Record> r = pdu::Record::parse(req, f, f != Function::Read);
  if (!r)
    return pdu::ErrorResponse{f, pdu::Error_Decode_DPV1, pdu::error::Invalid_Parameter, 0}.build();
  if (f == Function::Data_Transport) return r->build();  // the data echoed, whatever the record
  const auto it = std::find_if(cfg_.records.begin(), cfg_.records.end(), [&](const Dpv1Record& d) {
    return d.slot == r->slot && d.index == r->index;
  });
  const auto in_slot = [&](const Dpv1Record& d) { return d.slot == r->slot; };
  if (it == cfg_.records.end()) {
    const std::uint8_t code = std::any_of(cfg_.records.begin(), cfg_.records.end(), in_slot)
                                  ? pdu::error::Invalid_Index
                                  : pdu::error::Invalid_Slot;
    return pdu::ErrorResponse{f, pdu::Error_Decode_DPV1, code, 0}.build();
  }
  switch (f) {
    case Function::Read: {
      const auto n = static_cast<std::uint8_t>(std::min<std::size_t>(r->length, it->data.size()));
      return pdu::Record{f, r->slot, r->index, n,
                         pdu::Bytes(it->data.begin(), it->data.begin() + n)}
          .build();
    }
    case Function::Write:
      if (r->data.size() != it->data.size()) {
        return pdu::ErrorResponse{f, pdu::Error_Decode_DPV1, pdu::error::Write_Length_Error, 0}
            .build();
      }
      it->data = r->data;
      return pdu::Record{f, r->slot, r->index, r->length, {}}.build();
    default:
      return std::nullopt;
  }
}

std::optional<pdu::Bytes> Dpv1User::answer(BusPort& c, Sap s, const pdu::Bytes& req) {
  const std::optional<Function> f = pdu::function_of(req);
  if (!f) return std::nullopt;
  switch (s) {
    case c1:  // Alarm_Ack comes on SAP 50 or 51 (manual-quotes.md, "DPV1")
      if (*f == Function::Alarm_Ack) return answer(c, alarm, req);
      if (*f != Function::Read && *f != Function::Write) return std::nullopt;
      return record(*f, req);
    case alarm: {
      const std::optional<pdu::AlarmAck> a = pdu::AlarmAck::parse(req);
      if (!a) return std::nullopt;
      alarm_acks.push_back(*a);
      return a->build();
    }
    case rm: {
      if (*f != Function::Initiate) return std::nullopt;
      // A request too short to hold its Send_Timeout runs on the driver's own (its Abort IA
      // waits for the poll that long).
      const auto send_timeout = req.size() < 6 ? pdu::kMsacC2TimeoutMin
                                               : static_cast<std::uint16_t>(req[4] << 8 | req[5]);
      rm_timeout_ = send_timeout;
      if (open_) {
        return pdu::ErrorResponse{Function::Initiate, pdu::Error_Decode_DPV1,
                                  pdu::error::Resource_Busy, 0}
            .build();
      }
      // The Initiate response waits in the connection's buffer for the master's first poll
      // there; the resource manager answers with the connection's SAP. As the Profichip
      // driver: a request its checks refuse gets an Abort there instead (pdu::initiate_abort);
      // as its example user, one to an API other than 0 (the first byte of D_Addr) Abort IA,
      // one whose D_Type is not 0 (the slave is not the connection's end) a negative response
      // (application, not supported); either closes the connection once sent.
      const Slot& k = slots_[connection];
      std::optional<pdu::Abort> abort = pdu::initiate_abort(req);
      std::optional<pdu::Initiate> i;
      if (!abort) {  // through D_Addr (S_Len, D_Len: bytes 13, 15)
        const std::size_t n = pdu::kInitiateReqFixed + req[13] + req[15];
        i = pdu::Initiate::parse(pdu::View(req).first(n), false);
        if (!i->d_addr.empty() && i->d_addr[0] != 0) {
          abort = pdu::Abort{0, pdu::Abort_Instance_MSAC_C2, pdu::Abort_IA, 0};
        }
      }
      closing_ = abort || i->d_type != pdu::Addr_Type_API_SCL;
      pdu::Bytes r;
      if (abort) {
        r = abort->build();
      } else if (closing_) {
        r = pdu::ErrorResponse{Function::Initiate, pdu::Error_Decode_DPV1,
                               pdu::error::Feature_Not_Supported, 0}
                .build();
      } else {
        // Its own features (Read/Write) and no profile; S and D address swapped.
        pdu::Initiate res;
        res.response = true;
        res.max_len_data_unit = kRecordMax - 4;
        res.features_supported = pdu::Features_DPV1_RW;
        res.s_type = i->d_type;
        res.s_addr = i->d_addr;
        res.d_type = i->s_type;
        res.d_addr = i->s_addr;
        r = res.build();
      }
      c.write_block(k.buffer + hd::kBytes, r);
      c.write(k.buffer + hd::Length, static_cast<std::uint8_t>(r.size()));
      c.write(k.buffer + hd::Function_Code, kFcResponse);
      c.write(k.buffer + hd::Control, hd::USER | hd::RESP);
      c.write(k.entry + en::Ind_Buf_Ptr0, k.segment);
      open_ = true;
      send_timeout_ = send_timeout;
      activity_ = c.cycle();
      return pdu::ResourceManager{cfg_.c2_sap, send_timeout}.build();
    }
    case connection:
      activity_ = c.cycle();
      if (*f == Function::Abort) {
        close(c);
        return std::nullopt;
      }
      if (*f == Function::Idle) return pdu::Idle{}.build();
      if (*f == Function::Read || *f == Function::Write || *f == Function::Data_Transport)
        return record(*f, req);
      return std::nullopt;
    case kSaps:
      break;
  }
  return std::nullopt;
}

void Dpv1User::serve(BusPort& c, std::uint16_t ir) {
  if ((ir & irq::FDL_Ind) != 0) {
    for (unsigned s = 0; s < kSaps; ++s) {
      const Slot& sl = slots_[s];
      if ((c.read(sl.buffer + hd::Control) & hd::IND) == 0) continue;
      c.write(sl.buffer + hd::Control, hd::USER);  // taken
      pdu::Bytes req(c.read(sl.buffer + hd::Length));
      c.read_block(sl.buffer + hd::kBytes, req);
      const std::optional<pdu::Bytes> res = answer(c, static_cast<Sap>(s), req);
      if (!res) {
        if (s != connection || open_) c.write(sl.buffer + hd::Control, 0x00);  // freed
        continue;
      }
      if (cfg_.work_cycles != 0) c.idle(cfg_.work_cycles);
      c.write_block(sl.buffer + hd::kBytes, *res);
      c.write(sl.buffer + hd::Length, static_cast<std::uint8_t>(res->size()));
      c.write(sl.buffer + hd::Function_Code, kFcResponse);
      c.write(sl.buffer + hd::Control, hd::USER | hd::RESP);
      if (s == rm) {
        rm_waits_ = true;
        rm_since_ = c.cycle();
      }
    }
  }
  if ((ir & irq::Poll_End_Ind) != 0) {
    for (unsigned s = 0; s < kSaps; ++s) {
      const std::uint8_t b0 = c.read(slots_[s].entry + en::Sap);
      if ((b0 & en::Response_Sent) == 0) continue;
      c.write(slots_[s].entry + en::Sap, static_cast<std::uint8_t>(b0 & ~en::Response_Sent));
      if (s == connection) activity_ = c.cycle();
      if (s == connection && closing_) close(c);  // the refusal went out
      if (s == rm) rm_waits_ = false;
    }
  }
  if ((ir & irq::User_Timer_Clock) == 0) return;
  const auto elapsed = [&](std::uint64_t since, std::uint16_t timeout) {
    return c.cycle() - since >= std::uint64_t{timeout} * c.chip().clock_hz() / 100;
  };
  // The slave's side of the connection time-out: no request stored and no response sent for
  // Send_Timeout closes it (the master's next request there gets RS).
  if (open_ && elapsed(activity_, send_timeout_)) {
    close(c);
    ++timeouts;
  }
  // The resource manager has one buffer, and the chip answers every Initiate RR while its
  // response waits there: a response its master never polls for is withdrawn after that
  // Initiate's Send_Timeout, the time the master itself waits for it.
  if (rm_waits_ && elapsed(rm_since_, rm_timeout_)) {
    c.write(slots_[rm].buffer + hd::Control, 0x00);
    rm_waits_ = false;
    ++rm_withdrawn;
  }
}

}  // namespace dpc31
