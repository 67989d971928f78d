// Fuzz targets for the text and binary inputs of the product: golden traces, scenario files, the
// `dpc31 serve` command lines and snapshots. Each goes through the same function the product
// uses on a file or a socket line; errors must come back as the documented error values.
#include <sys/mman.h>
#include <unistd.h>
#include <zlib.h>

#include <algorithm>
#include <cctype>
#include <cstdio>
#include <cstdlib>
#include <string>
#include <string_view>
#include <vector>

#include "dpc31/chip.hpp"
#include "dpc31/snapshot.hpp"
#include "fuzz_targets.hpp"
#include "invariants.hpp"
#include "scenario.hpp"
#include "scenario_segment.hpp"
#include "serve_session.hpp"
#include "textfile.hpp"
#include "trace.hpp"

namespace dpc31::fuzz {

namespace {

std::string_view text(const std::uint8_t* data, std::size_t size) {
  return {reinterpret_cast<const char*>(data), size};
}

[[noreturn]] void bug(const std::string& what) {
  std::fprintf(stderr, "fuzz: %s\n", what.c_str());
  std::abort();
}

// A replay runs the chip up to the trace's last cycle; beyond this a trace only costs time (an
// `end 10^18` line is legal), so longer ones are parsed but not replayed.
constexpr std::uint64_t kMaxReplayCycles = std::uint64_t{1} << 32;

}  // namespace

// `dpc31 replay FILE`: the file checked line by line (TraceFile: errors are TraceError, exit 2),
// which must refuse what the file read whole refuses (its cut last line, cut_or_earlier_error,
// then parse_trace) at the same line in the same words; then the replay on a fresh chip from the
// file, which must end as the replay of the parsed text does.
int trace_parser(const std::uint8_t* data, std::size_t size) {
  const std::string_view input = text(data, size);
  TraceError whole{"fuzz.trace", 0, {}};
  whole.line =
      cut_or_earlier_error(input, whole.message, [&](const std::string& all, std::string& m) {
        Trace p;
        TraceError e;
        if (parse_trace(all, "fuzz.trace", p, e)) return 0;
        m = e.message;
        return e.line;
      });
  Trace t;
  const bool parsed = whole.line == 0 && parse_trace(input, "fuzz.trace", t, whole);
  if (!parsed && whole.message.empty()) bug("parse_trace failed without a message");

  const int fd = ::memfd_create("fuzz.trace", MFD_CLOEXEC);
  if (fd < 0 || ::write(fd, data, size) != static_cast<ssize_t>(size)) bug("memfd_create/write");
  TraceFile file;
  TraceError err;
  const bool opened = file.open("/proc/self/fd/" + std::to_string(fd), err);
  ::close(fd);
  if (opened != parsed || (!opened && (err.line != whole.line || err.message != whole.message))) {
    bug("TraceFile: '" + err.message + "' at line " + std::to_string(err.line) + ", read whole: '" +
        whole.message + "' at line " + std::to_string(whole.line));
  }
  if (!parsed) return 0;
  std::uint64_t last = 0;
  for (const TraceLine& l : t.lines) last = std::max({last, l.cycle, l.start, l.end});
  if (last > kMaxReplayCycles) return 0;
  const ReplayOutcome a = replay_trace(file);
  const ReplayOutcome b = replay_trace(t);
  // The failures name their files: the rest, "LINE: expected ...", is compared.
  const auto said = [](const std::string& f) { return f.substr(std::min(f.find(':'), f.size())); };
  if (a.ok != b.ok || said(a.failure) != said(b.failure) || a.final_cycle != b.final_cycle ||
      a.telegrams_out != b.telegrams_out || a.irq_edges != b.irq_edges ||
      a.pb3_edges != b.pb3_edges || a.states != b.states) {
    bug("the replay from the file ends unlike the parsed trace's: '" + a.failure + "' against '" +
        b.failure + "'");
  }
  return 0;
}

namespace {

// What `dpc31 run` parses a scenario file with, by its first command: a segment's parser or one
// chip's. False with `err` when it does not parse.
bool parse_any_scenario(std::string_view in, const std::string& file, ScenarioError& err) {
  if (is_segment_scenario(in)) {
    SegmentScenario seg;
    Scenario single;
    return parse_segment_file(in, file, "", seg, single, err) == SegmentLoad::ok;
  }
  Scenario s;
  return parse_scenario(in, file, s, err);
}

}  // namespace

// `dpc31 run FILE`, the parsing half (running needs the built-in master and a CPU thread).
int scenario_parser(const std::uint8_t* data, std::size_t size) {
  ScenarioError err;
  if (!parse_any_scenario(text(data, size), "fuzz.scn", err) && err.message.empty()) {
    bug("the scenario parser failed without a message");
  }
  return 0;
}

// One `dpc31 serve` client: every line of the input to the command interpreter, as the server
// runs it. There is no --state-dir: `save` and `load` are refused whatever their name says.
int serve_lines(const std::uint8_t* data, std::size_t size) {
  serve::Session session({}, [](const serve::AsyncLine&) {});
  serve::ClientState client;
  std::string_view in = text(data, size);
  while (!in.empty()) {
    const std::size_t nl = in.find('\n');
    const std::string_view line = in.substr(0, nl);
    in = nl == std::string_view::npos ? std::string_view{} : in.substr(nl + 1);
    const serve::Session::Result r = session.execute(line, client);
    if (r.reply.rfind("OK", 0) != 0 && r.reply.rfind("ERR ", 0) != 0) {
      bug("serve reply is neither OK nor ERR: " + r.reply);
    }
    if (r.reply.find('\n') != std::string::npos) bug("serve reply spans lines");
    if (r.action != serve::Session::Action::none) break;
  }
  return 0;
}

namespace {

int load_one(std::span<const std::uint8_t> bytes);

}  // namespace

// Chip::load_state: a snapshot is accepted by the chip of its configuration or rejected with
// SnapshotError, the chip unchanged. An accepted one must save again to bytes that load again to
// the same state, and the chip must run from it with the invariants holding. Every input is
// loaded as it is, and once more with its CRC-32 (header bytes 32..35, docs/snapshots.md) made
// to fit, so mutations reach the payload checks instead of all ending at the CRC.
int snapshot_loader(const std::uint8_t* data, std::size_t size) {
  load_one({data, size});
  if (size >= 36) {
    std::vector<std::uint8_t> fixed(data, data + size);
    uLong crc = crc32(0L, Z_NULL, 0);
    crc = crc32(crc, fixed.data(), 32);
    crc = crc32(crc, fixed.data() + 36, static_cast<uInt>(size - 36));
    for (int i = 0; i < 4; ++i)
      fixed[32 + static_cast<std::size_t>(i)] = std::uint8_t(crc >> 8 * i);
    load_one(fixed);
  }
  return 0;
}

namespace {

int load_one(std::span<const std::uint8_t> bytes) {
  for (Profile p : kAllProfiles) {
    for (BusMode bus : {BusMode::intel, BusMode::motorola}) {
      Chip chip({p, bus});
      chip.set_log_sink(nullptr);
      const std::vector<std::uint8_t> fresh = chip.save_state();
      try {
        chip.load_state(bytes);
      } catch (const SnapshotError&) {
        if (chip.save_state() != fresh) bug("a rejected snapshot changed the chip");
        continue;
      }
      const std::vector<std::uint8_t> once = chip.save_state();
      Chip again({p, bus});
      again.set_log_sink(nullptr);
      try {
        again.load_state(once);
      } catch (const SnapshotError& e) {
        bug(std::string("a saved snapshot does not load: ") + e.what());
      }
      if (again.save_state() != once) bug("save(load(save(load(x)))) differs from save(load(x))");
      InvariantChecker checker;
      checker.attach(chip);
      checker.check();
      chip.step(200'000);
      for (std::uint32_t a = 0; a < 0x40; ++a) (void)chip.read(a);
      chip.step(2'000'000);
      return 0;
    }
  }
  return 0;
}

}  // namespace

std::string trace_parser_check(const std::uint8_t* data, std::size_t size) {
  Trace t;
  TraceError err;
  return parse_trace(text(data, size), "seed.trace", t, err) ? "" : err.message;
}

std::string scenario_parser_check(const std::uint8_t* data, std::size_t size) {
  ScenarioError err;
  return parse_any_scenario(text(data, size), "seed.scn", err) ? "" : err.message;
}

// What the server asks of a connection's first line: a command word.
std::string serve_lines_check(const std::uint8_t* data, std::size_t size) {
  const std::string_view in = text(data, size);
  const std::string_view word = in.substr(0, in.find_first_of(" \t\r\n"));
  return serve::is_command(word) ? "" : "the first line is not a command";
}

// The loader's own verdict: accepted by the chip of one configuration, else its SnapshotError.
std::string snapshot_loader_check(const std::uint8_t* data, std::size_t size) {
  std::string why = "no configuration";
  for (Profile p : kAllProfiles) {
    for (BusMode bus : {BusMode::intel, BusMode::motorola}) {
      Chip chip({p, bus});
      chip.set_log_sink(nullptr);
      try {
        chip.load_state({data, size});
        return "";
      } catch (const SnapshotError& e) {
        why = e.what();
      }
    }
  }
  return why;
}

}  // namespace dpc31::fuzz
