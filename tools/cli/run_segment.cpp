// `dpc31 run` of a segment's scenario (docs/segment.md, "Outputs"): the waveforms with a scope per
// station and the line at the top and one pcapng of the line (lib/segment_outputs), a golden trace
// per station, the JSON summary. Nothing is written unless the run completes.
#include <fmt/core.h>
#include <sys/stat.h>

#include <cstdint>
#include <memory>
#include <nlohmann/json.hpp>
#include <string_view>
#include <vector>

#include "board.hpp"
#include "firmware_host.hpp"
#include "outfile.hpp"
#include "run.hpp"
#include "scenario_segment.hpp"
#include "segment.hpp"
#include "segment_outputs.hpp"
#include "textfile.hpp"
#include "trace.hpp"
#include "vocabulary.hpp"

namespace dpc31::cli {

std::string station_trace_path(const std::string& record, const std::string& scope) {
  const std::string base =
      record.ends_with(".trace") ? record.substr(0, record.size() - 6) : record;
  return base + "." + scope + ".trace";
}

namespace {

// What `dpc31 run` writes of a segment's run beyond the library's waveforms and pcapng: a trace
// per station, the JSON summary.
class RunOutputs final : public SegmentScenarioOutputs {
 public:
  RunOutputs(const RunOptions& opt, const SegmentScenario& s, std::string_view text)
      : SegmentScenarioOutputs(s, SegmentOutputOptions{wave_options(opt, s.baud), opt.pcap}),
        opt_(opt),
        s_(s),
        comments_(leading_comments(text)) {}

  // Every file the run writes, for outfile::distinct.
  [[nodiscard]] std::vector<outfile::Named> outputs() const {
    std::vector<outfile::Named> out = {{"--json", opt_.json}, {"--vcd", opt_.vcd},
                                       {"--fst", opt_.fst},   {"--la-vcd", opt_.la_vcd},
                                       {"--pcap", opt_.pcap}, {"--gtkw", opt_.gtkw},
                                       {"--pvs", opt_.pvs}};
    for (const std::string& sc : scopes()) {
      // Named after FILE, which cannot be a descriptor: no /dev/stdout in its place.
      out.push_back(
          {"--record", opt_.record.empty() ? "" : station_trace_path(opt_.record, sc), false});
    }
    return out;
  }

  // Opens the files the run does not write as it goes; false with a line.
  bool open(std::string& error) {
    // The stations' traces are named after FILE, beside it: beside a device, a FIFO or a
    // descriptor (/dev/null, /dev/stdout) they would be new files in its directory (/dev), and
    // FILE `d/` would put hidden `d/.stationN.trace` files in d. One chip's FILE is refused so.
    if (!opt_.record.empty()) {
      const std::string& f = opt_.record;
      struct stat st {};
      const bool there = ::stat(f.c_str(), &st) == 0;
      const char* why =
          f.ends_with('/')               ? "cannot write: a file name cannot end in '/'"
          : there && S_ISDIR(st.st_mode) ? "cannot write: is a directory"
          : (there && !S_ISREG(st.st_mode)) || outfile::descriptor_link(f).link
              ? "not a regular file: a segment writes a trace per station beside FILE "
                "(FILE.stationN.trace), so FILE names a file"
              : nullptr;
      if (why != nullptr) {
        error = shown_line(fmt::format("--record {}: {}", f, why));
        return false;
      }
    }
    if (!SegmentScenarioOutputs::open(error)) return false;
    for (const std::string& sc : scopes()) {
      if (opt_.record.empty()) break;
      auto& f = trace_files_.emplace_back(std::make_unique<outfile::OutFile>());
      if (!f->open(station_trace_path(opt_.record, sc)) || !f->spool()) {
        error = f->error();
        return false;
      }
    }
    if (!opt_.json.empty() && !json_.open(opt_.json)) {
      error = json_.error();
      return false;
    }
    return true;
  }

  // A chip station at cycle 0, before its init: its scope in every waveform, its trace.
  void station_added(Segment& seg, std::size_t index) override {
    SegmentScenarioOutputs::station_added(seg, index);
    seg_ = &seg;
    if (opt_.record.empty()) return;
    std::vector<std::string> notes = comments_;
    if (!notes.empty()) notes.emplace_back();
    notes.push_back(
        fmt::format("recorded by `dpc31 run --record` from {}, station {} ({}) of its segment "
                    "(docs/trace-format.md)",
                    s_.file, s_.stations[index].slave.address, s_.stations[index].name));
    auto& r = traces_.emplace_back(std::make_unique<TraceRecorder>(s_.baud, std::move(notes)));
    // Written as it goes into the station's temporary (as one chip's trace is).
    r->write_to([&out = *trace_files_[index]](std::string_view bytes) { out.write(bytes); });
    r->hear_line(seg.bit_cycles());
    r->attach(seg.chip(index));
    heard_from_.push_back(SIZE_MAX);
  }

  void user_side_started(std::size_t index, std::string_view text) override {
    if (index >= traces_.size()) return;
    traces_[index]->heading(traces_[index]->user_side_heading(text));
    traces_[index]->checkpoint();
  }

  void step_begins(const SegmentStep& st, std::string_view text) override {
    SegmentScenarioOutputs::step_begins(st, text);
    for (auto& r : traces_) r->heading(std::string(text));
  }
  void step_ends(const SegmentStep&) override {
    for (auto& r : traces_) r->checkpoint();
  }

  void telegram(const LineTelegram& t) override {
    // Each station's trace names the sender of what it heard when the sender changes.
    for (std::size_t k = 0; k < traces_.size(); ++k) {
      if (k == t.from || heard_from_[k] == t.from) {
        traces_[k]->heard(t.start);
        continue;
      }
      heard_from_[k] = t.from;
      traces_[k]->note_heard(t.start, fmt::format("from {}", seg_->name(t.from)));
    }
    SegmentScenarioOutputs::telegram(t);
  }

  void run_ends(Segment& seg, std::uint32_t passed, std::uint32_t failed) override {
    SegmentScenarioOutputs::run_ends(seg, passed, failed);
    for (auto& r : traces_) r->finish();
    if (!opt_.json.empty()) json_text_ = summary(seg, passed, failed).dump(2) + '\n';
  }

  // Writes every output of a run that completed; false with a line.
  bool write(std::string& error) {
    for (std::size_t k = 0; k < traces_.size(); ++k) {
      if (!traces_[k]->error().empty()) {
        error = fmt::format("cannot record station {} of {}: {}", s_.stations[k].slave.address,
                            opt_.scenario, traces_[k]->error());
        return false;
      }
      if (!trace_files_[k]->commit()) {
        error = trace_files_[k]->error();
        return false;
      }
    }
    if (!SegmentScenarioOutputs::write(error)) return false;
    if (json_.is_open() && !(json_.write(json_text_) && json_.commit())) {
      error = json_.error();
      return false;
    }
    return true;
  }

 private:
  nlohmann::json summary(Segment& seg, std::uint32_t passed, std::uint32_t failed) const {
    nlohmann::json stations = nlohmann::json::array();
    for (std::size_t k = 0; k < s_.stations.size(); ++k) {
      const Chip& c = seg.chip(k);
      nlohmann::json counters = nlohmann::json::object();
      for (const CounterField& f : fdl_counter_fields())
        counters[std::string(f.name)] = c.fdl_counters().*(f.member);
      stations.push_back({{"name", s_.stations[k].name},
                          {"address", s_.stations[k].slave.address},
                          {"scope", scopes()[k]},
                          {"profile", std::string(profile_name(c.profile().id))},
                          {"dp_state", std::string(dp_state_name(c.dp_state()))},
                          {"wd_state", std::string(wd_state_name(c.wd_state()))},
                          {"counters", counters}});
    }
    return {{"scenario", s_.file},
            {"baud", s_.baud},
            {"final_cycle", seg.cycle()},
            {"stations", stations},
            {"collisions", seg.collisions().size()},
            {"expects", {{"passed", passed}, {"failed", failed}}},
            {"ok", failed == 0}};
  }

  const RunOptions& opt_;
  const SegmentScenario& s_;
  const std::vector<std::string> comments_;  // the scenario's leading comments
  Segment* seg_ = nullptr;
  std::vector<std::unique_ptr<TraceRecorder>> traces_;
  std::vector<std::unique_ptr<outfile::OutFile>> trace_files_;
  std::vector<std::size_t> heard_from_;  // per trace: the sender of the last telegram noted
  outfile::OutFile json_;
  std::string json_text_;
};

}  // namespace

int run_segment_command(const RunOptions& opt, const SegmentScenario& s, std::string_view text,
                        const LineSink& walk, const LineSink& errors, std::FILE* err) {
  if (opt.engine != Engine::event) {
    fmt::print(err, "dpc31 run: {}: --engine per-cycle: a segment runs on the event engine\n",
               opt.scenario);
    return 2;
  }
  std::string error = waveform_options_error(opt);
  RunOutputs out(opt, s, text);
  std::vector<outfile::Named> inputs = {{"the scenario", opt.scenario}};
  for (const std::string& p : segment_plugins(s)) inputs.push_back({"the firmware plug-in", p});
  if (error.empty()) error = outfile::distinct(inputs, out.outputs());
  if (error.empty()) out.open(error);
  if (!error.empty()) {
    fmt::print(err, "dpc31 run: {}\n", error);
    return 2;
  }
  // The plug-ins the stations name are loaded now, after every other check (docs/security.md).
  SegmentScenario bound = s;
  ScenarioError berr;
  if (!bind_segment_plugins(bound, berr)) {
    errors(berr.text());
    return 2;
  }
  // A firmware stuck in a loop without a bus access cannot be stopped from this thread: the guard
  // ends the process with one line, naming the place and the station that spins (its
  // FirmwareHost's name), as the fault line below does.
  std::string plugins;
  for (const std::string& p : segment_plugins(bound)) plugins += (plugins.empty() ? "" : ", ") + p;
  if (!plugins.empty()) board::guard_hangs("dpc31 run", plugins);
  int rc = 0;
  try {
    const board::HangPlace place(out.firmware_place().text());
    rc = run_segment_scenario(bound, walk, errors, &out);
  } catch (const FirmwareError& e) {
    fmt::print(err, "dpc31 run: {}\n", out.firmware_place().message(e.what()));
    return 2;
  } catch (const SegmentOutputError& e) {
    fmt::print(err, "dpc31 run: {}\n", e.what());
    return 2;
  }
  if (!out.write(error)) {
    fmt::print(err, "dpc31 run: {}\n", error);
    return 2;
  }
  return rc;
}

}  // namespace dpc31::cli
