// Scenarios: a line-based, diff-friendly script of what a DP master does to one chip (start-up,
// Data_Exchange, Global_Control, faults on the wire, silence) with checks on the outcome, and the
// runner that plays it and prints the state walk with cycle numbers. The format is specified in
// docs/scenario-format.md; `dpc31 run SCENARIO` is the front end.
//
// A file is parsed completely before anything runs, so a typo on the last line costs no
// simulation time and never leaves a half-run walk behind.
#pragma once

#include <cstdint>
#include <functional>
#include <optional>
#include <span>
#include <string>
#include <string_view>
#include <vector>

#include "cpu51_config.hpp"
#include "dp_master.hpp"
#include "dpc31/chip.hpp"
#include "dpc31/fdl_counters.hpp"
#include "dpc31/uart.hpp"
#include "dpv1_master.hpp"
#include "responder.hpp"
#include "vocabulary.hpp"

struct dpc31_firmware;  // dpc31/dpc31_firmware.h

// util/outfile/outfile.hpp: not installed, so this installed header only names the type.
namespace dpc31::outfile {
struct Named;
}

namespace dpc31 {

struct ScenarioError {
  std::string file;
  int line = 0;  // 0: the file as a whole (missing, unreadable, empty)
  std::string message;
  [[nodiscard]] std::string text() const;  // "FILE:LINE: message" (or "FILE: message")
};

enum class StepKind : std::uint8_t {
  // actions (they let time pass)
  startup,
  restart,
  exchange,
  gc,
  diag,
  fdl_status,
  set_prm,
  chk_cfg,
  get_cfg,
  read_inputs,
  read_outputs,
  set_slave_address,
  foreign_master,
  silence,
  inputs,  // new inputs for the user side (no time passes)
  hw,      // a hardware input of the firmware's module (no time passes)
  // modifiers of the next request
  corrupt,
  bad_fcs,
  // checks
  expect,
  // actions added later (after expect, so the Python enum's values stay put)
  write,    // bus writes of the CPU: a register by name, a byte, a block (docs/scenario-format.md)
  read,     // bus reads of the CPU, command reads included
  send,     // a telegram as given: raw bytes, or fields from any station
  request,  // a DPC31 request through the Instruction_Queue (bus writes)
  dpv1,     // a DPV1 service of the master (MSAC_C1, MSAC_C2): `name` says which
  reset,    // the RESET of a `cpu` board: CPU and chip together (no time passes)
};

enum class ExpectKind : std::uint8_t {
  dp_state,
  wd_state,
  outputs,
  cleared,
  inputs,
  counter,
  irr_bit,
  answer,
  station,
  diag_byte,
  baud,
  port,
  pb3,
  reg,         // a register's whole value (peek_reg: no side effect)
  ram,         // bytes at an address (peek)
  read,        // what the last `read` returned
  indication,  // the DPC31's newest Indication_Queue entry
  dpv1,        // the last DPV1 service's response
  irq,         // X/INT activations of the last action: one at a cycle, or their count
};

// The modifiers: a fault that damages the action after it (they count as one action).
[[nodiscard]] constexpr bool is_fault(StepKind k) {
  return k == StepKind::corrupt || k == StepKind::bad_fcs;
}
// Steps that let time pass (and may send requests), as opposed to modifiers, inputs and checks.
[[nodiscard]] constexpr bool is_action(StepKind k) {
  return k != StepKind::expect && !is_fault(k) && k != StepKind::inputs && k != StepKind::hw;
}

// One line of the file. Only the fields its kind uses are meaningful.
struct ScenarioStep {
  int line = 0;
  std::string text;  // the line without its comment, for the walk
  StepKind kind = StepKind::expect;
  std::uint64_t count = 1;           // exchange: requests; startup/restart: tries
  std::uint64_t cycles = 0;          // silence
  std::vector<std::uint8_t> bytes;   // outputs, inputs, expected bytes
  bool has_bytes = false;            // exchange: outputs= given
  std::uint32_t value = 0;           // gc command, address, expected number / bit / state
  std::uint32_t value2 = 0;          // gc groups, no_change, diag byte index, counter delta flag
  UartFault fault;                   // corrupt: char_index -1 = the last character
  std::optional<SlaveConfig> slave;  // set_prm / chk_cfg: the master's view from now on
  ExpectKind expect = ExpectKind::dp_state;
  std::string name;  // expect: counter / interrupt / answer kind / port / register; hw: the input
  std::optional<RegId> reg;  // write / read / expect reg: the register (else `addr`)
  std::uint32_t addr = 0;    // write / read / expect ram: the first byte address
  // expect dp_state / wd_state / dpv1 / irq: when the state was entered (dpv1: the response's
  // end; irq: X/INT went active), `at` a cycle or `after` cycles since the last action began
  // (docs/scenario-format.md, "Exact cycles").
  enum class When : std::uint8_t { any, at, after } when = When::any;
  std::uint64_t when_cycle = 0;
  // set_prm / chk_cfg / gc / send: the station that sends it (another master); nullopt: ours.
  std::optional<std::uint8_t> from;
  // send with fields: destination (nullopt: the slave) and SAPs (nullopt: none).
  std::optional<std::uint8_t> to, dsap, ssap;
  pdu::Initiate initiate;  // c2_initiate: the request
};

struct Scenario {
  std::string file;
  ChipOptions chip;
  MasterConfig master;
  ResponderConfig user;  // user.slave is also what the master parameterises
  std::string firmware;  // a built-in firmware's name or a plug-in's path, instead of the responder
  // The firmware's descriptor: a built-in's from the parse, a plug-in's once bind_plugin() has
  // loaded it (nullptr before: parsing never loads code).
  const dpc31_firmware* firmware_desc = nullptr;
  int firmware_line = 0;  // the 'firmware' line (0: none), a plug-in's or a built-in's
  std::string text;       // the scenario's text while a plug-in waits for bind_plugin()
  // load_scenario(): why another user could have changed the file ("" if none could); a
  // scenario that names a plug-in is then refused (docs/security.md).
  std::string untrusted;
  std::optional<Cpu51Config> cpu;    // `cpu 80c32`: a firmware image on an 80C32 instead
  int cpu_line = 0;                  // the `cpu` line, named by check_cpu_image()'s message
  std::vector<std::uint8_t> inputs;  // the user's inputs from the start
  std::uint32_t retries = 1;         // repeats of a request that got no answer (max_retry_limit)
  Dpv1Rules dpv1;                    // the master's DPV1 rules (header `dpv1`)
  std::vector<ScenarioStep> steps;
};

// Parses scenario text; `file` names it in messages. False with `err` set on the first error.
bool parse_scenario(std::string_view text, const std::string& file, Scenario& out,
                    ScenarioError& err);
// The same with a plug-in's loaded descriptor for its `firmware` line (bind_plugin's parse).
bool parse_scenario(std::string_view text, const std::string& file, const dpc31_firmware* plugin,
                    Scenario& out, ScenarioError& err);
bool load_scenario(const std::string& path, Scenario& out, ScenarioError& err);
// A scenario file's text (util/textfile, at most 16 MiB), and why another user could have changed
// it ("" if none could), judged on the descriptor it is read from. False with `err.message`.
bool read_scenario_file(const std::string& path, std::string& text, std::string& untrusted,
                        ScenarioError& err);
// load_scenario() on what read_scenario_file() gave (a pipe gives its text only once): a cut last
// line is refused, then the text is parsed and `untrusted` kept with it.
bool parse_scenario_file(std::string_view text, const std::string& path,
                         const std::string& untrusted, Scenario& out, ScenarioError& err);
// The one line that refuses a plug-in an untrusted scenario names (`untrusted`: why it is).
[[nodiscard]] std::string plugin_refused_untrusted(const std::string& untrusted);

// A scenario naming a firmware plug-in runs that plug-in's code. Parsing never loads it: the
// caller checks what it must (its outputs, docs/security.md), then bind_plugin() loads it
// (find_firmware: refused when another user could have changed it) and parses the text again with
// its descriptor, which sets `user` and `steps` (the slave's GSD defaults, the port and input
// names). True at once when nothing waits; false with `err` (FILE:LINE). run_scenario() binds a
// copy itself when the caller did not.
[[nodiscard]] bool plugin_pending(const Scenario& s);
bool bind_plugin(Scenario& s, ScenarioError& err);

// The files a run of `s` reads besides its text: a firmware plug-in not yet bound, a `cpu` line's
// image and the SDCC map beside it. Every door that runs a scenario hands them with its outputs
// to outfile::distinct, before any work: no output may replace one.
[[nodiscard]] std::vector<outfile::Named> scenario_inputs(const Scenario& s);

// The 80C32 image a `cpu` header names, read and checked before anything runs or is written: false
// with `error` (`SCENARIO:LINE: IMAGE: reason`, or `SCENARIO:LINE: IMAGE:LINE: reason`, the `cpu`
// line first) for the caller's exit 2. True at once without a `cpu` header. The run reads it
// again when it starts.
bool check_cpu_image(const Scenario& s, std::string& error);

struct ScenarioOutcome {
  std::uint64_t final_cycle = 0;
  DpState dp = DpState::Wait_Prm;
  WdState wd = WdState::Baud_Search;
  FdlCounters counters;
  std::uint32_t passed = 0;
  std::uint32_t failed = 0;
  std::vector<std::string> failures;  // "FILE:LINE: expected X, got Y", in order
  struct PortWrite {
    std::uint64_t cycle;
    std::string port;
    std::uint32_t value;
  };
  std::vector<PortWrite> port_writes;  // the firmware's module outputs, when it has one
  [[nodiscard]] bool ok() const { return failures.empty(); }
};

// Receives one line at a time, without its newline. An empty function discards the lines.
using LineSink = std::function<void(const std::string&)>;

// What a run tells an observer (the trace recorder), as structured events: the walk's lines are
// their text, handed over in walk order (cycle order within each step), so an observer never
// reads the printed walk. Every method does nothing unless overridden.
class ScenarioObserver {
 public:
  virtual ~ScenarioObserver() = default;
  // At cycle 0, before the user side's init and before ScenarioHooks::at_start.
  virtual void run_begins(Chip& /*chip*/) {}
  // The user side `who` ("the built-in user side", "the host firmware DO4", "the 80C32 firmware
  // F.ihx", "the C31 firmware F.ihx") has set up the chip; `text` is the walk's `started:` line,
  // or its `not started:` line for a CPU's firmware (it starts the chip later) and a host user
  // side that gave no Start_SPC3.
  virtual void user_side_started(std::uint64_t /*cycle*/, std::string_view /*who*/,
                                 std::string_view /*text*/) {}
  // Step `st` begins at `cycle` ("line K: TEXT"). Told with the step's other events, in cycle
  // order: at the step's end, or during a long action (a DPV1 service's polls) as they come.
  virtual void step_begins(std::uint64_t /*cycle*/, const ScenarioStep& /*st*/,
                           std::string_view /*text*/) {}
  // The expect `st` was checked ("line K: TEXT: ok", or "...: FAILED, got X").
  virtual void expect_checked(std::uint64_t /*cycle*/, const ScenarioStep& /*st*/, bool /*ok*/,
                              std::string_view /*text*/) {}
  // The master puts a telegram on RxD from `start` (DpMaster::on_send), damaged by `fault`.
  virtual void telegram_sent(std::uint64_t /*start*/, std::span<const std::uint8_t> /*bytes*/,
                             UartFault /*fault*/) {}
  // Any other event of the walk at its cycle: a transaction, a state change, a chip message (not
  // PB3's edges: an observer has them from Chip::on_pb3_change).
  virtual void walk_note(std::uint64_t /*cycle*/, std::string_view /*text*/) {}
  // The board's RESET (the scenario's `reset`) at `cycle`, before the chip's reset tells its edges.
  virtual void board_reset(std::uint64_t /*cycle*/) {}
  // Every event before `cycle` (the chip's cycle) has been told, and no later one is older:
  // during a long action, between two of its polls.
  virtual void events_told(std::uint64_t /*cycle*/) {}
  // Every event of the user side's init, of a step or of an expect's check has been told: the
  // chip stands at the end of it, `cycle` (a trace's checkpoint).
  virtual void step_ends(std::uint64_t /*cycle*/) {}
  // After the last step, before ScenarioHooks::at_end.
  virtual void run_ends(Chip& /*chip*/) {}
};

// Optional access to the chip a scenario runs on (the lockstep's chip-session mode records its
// block events): at_start before the firmware's init, at_end after the last step; `observer`
// gets the run's events (it must outlive the run).
struct ScenarioHooks {
  std::function<void(Chip&)> at_start;
  std::function<void(Chip&)> at_end;
  ScenarioObserver* observer = nullptr;
  // Step `st` (an action, or the fault that damages the next) begins: its walk line is out, the
  // firmware has not run in it yet (`dpc31 run` names it in the firmware's hang and fault lines).
  std::function<void(const ScenarioStep&)> at_step;
};

// Plays a parsed scenario: the walk goes to `walk`, failed expects to `errors` (and the walk).
ScenarioOutcome run_scenario(const Scenario& s, const LineSink& walk, const LineSink& errors,
                             const ScenarioHooks& hooks = {});

// Load, parse, run. Exit code: 0 every expect held, 1 one failed, 2 the file did not load or
// parse (one line to `errors`, nothing run). `scenario` / `outcome` are filled when given.
int run_scenario_file(const std::string& path, const LineSink& walk, const LineSink& errors,
                      Scenario* scenario = nullptr, ScenarioOutcome* outcome = nullptr);

}  // namespace dpc31
