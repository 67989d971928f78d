#include "demo.hpp"

#include <fmt/core.h>
#include <unistd.h>

#include <algorithm>
#include <cctype>
#include <cerrno>
#include <charconv>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <string>
#include <string_view>
#include <vector>

#include "cleanup.hpp"
#include "dpc31/dp.hpp"
#include "firmware_host.hpp"
#include "harness.hpp"
#include "outfile.hpp"
#include "run.hpp"
#include "scenario.hpp"

namespace dpc31::cli {

namespace {

namespace m0 = fields::Mode_Reg0;
namespace m1 = fields::Mode_Reg1_S;

// `path` as one word of a POSIX shell command, quoted only where the shell would split or
// expand it (a space in TMPDIR): the printed commands can be pasted as they are.
std::string shell_word(const std::string& path) {
  const bool plain = !path.empty() && std::all_of(path.begin(), path.end(), [](char c) {
    const auto u = static_cast<unsigned char>(c);
    return u >= 0x80 || std::isalnum(u) != 0 ||
           std::string_view("_-./:@%+=,").find(c) != std::string_view::npos;
  });
  if (plain) return path;
  std::string q = "'";
  for (char c : path) q += c == '\'' ? std::string("'\\''") : std::string(1, c);
  return q + "'";
}

// A firmware-like view of the chip that narrates what it does.
class Narrator {
 public:
  Narrator(Chip& chip, std::FILE* out) : chip_(chip), out_(out) {
    // The served controller's output: X/INT, or with c31 the C31 core's interrupt, while X/INT
    // stays inactive (docs/dpc31.md, "Two interrupt controllers").
    chip_.on_irq_change([this](std::uint64_t cycle, bool active) {
      if (c31_served()) {
        fmt::print(out_, "[cycle {:>8}]   C31 interrupt -> {}\n", cycle,
                   active ? "active" : "inactive");
      } else {
        fmt::print(out_, "[cycle {:>8}]   X/INT -> {} ({})\n", cycle,
                   chip_.x_int_pin() ? "high" : "low", active ? "active" : "inactive");
      }
    });
    chip_.set_log_sink(
        [this](const LogRecord& r) {
          fmt::print(out_, "[cycle {:>8}]   chip: {}\n", r.cycle, r.text);
        },
        LogLevel::info);
  }

  std::uint8_t read(RegId id, int byte = 0) {
    const auto a = static_cast<std::uint32_t>(chip_.addr_of(id) + byte);
    const std::uint8_t v = chip_.read(a);
    fmt::print(out_, "[cycle {:>8}] read  {:#06x} -> {:02X}h  {}\n", chip_.cycle(), a, v,
               name(id, byte));
    return v;
  }
  void write(RegId id, std::uint8_t v, int byte = 0) {
    const auto a = static_cast<std::uint32_t>(write_addr(id) + byte);
    chip_.write(a, v);
    fmt::print(out_, "[cycle {:>8}] write {:#06x} <- {:02X}h  {}\n", chip_.cycle(), a, v,
               name(id, byte));
  }
  // 16-bit registers: the byte that holds bits 15..8 / 7..0 depends on the bus mode.
  std::uint16_t read16(RegId id) {
    const int lo = low_byte_offset(id);
    const std::uint8_t l = read(id, lo);
    const std::uint8_t h = read(id, 1 - lo);
    return static_cast<std::uint16_t>(h << 8 | l);
  }
  void write16(RegId id, std::uint16_t v) {
    const int lo = low_byte_offset(id);
    write(id, static_cast<std::uint8_t>(v), lo);
    write(id, static_cast<std::uint8_t>(v >> 8), 1 - lo);
  }
  // The user's start and stop: Mode_Reg1_S on the SPC3 and the VPC3+; on the DPC31, whose
  // Mode_Reg1 has no such bits, a request through the Instruction_Queue (docs/dpc31.md): the
  // entry (code, parameter) in RAM, then InstQ_Wr moved on, which executes it. Returns the
  // cycle it takes effect: the completion of that write (docs/timing.md).
  std::uint64_t user_command(std::uint8_t mode_reg1_bit, std::uint8_t request, const char* name) {
    if (chip_.profile().id != Profile::dpc31) {
      write(RegId::Mode_Reg1_S, mode_reg1_bit);
      return chip_.cycle();
    }
    const Chip::RequestSlot slot = *chip_.next_request_slot();  // the demo set the queue up
    write_ram(slot.entry, request,
              fmt::format("Instruction_Queue entry at {:#06x}: {}", slot.entry, name));
    write_ram(slot.entry + 1, 0x00, "  its parameter");
    write(RegId::InstQ_Wr, slot.next_wr);
    return chip_.cycle();
  }
  void write_ram(std::uint32_t a, std::uint8_t v, const std::string& what) {
    chip_.write(a, v);
    fmt::print(out_, "[cycle {:>8}] write {:#06x} <- {:02X}h  {}\n", chip_.cycle(), a, v, what);
  }
  void step(std::uint64_t n, const char* why) {
    fmt::print(out_, "[cycle {:>8}] step  {} cycles: {}\n", chip_.cycle(), n, why);
    chip_.step(n);
  }
  void say(const std::string& s) { fmt::print(out_, "\n# {}\n", s); }
  [[nodiscard]] bool c31_served() const { return chip_.irq_controller() == IrqController::c31; }
  // The interrupt the bus's controller drives, for the section titles.
  [[nodiscard]] const char* irq() const { return c31_served() ? "the C31 interrupt" : "X/INT"; }

 private:
  std::int32_t write_addr(RegId id) const {
    const RegDesc* r = find_reg(chip_.profile(), id);
    return r->write_addr >= 0 ? r->write_addr : r->read_addr;
  }
  int low_byte_offset(RegId id) const {
    const RegDesc* r = find_reg(chip_.profile(), id);
    return r->placement(chip_.bus_mode())[0] == 0 ? 0 : 1;
  }
  std::string name(RegId id, int byte) const {
    const RegDesc* r = find_reg(chip_.profile(), id);
    if (r->width == 8) return std::string(r->name);
    return fmt::format("{} bits {}", r->name,
                       r->placement(chip_.bus_mode())[byte] == 0 ? "7..0" : "15..8");
  }

  Chip& chip_;
  std::FILE* out_;
};

// The DP session: what the demo prints before it, its script (a scenario,
// docs/scenario-format.md) and the plug-in its `firmware` line stands for.
struct DpSession {
  std::string intro;
  std::string script;
  const dpc31_firmware* plugin = nullptr;
  Scenario scenario;
};

// The script's chip: the register session's, variant and interrupt controller included.
std::string chip_header(const ChipOptions& opt) {
  std::string h = fmt::format("profile {}\n", profile_desc(opt.profile).name);
  if (opt.variant) h += fmt::format("variant {}\n", vpc3_variant_name(*opt.variant));
  if (opt.irq_controller != IrqController::external)
    h += fmt::format("irq-controller {}\n", irq_controller_name(opt.irq_controller));
  return h + fmt::format("bus {}\n", opt.bus == BusMode::intel ? "intel" : "motorola");
}

// The DP session with DO4, and what its outputs did.
DpSession do4_session(const ChipOptions& opt) {
  DpSession s;
  s.intro =
      "\n# DP session: master 2 finds slave 5 at 1.5 Mbaud (after the chip's baud search); the\n"
      "# slave runs the example firmware DO4 (firmware/do4, 4 digital outputs with the OSP\n"
      "# function model: OSPMode 'replace with static value' 1001, refresh monitor off). The\n"
      "# master sends OSPValid 0 (OSP), then sets it; the cable is pulled for 1.1 s (the DP\n"
      "# watchdog, 10 x 10 x 10 ms, expires: OSP), the master starts over (recovery).\n";
  s.script = chip_header(opt) + R"(baud 1500000
firmware DO4
slave address=5 wd=10,10 wd_on=1 user_prm=00,01,09,00
startup
exchange 2 outputs=00,00
exchange 2 outputs=05,01
exchange 2 outputs=0A,01
silence 1100ms
expect port outputs 9
expect port modul_ok 0
startup
exchange 2 outputs=0A,01
expect dp_state Data_Exchange
expect port outputs 0xA
expect port modul_ok 1
)";
  return s;
}

// The same story with any firmware (a built-in name or a plug-in): configured from its GSD
// defaults, 05h in every output byte, the cable pulled past the DP watchdog, the master starts
// over. A plug-in is loaded already (`fw`): the script's line only stands for it, since a path
// may hold what a scenario line cannot (a space, '#', '=').
DpSession firmware_session(const ChipOptions& opt, const dpc31_firmware& fw,
                           const std::string& firmware) {
  DpSession s;
  if (is_plugin_path(firmware)) s.plugin = &fw;
  s.intro = fmt::format(
      "\n# DP session: master 2 finds slave 5 at 1.5 Mbaud; the slave runs the firmware {}\n"
      "# (configured from its GSD defaults). Data_Exchange with 05h in every output byte,\n"
      "# then the cable is pulled for 1.1 s (the DP watchdog, 10 x 10 x 10 ms, expires),\n"
      "# the master starts over.\n",
      firmware);
  std::string outputs;
  for (unsigned i = 0; i < fw.out_len; ++i) outputs += i == 0 ? "05" : ",05";
  if (!outputs.empty()) outputs = " outputs=" + outputs;
  s.script = chip_header(opt) + fmt::format(R"(baud 1500000
firmware {}
slave address=5 wd=10,10 wd_on=1
startup
exchange 4{}
silence 1100ms
startup
exchange 4{}
expect dp_state Data_Exchange
)",
                                            s.plugin != nullptr ? "./plugin.so" : fw.name, outputs,
                                            outputs);
  return s;
}

// The files the demo writes, in `out_dir`. No scenario file: its failures name none.
RunOptions demo_outputs(const std::string& out_dir, const std::optional<std::string>& timescale) {
  RunOptions ro;
  ro.vcd = (std::filesystem::path(out_dir) / "dpc31-demo.vcd").string();
  ro.la_vcd = (std::filesystem::path(out_dir) / "dpc31-demo-la.vcd").string();
  ro.gtkw = (std::filesystem::path(out_dir) / "dpc31-demo.gtkw").string();
  // Beside its VCD under the same name: PulseView opens it with the VCD by itself.
  ro.pvs = (std::filesystem::path(out_dir) / "dpc31-demo-la.pvs").string();
  ro.timescale = timescale;
  ro.pcap = (std::filesystem::path(out_dir) / "dpc31-demo.pcapng").string();
  return ro;
}

// The demo's script has no file the user could open: a failure ("<demo>:LINE: what") names the
// line's command instead, and for a step the walk's "line LINE", where its run shows.
constexpr std::string_view kScriptName = "<demo>";

std::string session_error(const DpSession& s, std::string_view line) {
  const std::string_view prefix = line.substr(0, kScriptName.size() + 1);
  std::string_view rest = line.substr(prefix.size());
  int at = 0;
  const auto [end, ec] = std::from_chars(rest.data(), rest.data() + rest.size(), at);
  if (prefix != fmt::format("{}:", kScriptName) || ec != std::errc() ||
      !std::string_view(end, rest.data() + rest.size()).starts_with(": ")) {
    return fmt::format("dpc31 demo: the DP session: {}", line);
  }
  rest = std::string_view(end + 2, rest.data() + rest.size());
  std::string_view command = s.script;
  for (int i = 1; i < at && command.find('\n') != std::string_view::npos; ++i)
    command.remove_prefix(command.find('\n') + 1);
  command = command.substr(0, command.find('\n'));
  const bool step =
      std::ranges::any_of(s.scenario.steps, [at](const ScenarioStep& st) { return st.line == at; });
  return fmt::format("dpc31 demo: the DP session's `{}`{}: {}", command,
                     step ? fmt::format(" (the walk's line {})", at) : std::string(), rest);
}

// The chip's main job: a DP master on the RS-485 side, a firmware (C99, over the C HAL) on the
// other. Its outputs are what a bring-up is about: when did they change, and why. `run` was
// opened with `ro`.
int run_dp_session(const ChipOptions& opt, const RunOptions& ro, ChipRun& run,
                   const std::optional<std::string>& firmware, const DpSession& session,
                   std::FILE* out) {
  fmt::print(out, "{}", session.intro);
  ScenarioOutcome o;
  const int rc = run.run(
      session.scenario, session.script,
      [out](const std::string& line) { fmt::print(out, "{}\n", line); },
      [&session](const std::string& line) {
        fmt::print(stderr, "{}\n", session_error(session, line));
      },
      o);
  if (rc == 2) return rc;
  const double hz = Chip(opt).clock_hz();
  if (!firmware) {
    fmt::print(out,
               "\n# What DO4's outputs did (terminals DO4..DO1; ModulOK 1 = normal, 0 = OSP)\n");
  } else {
    fmt::print(out, "\n# What the firmware's ports did\n");
  }
  fmt::print(out, "{:>12} {:>14}  {}\n", "cycle", "time", "change");
  for (const ScenarioOutcome::PortWrite& w : o.port_writes) {
    std::string value = fmt::format("0x{:02X}", w.value);
    if (!firmware) {
      value = w.port == "outputs" ? fmt::format("{:04b}", w.value) : std::to_string(w.value);
    }
    fmt::print(out, "{:>12} {:>11.3f} us  {} = {}\n", w.cycle,
               static_cast<double>(w.cycle) * 1e6 / hz, w.port, value);
  }
  fmt::print(out,
             "\nwaveform (VCD): {}\nGTKWave save file (gtkwave {}): {}\nwaveform for "
             "logic-analyser tools (VCD, sigrok-cli -I vcd): {}\nPulseView session (pulseview "
             "-I vcd -i {} opens it, UART and PROFIBUS DP decoders stacked): {}\ntelegrams "
             "(pcapng, link type 257): {}\n",
             ro.vcd, shell_word(ro.gtkw), ro.gtkw, ro.la_vcd, shell_word(ro.la_vcd), ro.pvs,
             ro.pcap);
  return rc;
}

}  // namespace

int run_demo(ChipOptions opt, const std::string& out_dir_option,
             const std::optional<std::string>& firmware,
             const std::optional<std::string>& timescale, std::FILE* out) {
  int unit_exp = 0;
  if (timescale && !parse_timescale(*timescale, unit_exp)) {
    fmt::print(stderr, "dpc31 demo: {}\n", timescale_error(*timescale));
    return 2;
  }
  // A link in --out-dir may name the plug-in, as a bridge's or soak's output may: refused
  // before the plug-in is loaded (a fresh private directory holds no such link).
  if (const RunOptions ro = demo_outputs(out_dir_option, timescale); !out_dir_option.empty()) {
    if (const std::string same = outfile::distinct(
            {{"--firmware", firmware && is_plugin_path(*firmware) ? *firmware : std::string()}},
            {{"--out-dir", ro.vcd},
             {"--out-dir", ro.la_vcd},
             {"--out-dir", ro.gtkw},
             {"--out-dir", ro.pvs},
             {"--out-dir", ro.pcap}});
        !same.empty()) {
      fmt::print(stderr, "dpc31 demo: {}\n", same);
      return 2;
    }
  }
  // Checked first: bad input is one line, and nothing is made. "" is an unknown firmware, as in
  // soak, not the default.
  DpSession session = do4_session(opt);
  if (firmware) {
    try {
      const dpc31_firmware& fw = find_firmware(*firmware, hex_at_command("demo"));
      board::guard_hangs("dpc31 demo", fw.name);
      session = firmware_session(opt, fw, *firmware);
    } catch (const FirmwareError& e) {
      fmt::print(stderr, "dpc31 demo: {}\n", e.what());
      return 2;
    }
  }
  if (ScenarioError err; !parse_scenario(session.script, std::string(kScriptName), session.plugin,
                                         session.scenario, err)) {
    fmt::print(stderr, "{}\n", session_error(session, err.text()));
    return 2;
  }
  // The output directory is made before anything is printed: bad input is one line. Without
  // --out-dir it is a new one only this user can enter (mkdtemp, mode 0700): a fixed name in a
  // shared TMPDIR could be a directory or a link another user made, and the outputs would go
  // wherever that led.
  std::string out_dir = out_dir_option;
  std::error_code ec;
  // Removed again unless its files are written, also by a signal or the hang guard, so that a
  // demo that fails leaves nothing behind.
  outfile::MadeDirs made;
  if (out_dir.empty()) {
    std::string error;
    out_dir = outfile::make_temp_dir("dpc31-demo-", error);
    if (out_dir.empty()) {
      fmt::print(stderr, "dpc31 demo: {}\n", error);
      return 2;
    }
    made.add(out_dir);
  } else if (!made.make(out_dir, ec)) {
    fmt::print(stderr, "dpc31 demo: {}: cannot create the output directory: {}\n", out_dir,
               ec.message());
    return 2;
  }
  // Its files are opened now, before the register session prints: one that cannot be made is
  // one line, and nothing else.
  const RunOptions ro = demo_outputs(out_dir, timescale);
  ChipRun run(ro, "dpc31 demo", stderr);
  if (run.open(session.scenario.master.baud) != 0) return 2;
  Chip chip(opt);
  Narrator n(chip, out);
  const ProfileDesc& p = chip.profile();
  fmt::print(out, "dpc31emu demo: {} ({} profile), {} bus, {} Hz, {} clocks per bus access\n",
             p.title, p.name, chip.bus_mode() == BusMode::intel ? "Intel" : "Motorola",
             chip.clock_hz(), chip.bus_access_cycles());
  fmt::print(out, "X/INT is low-active after reset; the pin is {} at cycle 0\n",
             chip.x_int_pin() ? "high (inactive)" : "low");
  if (n.c31_served()) {
    fmt::print(out,
               "The bus reaches the C31's interrupt controller (--irq-controller c31): the lines "
               "below are the C31 interrupt; X/INT, the external controller's, stays inactive\n");
  }

  n.say(p.id == Profile::dpc31
            ? "Initialise as a driver does: clear IRR, acknowledge all, mode, unmask four "
              "events, the Instruction_Queue, MAC_Start"
            : "Initialise as a driver does: clear IRR, acknowledge all, mode, unmask four "
              "events, start");
  n.write16(RegId::Int_Req_Reg, 0x0000);
  n.write16(RegId::Int_Ack_Reg, 0xFFFF);
  n.write(RegId::Mode_Reg1_R, 0xFF);
  n.write16(RegId::Mode_Reg0, m0::DP_Mode);  // EOI inactive time 1 us; user timer 1 ms
  const std::uint16_t enabled =
      irq::DX_Out | irq::MAC_Reset | irq::User_Timer_Clock | irq::New_Prm_Data;
  n.write16(RegId::Int_Mask_Reg, static_cast<std::uint16_t>(~enabled));
  if (p.id == Profile::dpc31) {  // rings of 4 requests and 4 indications, the last two segments
    const auto last =
        static_cast<std::uint8_t>(((p.ram_begin + p.ram_size) >> p.segment_shift) - 1);
    n.write(RegId::InstQ_Base, last);
    n.write(RegId::InstQ_Len, 4);
    n.write(RegId::IndQ_Base, static_cast<std::uint8_t>(last - 1));
    n.write(RegId::IndQ_Len, 4);
  }
  // The start: the power-on clear of the outputs raises DX_Out.
  const std::uint64_t start = n.user_command(m1::Start_SPC3, request::MAC_Start, "MAC_Start");

  n.say("ISR: read IR, fetch the (cleared) outputs, acknowledge DX_Out, EOI");
  const std::uint16_t ir = n.read16(RegId::Int_Reg);
  fmt::print(out, "                   IR = {:04X}h (DX_Out = bit 13)\n", ir);
  const std::uint8_t dout = n.read(RegId::Next_Dout_Buffer_Cmd);
  fmt::print(out,
             "                   Next_Dout_Buffer_Cmd: U = buffer {}, new = {}, cleared = {}\n",
             dout & 3, (dout >> 2) & 1, (dout >> 3) & 1);
  n.write16(RegId::Int_Ack_Reg, irq::DX_Out);
  n.write(RegId::Mode_Reg1_S, m1::EOI);

  // The user timer's period P = ceil(1 ms x f) (User_Time_Base 0); its first tick is at the
  // Start's cycle + P (docs/timing.md, "Timers").
  const std::uint64_t period = (chip.clock_hz() + 999) / 1000;
  n.say(
      fmt::format("Wait for the 1 ms User_Timer_Clock (first tick at the start's cycle {} + {}); "
                  "ISR: read IR, acknowledge it, EOI",
                  start, period));
  n.step(start + period - chip.cycle(), "until the first user timer tick");
  fmt::print(out, "                   IR = {:04X}h (User_Timer_Clock = bit 4)\n",
             n.read16(RegId::Int_Reg));
  n.write16(RegId::Int_Ack_Reg, irq::User_Timer_Clock);
  n.write(RegId::Mode_Reg1_S, m1::EOI);

  n.say(fmt::format("Mask the user timer: IRR latches the event, {} stays inactive", n.irq()));
  n.write16(RegId::Int_Mask_Reg, static_cast<std::uint16_t>(~(enabled & ~irq::User_Timer_Clock)));
  n.step(chip.clock_hz() / 1000, "one more millisecond");
  fmt::print(out, "                   IRR = {:04X}h, IR = {:04X}h\n",
             chip.peek_reg(RegId::Int_Req_Reg), chip.peek_reg(RegId::Int_Reg));
  n.say(
      fmt::format("Unmask it again: {} goes active as soon as the mask write completes", n.irq()));
  n.write16(RegId::Int_Mask_Reg, static_cast<std::uint16_t>(~enabled));

  n.say(fmt::format(
      "Two events pending, acknowledge one, EOI: {} drops and returns after the 1 us inactive time",
      n.irq()));
  harness::asic_prm_received(chip);
  fmt::print(out, "[cycle {:>8}] (bus side) Set_Prm arrives: New_Prm_Data\n", chip.cycle());
  n.write16(RegId::Int_Ack_Reg, irq::User_Timer_Clock);
  n.write(RegId::Mode_Reg1_S, m1::EOI);
  n.step(60, "past the inactive time (48 cycles at 48 MHz)");

  n.say("New_Prm_Data is not acknowledged through IAR but by the User_Prm_Data_Okay read");
  n.write16(RegId::Int_Ack_Reg, irq::New_Prm_Data);
  const std::uint8_t ok = n.read(RegId::User_Prm_Data_Okay);
  fmt::print(out,
             "                   User_Prm_Data_Okay = {:02X}h (00 finished); DP state now {}\n", ok,
             chip.dp_state() == DpState::Wait_Cfg ? "Wait_Cfg" : "other");
  n.write(RegId::Mode_Reg1_S, m1::EOI);

  n.say(p.id == Profile::dpc31 ? "MAC_Stop: MAC_Reset, Status.Offline, its confirmation queued"
                               : "Go_Offline: MAC_Reset, Status.Offline");
  n.user_command(m1::Go_Offline, request::MAC_Stop, "MAC_Stop");
  const std::uint16_t status = n.read16(RegId::Status_Reg);
  fmt::print(out, "                   Status_Reg = {:04X}h (bit 0 = 0: Offline)\n", status);
  n.write16(RegId::Int_Ack_Reg, irq::MAC_Reset);
  n.write(RegId::Mode_Reg1_S, m1::EOI);
  fmt::print(out, "\nregister session done at cycle {} ({:.3f} ms of chip time)\n", chip.cycle(),
             static_cast<double>(chip.cycle()) * 1e3 / chip.clock_hz());
  const int rc = run_dp_session(opt, ro, run, firmware, session, out);
  if (rc != 2) made.keep();
  return rc;
}

}  // namespace dpc31::cli
