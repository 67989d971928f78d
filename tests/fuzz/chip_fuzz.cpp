// Fuzz targets chip_bits and chip_bytes: the serial line into the chip, with the user side
// (session/responder.cpp: Prm/Cfg verdicts, Dout/Din, diagnostics, New_GC_Command, EOI) running
// whenever X/INT is active, and the invariant checker (invariants.hpp) after every event.
//
// Input byte 0 chooses the set-up:
//   bits 1..0  profile: 0 spc3, 1 vpc3plus, 2 and 3 dpc31
//   bit 2      bus: 0 Intel, 1 Motorola
//   bit 3      1: start in Data_Exchange at 1.5 Mbaud (a snapshot taken once after the built-in
//              master's start-up: slave 5 locked by master 2), so deep DP states are one frame
//              away; 0: a freshly started chip, idle until its Baud_Search reaches the rate below
//   bits 7..4  baud code (0 = 12 Mbaud ... 9 = 9.6 kbaud, 10..15 = 9 - n % 10) for the fresh chip
// The rest is the line (see chip_bits / chip_bytes below). After the last item the chip runs on
// for a while with a silent line (watchdogs, the user's answers).
#include <algorithm>
#include <array>
#include <cstring>
#include <map>
#include <memory>
#include <optional>
#include <vector>

#include "cpu.hpp"
#include "dp_master.hpp"
#include "dpc31/uart.hpp"
#include "fuzz_targets.hpp"
#include "invariants.hpp"
#include "responder.hpp"

namespace dpc31::fuzz {

namespace {

constexpr std::uint32_t kRates[] = {12'000'000, 6'000'000, 3'000'000, 1'500'000, 500'000,
                                    187'500,    93'750,    45'450,    19'200,    9'600};
constexpr std::uint64_t kTailBits = 20'000;  // silent line after the input

ResponderConfig user_config() {
  ResponderConfig cfg;
  cfg.substitute = {0xA5, 0x5A, 0x0F, 0xF0};
  return cfg;
}

struct Setup {
  Profile profile;
  BusMode bus;
  bool data_exchange;
  std::uint8_t baud_code;
};

Setup decode_setup(std::uint8_t b) {
  static constexpr Profile kProfiles[] = {Profile::spc3, Profile::vpc3plus, Profile::dpc31,
                                          Profile::dpc31};
  const unsigned code = b >> 4;
  return {kProfiles[b & 3], (b & 4) != 0 ? BusMode::motorola : BusMode::intel, (b & 8) != 0,
          static_cast<std::uint8_t>(code < 10 ? code : 9 - code % 10)};
}

// The user side without a CPU thread: whenever X/INT is active the ISR runs to its end (its bus
// accesses take their clocks), otherwise the chip runs to the next interrupt.
void run_until(Chip& chip, Responder& user, std::uint64_t end) {
  while (chip.cycle() < end) {
    if (chip.irq_active()) {
      DirectBus bus(chip);
      user.isr(bus);
      user.outputs.clear();  // only the chip's state matters here; keep memory flat
      user.interrupts.clear();
      continue;
    }
    chip.step_until_irq(end - chip.cycle());
  }
}

// A chip in Data_Exchange and its user side, made once per profile and bus mode.
struct Prefix {
  std::vector<std::uint8_t> snapshot;
  std::unique_ptr<Responder> user;
};

const Prefix& data_exchange_prefix(Profile p, BusMode bus) {
  static std::map<std::pair<Profile, BusMode>, Prefix> cache;
  auto it = cache.find({p, bus});
  if (it != cache.end()) return it->second;
  Chip chip({p, bus});
  chip.set_log_sink(nullptr);
  auto user = std::make_unique<Responder>(user_config());
  user->set_inputs({0x11, 0x22, 0x33, 0x44});
  DirectBus direct(chip);
  user->init(direct);
  {
    DpMaster master(chip, MasterConfig{}, user_config().slave);
    master.set_firmware([&](BusPort& b) { user->isr(b); });
    if (!master.startup() || !master.data_exchange({1, 2, 3, 4}).answer) {
      std::fprintf(stderr, "fuzz prefix: the master did not reach Data_Exchange\n");
      std::abort();
    }
    master.idle(2000);
  }
  user->outputs.clear();
  user->interrupts.clear();
  Prefix px{chip.save_state(), std::move(user)};
  return cache.emplace(std::make_pair(p, bus), std::move(px)).first->second;
}

// One run: the chip after its prefix, the user side, the checker.
class Run {
 public:
  explicit Run(const Setup& s) : chip_({s.profile, s.bus}) {
    chip_.set_log_sink(nullptr);  // the log costs time and says nothing the checker needs
    if (s.data_exchange) {
      const Prefix& px = data_exchange_prefix(s.profile, s.bus);
      chip_.load_state(px.snapshot);
      user_ = std::make_unique<Responder>(*px.user);
      checker_.attach(chip_, true);  // the master idled 2000 clocks (62 bit times) before it
      t_ = bit_time(1'500'000);
    } else {
      user_ = std::make_unique<Responder>(user_config());
      user_->set_inputs({0x11, 0x22, 0x33, 0x44});
      checker_.attach(chip_, true);  // RxD idle since reset
      DirectBus direct(chip_);
      user_->init(direct);
      t_ = bit_time(kRates[s.baud_code]);
      // Baud_Search steps down from 12 Mbaud, max(4096 bit times, 20 ms) per rate (docs/timing.md):
      // wait in steps of a 64th of a window, so the input starts near the beginning of the chosen
      // rate's window.
      for (int i = 0; i < 12 * 64 && chip_.bit_cycles() != t_; ++i) {
        const std::uint64_t step =
            std::max<std::uint64_t>(64ull * chip_.bit_cycles(), chip_.clock_hz() / 50 / 64);
        run_until(chip_, *user_, chip_.cycle() + step);
      }
    }
    at_ = chip_.cycle();
  }

  [[nodiscard]] std::uint32_t bit_cycles() const { return t_; }
  // The line: RxD edges are handed to the chip ahead of time, as a master's UART would send them.
  void edge(std::uint64_t cycle, bool level) {
    if (cycle < chip_.cycle()) cycle = chip_.cycle();
    if (cycle < last_edge_) cycle = last_edge_;
    last_edge_ = cycle;
    chip_.drive_rxd(cycle, level);
  }
  // Characters back to back from `at_` after `gap_bits` idle bit times.
  void chars(std::span<const std::uint8_t> bytes, std::uint64_t gap_bits, UartFault fault = {}) {
    at_ = std::max(at_ + gap_bits * t_, chip_.cycle());
    at_ = std::max(at_, last_edge_);
    edges_.clear();
    uart_encode(bytes, at_, t_, edges_, fault);
    for (const auto& [c, l] : edges_) edge(c, l);
    at_ += bytes.size() * std::uint64_t{kUartCharBits} * t_;
  }
  void idle_cycles(std::uint64_t n) { at_ += n; }
  std::uint64_t& at() { return at_; }
  // The user side does something of its own at the current point of the line.
  void user_action(unsigned what) {
    run_until(chip_, *user_, at_);
    DirectBus bus(chip_);
    const std::int32_t mode1_s = chip_.addr_of(RegId::Mode_Reg1_S);
    switch (what % 4) {
      case 0: {  // new inputs: fill U, New_Din_Buffer_Cmd
        const std::int32_t cmd = chip_.addr_of(RegId::New_Din_Buffer_Cmd);
        if (cmd >= 0) bus.read(static_cast<std::uint32_t>(cmd));
        break;
      }
      case 1: {  // new diagnostics: New_Diag_Buffer_Cmd
        const std::int32_t cmd = chip_.addr_of(RegId::New_Diag_Buffer_Cmd);
        if (cmd >= 0) bus.read(static_cast<std::uint32_t>(cmd));
        break;
      }
      case 2:  // User_Leave_Master
        if (mode1_s >= 0) bus.write(static_cast<std::uint32_t>(mode1_s), 0x08);
        break;
      case 3: {  // fetch outputs: Next_Dout_Buffer_Cmd
        const std::int32_t cmd = chip_.addr_of(RegId::Next_Dout_Buffer_Cmd);
        if (cmd >= 0) bus.read(static_cast<std::uint32_t>(cmd));
        break;
      }
    }
    at_ = std::max(at_, chip_.cycle());
  }
  void finish() {
    run_until(chip_, *user_, std::max(at_, last_edge_) + kTailBits * t_);
    checker_.check();
  }

 private:
  [[nodiscard]] std::uint32_t bit_time(std::uint32_t baud) const {
    const std::uint64_t f = chip_.clock_hz();
    return static_cast<std::uint32_t>((2 * f + baud) / (2 * baud));  // round, halves up
  }

  Chip chip_;
  std::unique_ptr<Responder> user_;
  InvariantChecker checker_;
  std::uint32_t t_ = 0;
  std::uint64_t at_ = 0;
  std::uint64_t last_edge_ = 0;
  std::vector<std::pair<std::uint64_t, bool>> edges_;
};

std::uint8_t fcs(std::span<const std::uint8_t> b) {
  unsigned s = 0;
  for (std::uint8_t x : b) s += x;
  return static_cast<std::uint8_t>(s);
}

}  // namespace

// chip_bits: after byte 0, pairs (lo, hi): RxD goes to level hi.7 after a delay of
// ((hi & 3Fh) << 8 | lo) units, a unit being one clock if hi.6 is set, else 1/8 of the bit time.
int chip_bits(const std::uint8_t* data, std::size_t size) {
  if (size < 1) return 0;
  Run run(decode_setup(data[0]));
  const std::uint32_t t = run.bit_cycles();
  for (std::size_t i = 1; i + 1 < size; i += 2) {
    const std::uint8_t lo = data[i], hi = data[i + 1];
    const std::uint64_t units = static_cast<std::uint64_t>(hi & 0x3F) << 8 | lo;
    run.at() += (hi & 0x40) != 0 ? units : units * t / 8;
    run.edge(run.at(), (hi & 0x80) != 0);
  }
  run.finish();
  return 0;
}

// chip_bytes: after byte 0, items led by a control byte c:
//   c < 80h           one character (the next byte) after c idle bit times
//   80h..BFh          one damaged character (the next byte) after c & 0Fh idle bit times;
//                     (c >> 4) & 3: 0 parity, 1 stop bit, 2 start bit, 3 parity
//   C0h..DFh          a frame: the next byte n (mod 64) and n body bytes (DA SA FC [DSAP SSAP]
//                     DU...), sent as SD1 (n = 3), SD3 (n = 11 and c bit 1) or SD2 with LE, FCS
//                     and ED filled in, after 33 + (c >> 2 & 7) idle bit times; c bit 0 spoils
//                     the FCS
//   E0h..EFh          a silent line for ((c & 0Fh) + 1) x 4 000 000 clocks (watchdogs)
//   F0h..FFh          a user action: new inputs, new diagnostics, User_Leave_Master, fetch outputs
int chip_bytes(const std::uint8_t* data, std::size_t size) {
  if (size < 1) return 0;
  Run run(decode_setup(data[0]));
  std::size_t i = 1;
  while (i < size) {
    const std::uint8_t c = data[i++];
    if (c < 0x80) {
      if (i >= size) break;
      run.chars(std::span(&data[i++], 1), c);
    } else if (c < 0xC0) {
      if (i >= size) break;
      static constexpr UartFault::Kind kKinds[] = {UartFault::Kind::parity, UartFault::Kind::stop,
                                                   UartFault::Kind::start, UartFault::Kind::parity};
      run.chars(std::span(&data[i++], 1), c & 0x0F, UartFault{0, kKinds[(c >> 4) & 3]});
    } else if (c < 0xE0) {
      if (i >= size) break;
      const std::size_t n = data[i++] % 64;
      if (n < 3 || i + n > size) break;
      std::span<const std::uint8_t> body(&data[i], n);
      i += n;
      std::vector<std::uint8_t> f;
      if (n == 3) {
        f.push_back(0x10);
      } else if (n == 11 && (c & 2) != 0) {
        f.push_back(0xA2);
      } else {
        f = {0x68, static_cast<std::uint8_t>(n), static_cast<std::uint8_t>(n), 0x68};
      }
      f.insert(f.end(), body.begin(), body.end());
      f.push_back(static_cast<std::uint8_t>(fcs(body) + (c & 1)));
      f.push_back(0x16);
      run.chars(f, 33 + ((c >> 2) & 7));
    } else if (c < 0xF0) {
      run.idle_cycles((std::uint64_t{c & 0x0Fu} + 1) * 4'000'000);
    } else {
      run.user_action(c & 0x0F);
    }
  }
  run.finish();
  return 0;
}

// A set-up byte and one whole item (an edge) after it.
std::string chip_bits_check(const std::uint8_t* /*data*/, std::size_t size) {
  return size >= 3 ? "" : "no edge after the set-up byte";
}

// A set-up byte and one whole item after it (a character, a frame, a silence or an action).
std::string chip_bytes_check(const std::uint8_t* data, std::size_t size) {
  if (size < 2) return "no item after the set-up byte";
  const std::uint8_t c = data[1];
  if (c >= 0xE0) return "";
  if (size < 3) return "the first item is cut off";
  if (c < 0xC0) return "";
  const std::size_t n = data[2] % 64;
  return n >= 3 && 3 + n <= size ? "" : "the first frame is cut off or shorter than 3 bytes";
}

}  // namespace dpc31::fuzz
