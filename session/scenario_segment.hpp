// Segment scenarios (docs/scenario-format.md, "Segments"; docs/segment.md): several stations,
// masters and scripted senders on one line, their actions and checks. A file whose first command
// is `segment` is one; every other scenario stays as it is.
#pragma once

#include <cstdint>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "bus_check.hpp"
#include "scenario.hpp"

namespace dpc31 {

struct SegmentStation {
  std::string name;
  ChipOptions chip;
  // "" (the built-in responder), a built-in firmware's name, or a plug-in's path (relative ones
  // made relative to the scenario's real directory).
  std::string firmware;
  SlaveConfig slave;  // what its master parameterises (address, watchdog, GSD defaults)
  // The built-in user side's user watchdog (`user_wd=`, `user_wd_value=`: the single chip's
  // `user` options); not served unless asked, as there.
  bool user_watchdog = false;
  std::uint16_t user_wd_value = ResponderConfig{}.user_wd_value;
  int plugin_line = 0;  // the line naming a plug-in; its GSD defaults wait for the binding
};

struct SegmentMaster {
  std::uint8_t address = 2;
  std::vector<std::uint8_t> slaves;  // station addresses, in polling order
  // The token rules it obeys (`ttr=`, `gap=`, `hsa=`: DpMaster::use_token, docs/segment.md "A
  // master that obeys TTR"); none given: one whole DP cycle a rotation.
  std::uint64_t ttr_bits = 0;
  std::uint8_t gap_factor = 0;
  std::uint8_t hsa = 126;
  bool obeys_token = false;
};

struct SegmentStep {
  enum class Kind : std::uint8_t {
    startup,     // each master's start-up of its slaves, the token passed on after each
    cycle,       // `count` rotations: each master one DP cycle (not `station`), then the token
    run,         // the line idle for `time`
    send,        // sender `name` puts `bytes` on the line `time` after the last telegram's end
    pass_token,  // master `address` passes the token to `station`
    expect_state,
    expect_tsdr,        // every answer so far began `count` bit times after its request's end
    expect_expired,     // `station` left DP_Control at its last restart + `time` (TWD)
    expect_violation,   // `violation` counted `count` times
    expect_collisions,  // `count` collisions
    expect_visit,       // master `address`'s last token visit (`visit`)
    expect_port,        // `station`'s firmware port `name` holds `count`
  };
  Kind kind = Kind::run;
  int line = 0;
  std::string text;
  std::uint64_t count = 0;
  std::uint64_t time = 0;
  std::uint8_t address = 0;
  std::uint8_t station = 0;
  // The station an expect names (by address or name=): its place in SegmentScenario::stations.
  std::size_t station_index = 0;
  std::optional<std::uint8_t> skip;
  std::string name;
  std::vector<std::uint8_t> bytes;
  DpState dp = DpState::Wait_Prm;
  std::optional<WdState> wd;
  // expect state … after_request=N: entered N cycles after the end of the last request to it.
  std::optional<std::uint64_t> after_request;
  BusViolation violation = BusViolation::collision;
  // expect visit: what the last visit must show; an unset field is not checked.
  struct Visit {
    std::optional<std::vector<std::uint8_t>> polled;   // slave addresses, in order
    std::optional<std::vector<std::uint8_t>> startup;  // each start-up request's slave, in order
    std::optional<std::uint64_t> rotation_bits;        // TRR
    std::optional<std::uint64_t> hold_bits;            // TTH
    std::optional<std::optional<std::uint8_t>> gap;    // the GAP address asked, or none
    std::optional<bool> gap_answered;
  } visit;
};

struct SegmentScenario {
  std::string file;
  std::uint32_t baud = 1'500'000;
  std::uint32_t slot_bits = 100;
  // The bus check's TTR (with two or more masters: the token checks); not given: the TTR its
  // masters obey (`master ... ttr=`), 0 when none does.
  std::uint64_t ttr_bits = 0;
  std::vector<SegmentStation> stations;
  std::vector<SegmentMaster> masters;
  std::vector<std::string> senders;
  std::vector<SegmentStep> steps;
  // load_segment_scenario(): why another user could have changed the file ("" if none could); a
  // scenario that names a plug-in is then refused (docs/security.md).
  std::string untrusted;
  bool plugins_bound = false;  // bind_segment_plugins() has loaded them
};

// The first command of `text` is `segment`.
[[nodiscard]] bool is_segment_scenario(std::string_view text);
bool parse_segment_scenario(std::string_view text, const std::string& file, SegmentScenario& out,
                            ScenarioError& err);
// A scenario file's text (read_scenario_file) parsed by its first command: a segment's into `out`
// (ok), one chip's into `single` as parse_scenario_file() parses it (not_segment); error with
// `err` when it does not parse.
enum class SegmentLoad : std::uint8_t { not_segment, error, ok };
SegmentLoad parse_segment_file(std::string_view text, const std::string& path,
                               const std::string& untrusted, SegmentScenario& out, Scenario& single,
                               ScenarioError& err);
// The same for the file at `path`, read once (a pipe gives its text only once); error with `err`
// also when it cannot be read.
SegmentLoad load_segment_scenario(const std::string& path, SegmentScenario& out, Scenario& single,
                                  ScenarioError& err);
// The plug-ins its stations name, as the single chip's scenario does (docs/security.md, "Code a
// command runs"): parsing never loads one; the caller checks its outputs against
// segment_plugins(), then bind_segment_plugins() loads each (find_firmware: refused when another
// user could have changed it, or the scenario) and gives its station the plug-in's GSD defaults.
// True at once when none waits; false with `err` (FILE:LINE). run_segment_scenario() binds a
// copy itself when the caller did not.
[[nodiscard]] std::vector<std::string> segment_plugins(const SegmentScenario& s);
bool bind_segment_plugins(SegmentScenario& s, ScenarioError& err);

class Segment;
struct LineTelegram;

// What watches a segment's run (the outputs of `dpc31 run`, docs/segment.md "Outputs"). The
// segment's stations are, in this order: the chips of `SegmentScenario::stations`, the senders,
// the masters.
class SegmentObserver {
 public:
  virtual ~SegmentObserver() = default;
  // Chip station `index` joined the segment, at cycle 0, before its user side's init.
  virtual void station_added(Segment& /*seg*/, std::size_t /*index*/) {}
  // Every station (chips, senders, masters) is on the segment, before the first step.
  virtual void stations_added(Segment& /*seg*/) {}
  // Station `index`'s user side has set up and started its chip.
  virtual void user_side_started(std::size_t /*index*/, std::string_view /*text*/) {}
  // Step `st` begins ("line K: TEXT"), and it ended (the line settled after it).
  virtual void step_begins(const SegmentStep& /*st*/, std::string_view /*text*/) {}
  virtual void step_ends(const SegmentStep& /*st*/) {}
  // Every telegram on the line (Segment::on_telegram).
  virtual void telegram(const LineTelegram& /*t*/) {}
  // After the last step and the line's flush.
  virtual void run_ends(Segment& /*seg*/, std::uint32_t /*passed*/, std::uint32_t /*failed*/) {}
};

// Plays it: the walk to `walk`, failed expects to `errors`. Exit code as run_scenario_file.
int run_segment_scenario(const SegmentScenario& s, const LineSink& walk, const LineSink& errors,
                         SegmentObserver* observer = nullptr);

}  // namespace dpc31
