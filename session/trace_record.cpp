// Golden traces: the recorder (a chip session -> trace text). The format: docs/trace-format.md;
// the parser is trace_parse.cpp, the replay trace_replay.cpp.
#include <fmt/format.h>

#include <algorithm>
#include <charconv>
#include <iterator>

#include "dpc31/hex.hpp"
#include "trace.hpp"
#include "vocabulary.hpp"

namespace dpc31 {

namespace {

// A comment line of the trace: its text stays on the line (a scenario's or a firmware's file name
// may hold a newline, which put the rest of the name on body lines), and a control byte, which
// the parser refuses anywhere in the file, is written as \xHH. Tabs and UTF-8 stay as they are.
std::string comment_line(std::string_view text) {
  std::string out = "# ";
  for (const char c : text) {
    const auto b = static_cast<unsigned char>(c);
    if ((b < 0x20 && c != '\t') || b == 0x7F) {
      out += fmt::format("\\x{:02X}", b);
    } else {
      out += c;
    }
  }
  return out;
}

// The start bit's cycle of an `rx` line.
std::uint64_t rx_start(std::string_view line) {
  std::uint64_t at = 0;
  std::from_chars(line.data() + 3, line.data() + line.size(), at);
  return at;
}

}  // namespace

std::vector<TraceStateKey> trace_state(const Chip& c) {
  return {
      {"dp", std::string(dp_state_name(c.dp_state()))},
      {"wd", std::string(wd_state_name(c.wd_state()))},
      {"status", fmt::format("{:04X}", c.peek_reg(RegId::Status_Reg))},
      {"irr", fmt::format("{:04X}", c.peek_reg(RegId::Int_Req_Reg))},
      {"imr", fmt::format("{:04X}", c.peek_reg(RegId::Int_Mask_Reg))},
      {"station", std::to_string(c.station_address())},
      {"fdl", counters_text(c.fdl_counters())},
  };
}

// ---------------------------------------------------------------------------------------------
// RxD batches

std::string format_rxd(std::uint64_t fed, const std::vector<std::pair<std::uint64_t, bool>>& edges,
                       std::uint32_t t, const RxdTelegram* sent) {
  // No start bit to count from (a first character sent without one) is no `rx` line either.
  if (sent != nullptr && t != 0 && !edges.empty() && !edges.front().second &&
      edges.front().first == sent->start) {
    std::vector<std::pair<std::uint64_t, bool>> enc;
    uart_encode(sent->bytes, sent->start, t, enc, sent->fault);
    if (enc == edges) {
      std::string line = fmt::format("rx {} {}", sent->start, hex_bytes(sent->bytes));
      if (sent->fault.kind != UartFault::Kind::none) {
        line +=
            fmt::format(" fault={}:{}", fault_kind_name(sent->fault.kind), sent->fault.char_index);
      }
      if (fed != sent->start) line += fmt::format(" fed={}", fed);
      return line;
    }
  }
  std::string line = fmt::format("rxd {}", fed);
  for (const auto& [c, l] : edges) line += fmt::format(" {}:{}", c, l ? 1 : 0);
  return line;
}

std::optional<RxdTelegram> read_chars(const std::vector<std::pair<std::uint64_t, bool>>& edges,
                                      std::uint32_t t) {
  if (t == 0 || edges.empty() || edges.front().second) return std::nullopt;
  const std::uint64_t start = edges.front().first;
  UartRx rx(t, start);
  for (const auto& [c, l] : edges) rx.edge(c, l);
  std::vector<UartChar> chars;
  rx.advance(edges.back().first + std::uint64_t{kUartCharBits} * t, chars);
  RxdTelegram out{start, {}, {}};
  for (const UartChar& c : chars) out.bytes.push_back(c.data);
  std::vector<std::pair<std::uint64_t, bool>> enc;
  uart_encode(out.bytes, start, t, enc);
  if (out.bytes.empty() || enc != edges) return std::nullopt;
  return out;
}

// ---------------------------------------------------------------------------------------------
// Recorder

TraceRecorder::TraceRecorder(std::uint32_t baud, std::vector<std::string> notes)
    : baud_(baud), notes_(std::move(notes)) {}

void TraceRecorder::attach(Chip& chip) {
  chip_ = &chip;
  if (chip.cycle() != 0) {
    error_ = fmt::format("the recording must start at cycle 0, not {}", chip.cycle());
  } else {
    // A baud the trace's `baud` line cannot hold makes a file replay refuses at that line.
    error_ = trace_baud_problem(baud_, chip.clock_hz());
  }
  put(kTraceMagic);
  for (const std::string& n : notes_) put(n.empty() ? "#" : comment_line(n));
  put(fmt::format("profile {}", profile_name(chip.profile().id)));
  if (chip.vpc3_variant()) {
    put(fmt::format("variant {}", vpc3_variant_name(*chip.vpc3_variant())));
  }
  if (chip.irq_controller() != IrqController::external) {
    put(fmt::format("irq-controller {}", irq_controller_name(chip.irq_controller())));
  }
  // The DPC31's PB3 is checked as X/INT is: its edges are `pb3` lines, and a replay whose chip
  // drives it otherwise fails, even where the port is never enabled.
  const bool pb3 = chip.profile().id == Profile::dpc31;
  if (pb3) put("check pb3");
  put(fmt::format("bus {}", chip.bus_mode() == BusMode::intel ? "intel" : "motorola"));
  put(fmt::format("clock {}", chip.clock_hz()));
  put(fmt::format("baud {}", baud_));

  chip.on_bus_access([this](std::uint64_t cycle, const BusAccess& e) {
    if (e.write) {
      add(cycle, fmt::format("wr {} {:04X} {:02X}", cycle, e.addr, e.data));
    } else {
      // Emitted when the access completes, just before it acts: peek gives what it returns
      // (a command read's result included). The replay holds the two to account.
      add(cycle, fmt::format("rd {} {:04X} = {:02X}", cycle, e.addr, chip_->peek(e.addr)));
    }
  });
  chip.on_irq_change([this](std::uint64_t cycle, bool active) {
    add(cycle, fmt::format("xint {} {}", cycle, active ? 1 : 0));
  });
  if (pb3) {
    chip.on_pb3_change([this](std::uint64_t cycle, bool high) {
      add(cycle, fmt::format("pb3 {} {}", cycle, high ? 1 : 0));
    });
  }
  chip.on_telegram([this](const Telegram& t) {
    if (!t.from_chip) return;  // received ones are recorded from RxD, edge by edge
    add(t.start, fmt::format("tx {} {} {}", t.start, t.end, hex_bytes(t.bytes)));
  });
  chip.on_rxd([this](std::uint64_t cycle, bool level) {
    if (finished_) return;
    if (closing_) close_segment();
    const std::uint64_t fed = chip_->cycle();
    if (line_t_ != 0) {
      // A segment's line: a start bit later than the end of the last character begins a
      // telegram (one back to back continues it).
      const bool start = !level && cycle >= line_char_end_;
      if (start && cycle > line_char_end_) close_rxd();
      if (start) line_char_end_ = cycle + std::uint64_t{kUartCharBits} * line_t_;
    } else if (!rxd_.empty() && fed != rxd_fed_) {
      close_rxd();
    }
    if (rxd_.empty()) rxd_fed_ = fed;
    rxd_.emplace_back(cycle, level);
  });
}

void TraceRecorder::add(std::uint64_t key, std::string text) {
  if (finished_) {
    if (error_.empty()) error_ = fmt::format("an event at cycle {} after the end", key);
    return;
  }
  if (closing_) close_segment();
  close_rxd();
  seg_.push_back(Entry{key, std::move(text)});
}

void TraceRecorder::close_rxd() {
  if (rxd_.empty()) return;
  const std::uint32_t t = chip_ != nullptr ? bit_cycles(chip_->clock_hz(), baud_) : 0;
  if (line_t_ != 0 && !sent_) sent_ = read_chars(rxd_, line_t_);
  seg_.push_back(Entry{rxd_fed_, format_rxd(rxd_fed_, rxd_, t, sent_ ? &*sent_ : nullptr)});
  rxd_.clear();
  sent_.reset();
}

void TraceRecorder::heading(std::string text) { headings_.push_back(std::move(text)); }

void TraceRecorder::note(std::uint64_t cycle, std::string text) {
  seg_.push_back(Entry{cycle, comment_line(text)});
}

void TraceRecorder::note_heard(std::uint64_t start, std::string text) {
  if (finished_) return;
  // Its batch is complete once the segment reports the telegram: closed now, its line comes first.
  if (!rxd_.empty() && rxd_.front().first == start) close_rxd();
  // The segment reports a telegram once the line stayed idle past its end, which can be after the
  // step that heard it ended: its line is then written already, and the note follows it there,
  // not the next step's heading (where it would name the sender of the telegram after it).
  const std::string rx = fmt::format("rx {} ", start);
  const bool open = std::any_of(seg_.begin(), seg_.end(), [&](const Entry& e) {
    return e.key == start && e.text.starts_with(rx);
  });
  // Back to its line: the rx lines before it are earlier (the trace is in cycle order); those
  // gone out are of telegrams reported before (heard()).
  for (std::size_t i = held_.size(); !open && i > 0; --i) {
    const std::string& line = held_[i - 1];
    if (!line.starts_with("rx ")) continue;
    if (line.starts_with(rx)) {
      held_.insert(held_.begin() + static_cast<std::ptrdiff_t>(i), comment_line(text));
      heard(start);
      return;
    }
    if (rx_start(line) < start) break;
  }
  note(start, std::move(text));
  heard(start);
}

void TraceRecorder::heard(std::uint64_t start) {
  heard_ = std::max(heard_.value_or(0), start);
  release_held(false);
}

void TraceRecorder::put(std::string_view line) {
  if (out_) {
    out_(line);
    out_("\n");
  } else {
    kept_.append(line);
    kept_ += '\n';
  }
}

void TraceRecorder::emit(std::string line) {
  if (line_t_ == 0) {
    put(line);
  } else {
    held_.push_back(std::move(line));
  }
}

void TraceRecorder::release_held(bool all) {
  while (!held_.empty()) {
    const std::string& line = held_.front();
    // An rx line of a telegram not yet reported may still get its note.
    if (!all && line.starts_with("rx ") && (!heard_ || rx_start(line) > *heard_)) return;
    put(line);
    held_.pop_front();
  }
}

std::string TraceRecorder::state_line() const {
  std::string s = fmt::format("state {}", chip_->cycle());
  for (const TraceStateKey& k : trace_state(*chip_)) s += fmt::format(" {}={}", k.key, k.value);
  return s;
}

void TraceRecorder::write_entries(std::uint64_t upto) {
  std::stable_sort(seg_.begin(), seg_.end(), [](const Entry& a, const Entry& b) {
    return a.key < b.key || (a.key == b.key && !a.walk && b.walk);
  });
  for (std::string& h : headings_) emit(comment_line(h));
  headings_.clear();
  const auto beyond =
      std::find_if(seg_.begin(), seg_.end(), [&](const Entry& e) { return e.key >= upto; });
  for (auto e = seg_.begin(); e != beyond; ++e) {
    const bool comment = e->text.starts_with('#');
    if (e->key < last_key_ && !comment && error_.empty()) {
      error_ = fmt::format("'{}' is out of cycle order (after cycle {})", e->text, last_key_);
    }
    if (!comment) last_key_ = std::max(last_key_, e->key);
    emit(std::move(e->text));
  }
  seg_.erase(seg_.begin(), beyond);
}

void TraceRecorder::close_segment() {
  close_rxd();
  closing_ = false;
  // What lies beyond the checkpoint (an answer the chip decided at its request's end, due
  // TSDR later, when a segment's step ended in between) stays to open the next segment.
  write_entries(pending_state_ ? pending_state_->first + 1 : UINT64_MAX);
  if (pending_state_) {
    const auto& [cycle, line] = *pending_state_;
    if (cycle < last_key_ && error_.empty()) {
      error_ = fmt::format("'{}' is out of cycle order (after cycle {})", line, last_key_);
    }
    last_key_ = std::max(last_key_, cycle);
    if (line != last_state_) emit(line);
    last_state_ = line;
    pending_state_.reset();
  }
  release_held(false);
}

void TraceRecorder::checkpoint() {
  if (chip_ == nullptr || finished_) return;
  close_rxd();
  pending_state_.emplace(chip_->cycle(), state_line());
  close_segment();
}

void TraceRecorder::finish() {
  if (chip_ == nullptr) {
    // text() has no header then: nothing replay could read.
    if (error_.empty()) error_ = "never attached to a chip: attach() before the run";
    return;
  }
  if (finished_) return;
  if (closing_) close_segment();
  checkpoint();
  emit(fmt::format("end {}", chip_->cycle()));
  release_held(true);
  finished_ = true;
}

ScenarioHooks TraceRecorder::scenario_hooks() {
  ScenarioHooks h;
  h.observer = this;
  return h;
}

void TraceRecorder::run_begins(Chip& chip) { attach(chip); }

void TraceRecorder::run_ends(Chip&) { finish(); }

// The runner tells a step's events in cycle order, its own line first (at its end, or during a
// long action as they come): that line heads a segment, the other events become notes at their
// cycles, and step_ends() gives the checkpoint.
void TraceRecorder::mark(std::string heading) {
  if (chip_ == nullptr || finished_) return;
  if (closing_) close_segment();  // the previous step left no event: close it now
  headings_.push_back(std::move(heading));
}

void TraceRecorder::step_ends(std::uint64_t) {
  if (chip_ == nullptr || finished_) return;
  if (closing_) close_segment();
  close_rxd();
  pending_state_.emplace(chip_->cycle(), state_line());
  closing_ = true;
}

void TraceRecorder::events_told(std::uint64_t cycle) {
  if (chip_ == nullptr || finished_ || closing_) return;
  write_entries(rxd_.empty() ? cycle : std::min(cycle, rxd_fed_));
  release_held(false);
}

std::string TraceRecorder::user_side_heading(std::string_view who) const {
  // A `cpu` firmware runs from cycle 0 and starts the chip later (the walk says when); a host user
  // side that gave no Start_SPC3 never does.
  if (chip_ != nullptr &&
      field_of(chip_->peek_reg(RegId::Status_Reg), fields::Status_Reg::Offline_Passive_Idle) == 0) {
    return fmt::format("user side: {}", who);
  }
  // The DPC31 starts through its Instruction_Queue (MAC_Start), the others through Mode_Reg1.
  const bool dpc31 = chip_ != nullptr && chip_->profile().id == Profile::dpc31;
  return fmt::format("firmware init ({}): registers, buffers, {}", who,
                     dpc31 ? "MAC_Start" : "Start_SPC3");
}

void TraceRecorder::user_side_started(std::uint64_t, std::string_view who, std::string_view text) {
  mark(fmt::format("{}; {}", user_side_heading(who), text));
}

void TraceRecorder::step_begins(std::uint64_t, const ScenarioStep&, std::string_view text) {
  mark(std::string(text));
}

void TraceRecorder::expect_checked(std::uint64_t, const ScenarioStep&, bool,
                                   std::string_view text) {
  mark(std::string(text));
}

void TraceRecorder::telegram_sent(std::uint64_t start, std::span<const std::uint8_t> bytes,
                                  UartFault fault) {
  close_rxd();  // the batch before is another's
  sent_ = RxdTelegram{start, {bytes.begin(), bytes.end()}, fault};
}

void TraceRecorder::board_reset(std::uint64_t cycle) { add(cycle, fmt::format("reset {}", cycle)); }

void TraceRecorder::walk_note(std::uint64_t cycle, std::string_view text) {
  if (chip_ == nullptr || finished_) return;
  seg_.push_back(Entry{cycle, comment_line(text), true});
}

}  // namespace dpc31
