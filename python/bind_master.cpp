// dpc31.Master with its DPV1 services in Python (docs/python.md): the built-in DP master of
// session/dp_master.hpp and session/dpv1_master.hpp on one chip's wire, one call for one call.
#include <fmt/format.h>
#include <pybind11/operators.h>

#include <memory>
#include <thread>
#include <tuple>
#include <unordered_map>
#include <utility>
#include <vector>

#include "bind_session.hpp"
#include "dp_master.hpp"
#include "dpv1_master.hpp"
#include "firmware_host.hpp"
#include "responder.hpp"
#include "vocabulary.hpp"

namespace dpc31::py_bind {

namespace {

// DPV1 is modelled on the VPC3+ only (a scenario refuses `record`, `dpv1` and the DPV1 actions
// on another profile at its parse): a ValueError naming the chip's, before anything is sent.
void no_dpv1_but_on_vpc3plus(const Chip& chip, std::string_view what) {
  if (std::string why = dpv1_refused(chip, what); !why.empty()) throw py::value_error(why);
}

using RecordArg = std::tuple<py::int_, py::int_, py::object>;

// run_responder's records=: (slot, index, data) each, as a scenario's `record` lines take them;
// a ValueError in their words, after the record's place in the list.
std::vector<Dpv1Record> dpv1_records(const std::vector<RecordArg>& given) {
  std::vector<Dpv1Record> out;
  for (const auto& [slot, index, data] : given) {
    const std::string at = fmt::format("records[{}]: ", out.size());
    try {
      Dpv1Record r{in_range<U8>(kRecordSlot, slot), in_range<U8>(kRecordIndex, index),
                   bytes_like(data, "data")};
      if (r.data.size() > kRecordLength.max)
        throw py::value_error(fmt::format("data: more than {} bytes", kRecordLength.max));
      for (const Dpv1Record& o : out) {
        if (o.slot == r.slot && o.index == r.index)
          throw py::value_error(fmt::format("slot={} index={} given twice", r.slot, r.index));
      }
      out.push_back(std::move(r));
    } catch (const py::value_error& e) {
      throw py::value_error(at + e.what());
    }
  }
  return out;
}

// The built-in DP master on one chip's wire. It keeps the chip (and the user side) alive.
struct PyMaster {
  PyMaster(py::object chip_obj, const MasterConfig& mc, const SlaveConfig& sc)
      : chip_ref(std::move(chip_obj)),
        chip(chip_ref.cast<PyChip&>()),
        config(mc),
        m(std::make_unique<DpMaster>(chip.chip, mc, sc)) {
    ends_at_observer_error();
  }
  py::object chip_ref;
  PyChip& chip;
  MasterConfig config;
  std::unique_ptr<DpMaster> m;
  std::shared_ptr<FirmwareHost> firmware;
  std::shared_ptr<Responder> responder;
  py::object board;  // run_board's Cpu51Board
  Dpv1Rules dpv1_rules;
  std::unique_ptr<Dpv1Master> dpv1_m;  // on `m`: made at the first DPV1 service

  // A DPV1 service of the master (session/dpv1_master.hpp), with the rules as Python set them.
  template <typename F>
  Dpv1Answer dpv1(F&& f) {
    no_dpv1_but_on_vpc3plus(chip.chip, "DPV1 services");
    if (!dpv1_m) dpv1_m = std::make_unique<Dpv1Master>(chip.chip, *m, dpv1_rules);
    dpv1_m->rules() = dpv1_rules;
    return act([&] { return f(*dpv1_m); });
  }

  template <typename F>
  auto act(F&& f) {
    return chip.run(std::forward<F>(f));
  }
  // An observer's exception ends the master's call after the wait it stopped (docs/python.md,
  // "The GIL"): the master clears the chip's stop after each wait and would go on.
  void ends_at_observer_error() {
    m->waited = [this] {
      if (chip.error) throw ObserverStopped{};
    };
  }
  // The user side sets the chip up before the master's first request, and the master counts
  // its bus idle from then on, as in a scenario (session/scenario_run.cpp): it is made anew.
  template <typename Init>
  void start_user_side(const SlaveConfig& slave, Init&& init) {
    if (firmware || responder || board || m->counters().requests != 0) {
      raise(errors().error,
            "the user side starts once, before the master's first request (docs/python.md)");
    }
    act([&] {
      DirectBus bus(chip.chip);
      init(bus);
    });
    dpv1_m.reset();  // it holds the master
    m = std::make_unique<DpMaster>(chip.chip, config, slave);
    ends_at_observer_error();
  }
};

// A Read (MSAC_C1 or on the connection) and a service with record data (Write, Data_Transport):
// one binding per Dpv1Master member.
// Slot, index, length and data in the scenario's ranges (vocabulary.hpp).
template <Dpv1Answer (Dpv1Master::*Read)(U8, U8, U8)>
Dpv1Answer read_record(PyMaster& pm, std::int64_t slot, std::int64_t index, std::int64_t length) {
  const auto s = in_range<U8>(kRecordSlot, slot);
  const auto i = in_range<U8>(kRecordIndex, index);
  const auto n = in_range<U8>(kRecordLength, length);
  return pm.dpv1([&](Dpv1Master& d) { return (d.*Read)(s, i, n); });
}
template <Dpv1Answer (Dpv1Master::*Send)(U8, U8, pdu::Bytes)>
Dpv1Answer send_record(PyMaster& pm, std::int64_t slot, std::int64_t index,
                       const py::object& data) {
  const auto s = in_range<U8>(kRecordSlot, slot);
  const auto i = in_range<U8>(kRecordIndex, index);
  pdu::Bytes v = bytes_like(data, "data");
  if (v.size() > kRecordLength.max)
    throw py::value_error(fmt::format("data: more than {} bytes", kRecordLength.max));
  return pm.dpv1([&](Dpv1Master& d) { return (d.*Send)(s, i, std::move(v)); });
}

// An Initiate's S_Addr or D_Addr: at most kAddrMax bytes (both together too: addresses_too_long),
// as a scenario's s_addr= / d_addr=.
pdu::Bytes address(const py::object& b, std::string_view what) {
  pdu::Bytes v = bytes_like(b, what);
  if (v.size() > kAddrMax)
    throw py::value_error(fmt::format("{}: more than {} bytes", what, kAddrMax));
  return v;
}

// The master's DPV1 services (docs/dpv1.md, "The master's side"), one call for one call of
// Dpv1Master; each runs the chip until the response, the time-out or no answer.
void bind_dpv1(py::module_& m, py::class_<PyMaster>& master) {
  using O = Dpv1Answer::Outcome;
  py::enum_<O>(m, "Dpv1Outcome")
      .value("positive", O::positive)
      .value("negative", O::negative)
      .value("refused", O::refused)
      .value("no_answer", O::no_answer)
      .value("timeout", O::timeout)
      .value("malformed", O::malformed)
      .value("no_connection", O::no_connection)
      .value("aborted", O::aborted);
  py::class_<Dpv1Rules>(m, "Dpv1Rules", "The master's DPV1 rules (retries, time-out, C2 SAP).")
      .def(py::init(&with_kwargs<Dpv1Rules>))
      .def_property(
          "retries", [](const Dpv1Rules& r) { return r.retries; },
          [](Dpv1Rules& r, const py::int_& v) { r.retries = in_range<std::uint32_t>(kRetries, v); })
      .def_property(
          "c1_response_timeout", [](const Dpv1Rules& r) { return r.c1_response_timeout; },
          [](Dpv1Rules& r, const py::int_& v) {
            // The scenario's `dpv1 c1_timeout=` range, under the property's name.
            r.c1_response_timeout =
                in_range<std::uint16_t>(named(kC1Timeout, "c1_response_timeout"), v);
          })
      .def_property(
          "c2_ssap", [](const Dpv1Rules& r) { return r.c2_ssap; },
          [](Dpv1Rules& r, const py::int_& v) { r.c2_ssap = in_range<U8>(kC2Ssap, v); });
  py::class_<Dpv1Answer>(m, "Dpv1Answer", "What a DPV1 service got (session/dpv1_master.hpp).")
      .def_readonly("outcome", &Dpv1Answer::outcome)
      .def_property_readonly("du", [](const Dpv1Answer& a) { return to_bytes(a.du); })
      .def_property_readonly("error",
                             [](const Dpv1Answer& a) -> std::optional<py::tuple> {
                               if (!a.error) return std::nullopt;
                               return py::make_tuple(a.error->error_decode, a.error->error_code_1,
                                                     a.error->error_code_2);
                             })
      .def_property_readonly("abort",
                             [](const Dpv1Answer& a) -> std::optional<py::tuple> {
                               // aborted: the slave's (Subnet, Instance, Reason_Code, detail)
                               if (!a.abort) return std::nullopt;
                               return py::make_tuple(a.abort->subnet, a.abort->instance,
                                                     a.abort->reason_code,
                                                     a.abort->additional_detail);
                             })
      .def_readonly("last", &Dpv1Answer::last)
      .def_readonly("polls", &Dpv1Answer::polls)
      .def_readonly("start", &Dpv1Answer::start)
      .def_readonly("end", &Dpv1Answer::end)
      .def("__repr__",
           [](const Dpv1Answer& a) { return "<Dpv1Answer " + answer_summary(a) + ">"; });
  master
      .def_property(
          // The master's own rules (def_property: reference_internal, the master kept alive):
          // `master.dpv1_rules.c1_response_timeout = 1` reaches the next service.
          "dpv1_rules", [](PyMaster& pm) -> Dpv1Rules& { return pm.dpv1_rules; },
          [](PyMaster& pm, const Dpv1Rules& r) { pm.dpv1_rules = r; })
      .def_property_readonly("c2_sap",
                             [](const PyMaster& pm) {
                               pm.chip.enter(false);  // the running service opens or forgets it
                               return pm.dpv1_m ? pm.dpv1_m->c2_sap() : std::nullopt;
                             })
      .def_property_readonly("c2_send_timeout",
                             [](const PyMaster& pm) -> std::optional<std::uint16_t> {
                               // the open connection's: max(the Initiate's, the resource manager's)
                               // x 10 ms
                               pm.chip.enter(false);
                               if (!pm.dpv1_m || !pm.dpv1_m->c2_sap()) return std::nullopt;
                               return pm.dpv1_m->c2_send_timeout();
                             })
      .def("dpv1_read", &read_record<&Dpv1Master::read>, py::arg("slot"), py::arg("index"),
           py::arg("length"), "MSAC_C1 Read (SAP 51 -> 51), polled until the response")
      .def("dpv1_write", &send_record<&Dpv1Master::write>, py::arg("slot"), py::arg("index"),
           py::arg("data"), "MSAC_C1 Write")
      .def(
          "alarm_ack",
          [](PyMaster& pm, std::int64_t slot, std::int64_t alarm_type, U8 specifier,
             std::int64_t sap) {
            const pdu::AlarmAck ack{in_range<U8>(kRecordSlot, slot),
                                    in_range<U8>(kAlarmType, alarm_type), specifier};
            const auto dsap = in_range<U8>(kAlarmSap, sap);
            return pm.dpv1([&](Dpv1Master& d) { return d.alarm_ack(ack, dsap); });
          },
          py::arg("slot"), py::arg("alarm_type"), py::arg("specifier"),
          py::arg("sap") = sap::MSAC_C1_Alarm,
          "MSAC_C1 Alarm_Ack (SAP 51 -> 50, or -> 51 with sap=51: the slave's SAP 50 or 51); "
          "specifier = Seq_Nr << 3 | Add_Ack << 2 | bits 1..0")
      .def(
          "c2_initiate",
          [](PyMaster& pm, std::int64_t send_timeout, std::uint16_t features_supported,
             std::int64_t s_type, const py::object& s_addr, std::int64_t d_type,
             const py::object& d_addr) {
            pdu::Initiate req =
                pdu::initiate_request(in_range<std::uint16_t>(kSendTimeout, send_timeout));
            req.features_supported = features_supported;
            req.s_type = in_range<U8>(named(kAddrType, "s_type"), s_type);
            req.d_type = in_range<U8>(named(kAddrType, "d_type"), d_type);
            req.s_addr = address(s_addr, "s_addr");
            req.d_addr = address(d_addr, "d_addr");
            if (const std::string why = addresses_too_long(req.s_addr.size(), req.d_addr.size());
                !why.empty()) {
              throw py::value_error(why);
            }
            return pm.dpv1([&](Dpv1Master& d) { return d.initiate(req); });
          },
          py::arg("send_timeout") = 100, py::arg("features_supported") = pdu::Features_DPV1_RW,
          py::arg("s_type") = pdu::Addr_Type_API_SCL, py::arg("s_addr") = py::bytes("\0\0", 2),
          py::arg("d_type") = pdu::Addr_Type_API_SCL, py::arg("d_addr") = py::bytes("\0\0", 2),
          "MSAC_C2 Initiate to SAP 49, then the connection's SAP polled for its response; "
          "features_supported: Features_Supported_1 in the high byte (0x0100: Read and Write); "
          "s_addr / d_addr: Type 0 is API, SCL (2 bytes)")
      .def("c2_read", &read_record<&Dpv1Master::c2_read>, py::arg("slot"), py::arg("index"),
           py::arg("length"))
      .def("c2_write", &send_record<&Dpv1Master::c2_write>, py::arg("slot"), py::arg("index"),
           py::arg("data"))
      .def("c2_transport", &send_record<&Dpv1Master::c2_transport>, py::arg("slot"),
           py::arg("index"), py::arg("data"))
      .def("c2_idle",
           [](PyMaster& pm) { return pm.dpv1([](Dpv1Master& d) { return d.c2_idle(); }); })
      .def(
          "c2_abort",
          [](PyMaster& pm, std::int64_t reason, std::int64_t instance) {
            const pdu::Abort a{0, in_range<U8>(kAbortInstance, instance),
                               in_range<U8>(kAbortReason, reason), 0};
            return pm.dpv1([&](Dpv1Master& d) { return d.c2_abort(a); });
          },
          py::arg("reason") = 0, py::arg("instance") = 2,
          "MSAC_C2 Abort on the open connection (Instance 2: the user)");
}

}  // namespace

void bind_master(py::module_& m) {
  py::class_<PyMaster> master(m, "Master",
                              "The built-in DP master (class 1) on a chip's RxD/TxD (DpMaster).");
  master
      .def(py::init([](py::object chip, std::int64_t address, std::uint32_t baud,
                       std::int64_t slot_bits, std::int64_t idle_bits,
                       const std::optional<SlaveConfig>& slave) {
             // The checks of a scenario's `baud` and `master address= slot= idle=`; a bit at
             // least one clock of the chip (as a Segment's).
             PyChip& c = class_arg<PyChip>(chip, "chip", "a dpc31.Chip");
             const std::uint32_t rate = profibus_rate(baud);
             one_clock_a_bit(c.chip.clock_hz(), rate);
             const MasterConfig mc{in_range<U8>(kMasterAddress, address), rate,
                                   in_range<std::uint32_t>(kSlotBits, slot_bits),
                                   in_range<std::uint32_t>(kIdleBits, idle_bits)};
             const SlaveConfig sc = slave.value_or(SlaveConfig{});
             if (sc.address == mc.address) throw py::value_error(master_and_slave_at(sc.address));
             if (sc.wd_base_1ms && c.chip.profile().id == Profile::vpc3plus &&
                 (sc.user_prm.empty() || (sc.user_prm[0] & dpv1::status1::DPV1_Enable) == 0)) {
               throw py::value_error(wd_base_needs_dpv1("wd_base_1ms=True"));
             }
             c.enter(true);
             return std::make_unique<PyMaster>(std::move(chip), mc, sc);
           }),
           py::arg("chip").none(true), py::arg("address") = 2, py::arg("baud") = 1'500'000,
           py::arg("slot_bits") = 100, py::arg("idle_bits") = 33, py::arg("slave") = py::none())
      .def(
          "run_firmware",
          [](PyMaster& pm, const py::object& spec, bool gsd_defaults) {
            const dpc31_firmware& d = find_firmware(
                fspath_arg(spec, "firmware"),
                "load it on a dpc31.Cpu51Board (board.load_hex(path), docs/python.md)");
            const SlaveConfig slave =
                gsd_defaults ? with_gsd_defaults(d, pm.m->slave()) : pm.m->slave();
            auto fw = std::make_shared<FirmwareHost>(d);
            pm.start_user_side(slave, [&](BusPort& bus) { fw->init(bus, slave.address); });
            pm.m->set_firmware(fw->program());
            user_side_runs_with(fw.get(), pm.chip.run_state());
            pm.firmware = fw;
            return fw;
          },
          py::arg("firmware"), py::arg("gsd_defaults") = true,
          "Runs a firmware (DO4, CNT2 or a plug-in path) on the host CPU: its init now, its ISR "
          "and main loop while the master runs the chip. gsd_defaults: the master's slave takes "
          "the "
          "firmware's Ident, Cfg, lengths and User_Prm (as a scenario's `firmware` line).")
      .def(
          "run_responder",
          [](PyMaster& pm, const py::object& inputs_arg, bool sync_supported, bool freeze_supported,
             bool spec_clear_mode, const py::object& substitute_arg, bool user_watchdog,
             bool dx_out_port, const std::vector<RecordArg>& records,
             const std::optional<py::int_>& work_cycles,
             const std::optional<py::int_>& wd_baud_control,
             const std::optional<py::int_>& user_wd_value) {
            const std::vector<U8> inputs = bytes_like(inputs_arg, "inputs");
            const std::vector<U8> substitute = bytes_like(substitute_arg, "substitute");
            ResponderConfig rc;
            if (pm.chip.chip.profile().id != Profile::dpc31) {  // as a scenario's `user` line
              if (dx_out_port) throw py::value_error(dx_out_port_is_for_dpc31("dx_out_port="));
              if (!substitute.empty())
                throw py::value_error(substitute_is_for_dpc31("substitute="));
            }
            // The `user` step's checks (scenario_parse.cpp): its ranges and words.
            if (wd_baud_control)
              rc.wd_baud_control = in_range<U8>(kWdBaudControl, *wd_baud_control);
            if (user_wd_value) {
              rc.user_wd_value = in_range<std::uint16_t>(kUserWdValue, *user_wd_value);
              if (pm.chip.chip.profile().id == Profile::dpc31 && !user_watchdog)
                throw py::value_error(user_wd_value_needs_user_wd("user_wd_value"));
            }
            // A scenario's `record` and `dpv1 work=` lines: the VPC3+'s only, and the time
            // spent on a record only where there is one (no silent options).
            if (!records.empty()) no_dpv1_but_on_vpc3plus(pm.chip.chip, "records");
            rc.dpv1.records = dpv1_records(records);
            if (work_cycles) {
              rc.dpv1.work_cycles =
                  in_range<std::uint64_t>(named(kWorkCycles, "work_cycles"), *work_cycles);
              if (records.empty())
                throw py::value_error("work_cycles: no records to work on (records=)");
            }
            rc.dpv1.c1_master = pm.config.address;  // as a scenario's (scenario_run.cpp)
            rc.slave = pm.m->slave();
            if (const std::string why = records_need_dpv1("records=", rc.slave.user_prm);
                !records.empty() && !why.empty())
              throw py::value_error(why);
            rc.sync_supported = sync_supported;
            rc.freeze_supported = freeze_supported;
            rc.spec_clear_mode = spec_clear_mode;
            rc.substitute = substitute;
            rc.user_watchdog = user_watchdog;
            rc.dx_out_port = dx_out_port;
            // The buffers for the Master's SlaveConfig must fit the chip's RAM.
            if (const std::string why = responder_layout_problem(pm.chip.chip.profile(), rc);
                !why.empty())
              throw py::value_error("SlaveConfig " + why);
            auto r = std::make_shared<Responder>(rc);
            r->set_inputs(inputs);
            pm.start_user_side(rc.slave, [&](BusPort& bus) { r->init(bus); });
            pm.m->set_firmware([r](BusPort& b) { r->isr(b); });
            user_side_runs_with(r.get(), pm.chip.run_state());
            pm.responder = r;
            return r;
          },
          py::arg("inputs") = py::bytes(), py::arg("sync_supported") = true,
          py::arg("freeze_supported") = true, py::arg("spec_clear_mode") = true,
          py::arg("substitute") = py::bytes(), py::arg("user_watchdog") = false,
          py::arg("dx_out_port") = false, py::arg("records") = std::vector<RecordArg>{},
          py::arg("work_cycles") = py::none(), py::arg("wd_baud_control") = py::none(),
          py::arg("user_wd_value") = py::none(),
          "Runs the built-in responder (session/responder.hpp) as the user side; on a vpc3plus "
          "it serves `records` [(slot, index, data)] over DPV1, `work_cycles` clocks per request "
          "(a scenario's `record` and `dpv1 work=` lines). wd_baud_control: WD_Baud_Control_Val "
          "(x 10 ms, 0x10 unless given); user_wd_value: R_User_WD_Value (0x1FF unless given; on "
          "a dpc31 only with user_watchdog), as a scenario's `user` line.")
      .def(
          "run_board",
          [](PyMaster& pm, py::object board) {
            PyBoard& b = class_arg<PyBoard>(board, "board", "a dpc31.Cpu51Board");
            if (&b.chip != &pm.chip) raise(errors().error, "the board is on another chip");
            if (pm.firmware || pm.responder || pm.board) {
              raise(errors().error, "the master's chip has a user side already");
            }
            // The board moves time while the master waits, as in a scenario's `cpu` header
            // (session/scenario_run.cpp): its CPU is the user side, from reset.
            pm.m->scheduler = [&b](U64 cycle) { b.run_until(cycle); };
            pm.board = std::move(board);
          },
          py::arg("board").none(true),
          "The CPU of a Cpu51Board is the user side: its image runs while the master runs the "
          "chip.")
      .def_property_readonly("firmware", [](const PyMaster& pm) { return pm.firmware; })
      .def_property_readonly("responder", [](const PyMaster& pm) { return pm.responder; })
      .def_property_readonly("chip", [](const PyMaster& pm) { return pm.chip_ref; })
      .def_property_readonly(
          "slave",
          [](const PyMaster& pm) {
            return MasterSlave{pm.m->slave(), "Master.slave", "Master(slave=SlaveConfig(...))"};
          })
      .def_property_readonly("bit_cycles", [](const PyMaster& pm) { return pm.m->bit_cycles(); })
      .def_property_readonly("counters",
                             [](const PyMaster& pm) {
                               pm.chip.enter(false);  // as the chip's state properties
                               return pm.m->counters();
                             })
      .def_property_readonly("history",
                             [](const PyMaster& pm) {
                               pm.chip.enter(false);  // as the chip's state properties
                               return pm.m->history();
                             })
      .def_property_readonly(
          "locks",
          [](const PyMaster& pm) {
            pm.chip.enter(false);
            return pm.m->locks();
          },
          "{slave address: master address}: a start-up that returned False because its slave is "
          "locked by another master (Slave_Diag's Master_Add) names it here")
      .def("clear_history",
           [](PyMaster& pm) {
             // The running master appends to it: refused to another thread and to an observer.
             enter_run(*pm.chip.run_state(), true, "chip", "history, counters, ...",
                       "clear the master's history");
             pm.m->clear_history();
           })
      .def(
          "startup",
          [](PyMaster& pm, const py::int_& tries) {
            const int n = in_range<int>(kTries, tries);
            return pm.act([&] { return pm.m->startup(n); });
          },
          py::arg("tries") = kStartupTries)
      .def(
          "restart",
          [](PyMaster& pm, const py::int_& tries, std::uint32_t retries) {
            const int n = in_range<int>(kTries, tries);
            return pm.act([&] { return pm.m->restart(n, retries); });
          },
          py::arg("tries") = kStartupTries, py::arg("retries") = 1)
      .def(
          "data_exchange",
          [](PyMaster& pm, const py::object& out, const std::optional<std::string>& fault,
             std::optional<int> fault_char) {
            const std::vector<U8> v = bytes_like(out, "outputs");
            const UartFault f = fault_of(fault, fault_char);
            return pm.act([&] { return pm.m->data_exchange(v, f); });
          },
          py::arg("outputs"), py::arg("fault") = py::none(), py::arg("fault_char") = py::none())
      .def(
          "global_control",
          [](PyMaster& pm, U8 command, U8 groups) {
            return pm.act([&] { return pm.m->global_control(command, groups); });
          },
          py::arg("command"), py::arg("groups") = 0)
      .def("slave_diag", [](PyMaster& pm) { return pm.act([&] { return pm.m->slave_diag(); }); })
      .def("fdl_status", [](PyMaster& pm) { return pm.act([&] { return pm.m->fdl_status(); }); })
      .def(
          "set_prm",
          [](PyMaster& pm, U8 extra) { return pm.act([&] { return pm.m->set_prm(extra); }); },
          py::arg("station_status_extra") = 0)
      .def("chk_cfg", [](PyMaster& pm) { return pm.act([&] { return pm.m->chk_cfg(); }); })
      .def("get_cfg", [](PyMaster& pm) { return pm.act([&] { return pm.m->get_cfg(); }); })
      .def("read_inputs", [](PyMaster& pm) { return pm.act([&] { return pm.m->read_inputs(); }); })
      .def("read_outputs",
           [](PyMaster& pm) { return pm.act([&] { return pm.m->read_outputs(); }); })
      .def(
          "set_slave_address",
          [](PyMaster& pm, std::int64_t a, bool no_change) {
            const U8 new_address = in_range<U8>(kNewAddress, a);
            return pm.act([&] { return pm.m->set_slave_address(new_address, no_change); });
          },
          py::arg("new_address"), py::arg("no_add_change") = false)
      .def(
          "transact",
          [](PyMaster& pm, const fdl::Frame& req, const std::optional<std::string>& fault,
             std::optional<int> fault_char) {
            static_cast<void>(sendable(req));
            const UartFault f = fault_of(fault, fault_char);
            return pm.act([&] { return pm.m->transact(req, f); });
          },
          py::arg("request"), py::arg("fault") = py::none(), py::arg("fault_char") = py::none())
      .def(
          "transact_raw",
          [](PyMaster& pm, const py::object& raw, const std::optional<std::string>& fault,
             std::optional<int> fault_char) {
            const std::vector<U8> v = raw_telegram(raw);
            const UartFault f = fault_of(fault, fault_char);
            return pm.act([&] { return pm.m->transact_raw(v, f); });
          },
          py::arg("data"), py::arg("fault") = py::none(), py::arg("fault_char") = py::none())
      .def(
          "idle",
          [](PyMaster& pm, U64 cycles) {
            idle_in_slices(
                pm, cycles, [&] { return pm.chip.chip.cycle(); },
                [&] { return pm.chip.error != nullptr; });
          },
          py::arg("cycles"), "Time passes with a silent bus (cable pulled); the firmware runs.")
      .def(
          "line_noise",
          [](PyMaster& pm, const py::object& b, std::uint32_t idle_bits) {
            const std::vector<U8> v = bytes_like(b, "data");
            pm.act([&] { pm.m->line_noise(v, idle_bits); });
          },
          py::arg("data"), py::arg("idle_bits"))
      .def(
          "glitch", [](PyMaster& pm, std::uint32_t low) { pm.act([&] { pm.m->glitch(low); }); },
          py::arg("low_cycles"))
      .def_static("diag_ready", &DpMaster::diag_ready, py::arg("diag_answer"));
  bind_dpv1(m, master);
}

}  // namespace dpc31::py_bind
