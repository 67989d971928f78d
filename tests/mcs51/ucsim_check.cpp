// The ucsim cross-check (docs/cpu.md): one Intel HEX program on our 80C32 and on SDCC's s51 (run
// as a separate program), compared instruction by instruction: PC, A, B, PSW, SP, DPTR, R0..R7 of
// the current bank and the oscillator clocks of each step. The first difference is printed with
// both states; exit 0 equal, 1 different, 2 bad input or an s51 that failed (its exit code or
// signal, no answer within --timeout seconds, no trace): never reported as a difference.
//
// s51 0.6.4 differs from the Intel manual in its interrupt call, and the comparison allows for
// exactly that (docs/cpu.md, "The ucsim cross-check"): its step that ends in an interrupt call
// also runs the routine's first instruction and counts the call as one machine cycle, not two.
#include <fcntl.h>
#include <fmt/format.h>
#include <poll.h>
#include <signal.h>
#include <spawn.h>
#include <sys/wait.h>
#include <unistd.h>

#include <bit>
#include <cerrno>
#include <charconv>
#include <chrono>
#include <cstdlib>
#include <cstring>
#include <fstream>
#include <iostream>
#include <optional>
#include <set>
#include <sstream>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

#include "mcs51/cpu.hpp"
#include "mcs51/ihex.hpp"

extern char** environ;

namespace {

struct State {
  unsigned pc = 0, a = 0, b = 0, psw = 0, sp = 0, dptr = 0;
  unsigned r[8] = {};
  unsigned long long clocks = 0;  // oscillator clocks of this step
  bool operator==(const State&) const = default;
};

std::string show(const State& s) {
  return fmt::format(
      "PC={:04X} A={:02X} B={:02X} PSW={:02X} SP={:02X} DPTR={:04X} "
      "R0-7={:02X} {:02X} {:02X} {:02X} {:02X} {:02X} {:02X} {:02X} clocks={}",
      s.pc, s.a, s.b, s.psw, s.sp, s.dptr, s.r[0], s.r[1], s.r[2], s.r[3], s.r[4], s.r[5], s.r[6],
      s.r[7], s.clocks);
}

State capture(const mcs51::Cpu& cpu, unsigned long long clocks) {
  State s{cpu.pc(), cpu.a(), cpu.b(), cpu.psw(), cpu.sp(), cpu.dptr(), {}, clocks};
  for (unsigned i = 0; i < 8; ++i) s.r[i] = cpu.reg(i);
  return s;
}

// Our run, grouped as s51 steps: an instruction, or an instruction, the call after it and the
// routine's first instruction. Ends at a jump to itself (the programs' halt) or after `limit`.
std::vector<State> ours(mcs51::Cpu& cpu, std::vector<std::uint16_t>& at, std::size_t limit) {
  std::vector<State> out;
  while (out.size() < limit) {
    std::uint16_t pc = cpu.pc();
    mcs51::StepResult r = cpu.step();
    unsigned long long clocks = r.cycles * 12ULL;
    if (r.kind == mcs51::StepKind::instruction && cpu.interrupt_due()) {
      clocks += (cpu.step().cycles - 1) * 12ULL;  // s51 counts the call as one cycle
      clocks += cpu.step().cycles * 12ULL;
    }
    out.push_back(capture(cpu, clocks));
    at.push_back(pc);
    if (cpu.pc() == pc && cpu.code(pc) == 0x80 && !cpu.interrupt_due()) break;
  }
  return out;
}

unsigned hex_after(const std::string& line, const std::string& key) {
  std::size_t p = line.find(key);
  if (p == std::string::npos) return ~0u;
  return static_cast<unsigned>(std::strtoul(line.c_str() + p + key.size(), nullptr, 16));
}

// s51 with a script of `steps` steps on its standard input, started at once so that several run
// side by side. The script is unlinked as soon as s51 has it open, and a run still going when it
// is dropped (a failure elsewhere in the batch) is killed: nothing is left behind on any way out.
class Run {
 public:
  Run() = default;
  Run(const Run&) = delete;
  Run& operator=(const Run&) = delete;
  Run(Run&& o) noexcept { *this = std::move(o); }
  Run& operator=(Run&& o) noexcept {
    std::swap(pid_, o.pid_);
    std::swap(out_, o.out_);
    std::swap(deadline_, o.deadline_);
    return *this;
  }
  ~Run() {
    if (out_ >= 0) ::close(out_);
    if (pid_ > 0) {
      ::kill(-pid_, SIGKILL);
      int status = 0;
      ::waitpid(pid_, &status, 0);
    }
  }

  // "" or why s51 could not be started.
  std::string start(const std::string& s51, const std::string& hex, std::size_t steps,
                    std::chrono::seconds timeout) {
    const char* tmp = std::getenv("TMPDIR");
    std::string script =
        fmt::format("{}/mcs51_ucsim_XXXXXX", tmp != nullptr && *tmp != 0 ? tmp : "/tmp");
    const int in = ::mkstemp(script.data());
    if (in < 0)
      return fmt::format("cannot create the s51 script {}: {}", script, std::strerror(errno));
    ::unlink(script.c_str());  // open as s51's standard input: gone with the last descriptor
    std::string text = "fill iram 0 0xff 0\nfill xram 0 0xffff 0\n";
    for (std::size_t i = 0; i < steps; ++i) text += "step\n";
    text += "quit\n";
    const bool written = ::write(in, text.data(), text.size()) == static_cast<ssize_t>(text.size());
    if (!written || ::lseek(in, 0, SEEK_SET) != 0) {
      ::close(in);
      return fmt::format("cannot write the s51 script: {}", std::strerror(errno));
    }
    int pipe_fds[2];
    if (::pipe2(pipe_fds, O_CLOEXEC) != 0) {
      ::close(in);
      return fmt::format("cannot make a pipe: {}", std::strerror(errno));
    }
    posix_spawn_file_actions_t fa;
    posix_spawn_file_actions_init(&fa);
    posix_spawn_file_actions_adddup2(&fa, in, 0);
    posix_spawn_file_actions_adddup2(&fa, pipe_fds[1], 1);
    posix_spawn_file_actions_adddup2(&fa, pipe_fds[1], 2);
    std::vector<std::string> args = {s51, "-t", "80C32", "-b", "-q", hex};
    std::vector<char*> argv;
    for (std::string& a : args) argv.push_back(a.data());
    argv.push_back(nullptr);
    // A group of its own: a kill reaches whatever it started too.
    posix_spawnattr_t attr;
    posix_spawnattr_init(&attr);
    posix_spawnattr_setflags(&attr, POSIX_SPAWN_SETPGROUP);
    posix_spawnattr_setpgroup(&attr, 0);
    const int rc = ::posix_spawn(&pid_, s51.c_str(), &fa, &attr, argv.data(), environ);
    posix_spawnattr_destroy(&attr);
    posix_spawn_file_actions_destroy(&fa);
    ::close(in);
    ::close(pipe_fds[1]);
    out_ = pipe_fds[0];
    if (rc != 0) {
      pid_ = 0;
      return fmt::format("cannot start s51 {}: {}", s51, std::strerror(rc));
    }
    deadline_ = std::chrono::steady_clock::now() + timeout;
    return {};
  }

  // Everything s51 wrote, until it ends; "" in `error` only when it ended with exit code 0.
  std::string output(std::chrono::seconds timeout, std::string& error) {
    std::string text;
    char buf[65536];
    for (;;) {
      const auto left = std::chrono::duration_cast<std::chrono::milliseconds>(
          deadline_ - std::chrono::steady_clock::now());
      pollfd p{out_, POLLIN, 0};
      if (left.count() <= 0 || ::poll(&p, 1, static_cast<int>(left.count())) == 0) {
        error = fmt::format("s51 gave no end within {} s: killed", timeout.count());
        return text;  // the destructor kills it
      }
      const ssize_t n = ::read(out_, buf, sizeof buf);
      if (n < 0 && errno == EINTR) continue;
      if (n <= 0) break;
      text.append(buf, static_cast<std::size_t>(n));
    }
    int status = 0;
    while (::waitpid(pid_, &status, 0) < 0 && errno == EINTR) {
    }
    pid_ = 0;
    if (WIFSIGNALED(status)) {
      error = fmt::format("s51 was ended by signal {} ({})", WTERMSIG(status),
                          ::strsignal(WTERMSIG(status)));
    } else if (WEXITSTATUS(status) != 0) {
      error = fmt::format("s51 ended with exit code {}{}", WEXITSTATUS(status),
                          WEXITSTATUS(status) == 127 ? " (not a program that runs?)" : "");
    }
    return text;
  }

 private:
  pid_t pid_ = 0;
  int out_ = -1;
  std::chrono::steady_clock::time_point deadline_{};
};

// s51's answer to `step`: "Stop at 0x000002: (109) stepped 12 ticks", then the register block.
std::vector<State> parse_trace(const std::string& text) {
  std::vector<std::string> lines;
  std::istringstream in(text);
  for (std::string l; std::getline(in, l);) lines.push_back(l);
  std::vector<State> out;
  for (std::size_t i = 0; i + 6 < lines.size(); ++i) {
    if (lines[i].rfind("Stop at 0x", 0) != 0) continue;
    State s;
    s.pc = hex_after(lines[i], "Stop at 0x");
    s.clocks = std::strtoull(lines[i].c_str() + lines[i].find("stepped ") + 8, nullptr, 10);
    std::istringstream regs(lines[i + 2]);
    for (unsigned& r : s.r) regs >> std::hex >> r;
    s.a = hex_after(lines[i + 3], "ACC= 0x");
    s.b = hex_after(lines[i + 3], "B= 0x");
    s.psw = hex_after(lines[i + 4], "PSW= 0x");
    s.sp = hex_after(lines[i + 5], "SP 0x");
    s.dptr = hex_after(lines[i + 6], "DPTR= 0x");
    // s51 sets P only when A changes; after a write to PSW its P may disagree with A. The
    // manual's P is the parity of A in every cycle: ours is checked against that instead.
    if ((std::popcount(s.a) & 1) != static_cast<int>(s.psw & 1)) s.psw ^= 1;
    out.push_back(s);
  }
  return out;
}

// A whole number lo..hi, or nullopt.
std::optional<std::size_t> whole(std::string_view s, std::size_t lo, std::size_t hi) {
  std::size_t v = 0;
  const auto [p, ec] = std::from_chars(s.data(), s.data() + s.size(), v);
  if (s.empty() || ec != std::errc() || p != s.data() + s.size() || v < lo || v > hi) return {};
  return v;
}

struct Program {
  std::string path;
  std::vector<std::uint16_t> at;
  std::vector<State> ours;
  Run run;
};

constexpr const char* kUsage =
    "usage: mcs51_ucsim_check [--limit N] [--timeout S] [--s51 PATH] [--coverage] PROGRAM.ihx...";

int usage(const std::string& why) {
  std::cerr << "mcs51_ucsim_check: " << why << " (" << kUsage << ")\n";
  return 2;
}

}  // namespace

int main(int argc, char** argv) {
  std::size_t limit = 20'000;        // steps per program unless it reaches its SJMP $ (docs/cpu.md)
  std::chrono::seconds timeout{60};  // per s51 run; the slowest program takes about 2 s
  std::string s51 = S51_PROGRAM;
  std::vector<Program> programs;
  std::set<unsigned> executed;  // opcodes run by any program
  bool coverage = false;
  for (int i = 1; i < argc; ++i) {
    const std::string arg = argv[i];
    if (arg == "--help" || arg == "-h") {
      std::cout << kUsage
                << "\nEach program runs to its SJMP $ or N steps (default 20000) on the core and "
                   "on s51, compared after every instruction (docs/cpu.md, \"The ucsim "
                   "cross-check\"); --timeout S per s51 run (default 60).\n";
      return 0;
    }
    if (arg == "--limit" || arg == "--timeout" || arg == "--s51") {
      if (i + 1 == argc) return usage(arg + " needs a value");
      const std::string v = argv[++i];
      if (arg == "--s51") {
        s51 = v;
        continue;
      }
      const std::optional<std::size_t> n = whole(v, 1, 100'000'000);
      if (!n) return usage(fmt::format("{} '{}' must be a whole number 1..100000000", arg, v));
      if (arg == "--limit") {
        limit = *n;
      } else {
        timeout = std::chrono::seconds(*n);
      }
      continue;
    }
    if (arg == "--coverage") {  // every opcode but the reserved A5h must have run
      coverage = true;
      continue;
    }
    std::ifstream in(arg);
    std::stringstream text;
    text << in.rdbuf();
    mcs51::HexImage img;
    std::string error;
    if (!in || !mcs51::parse_ihex(text.str(), img, error)) {
      std::cerr << arg << ": " << (in ? error : "cannot be read") << "\n";
      return 2;
    }
    mcs51::Cpu cpu;
    cpu.load_code(0, img.bytes);  // unused program memory reads FFh (an erased EPROM), as in s51
    Program p{arg, {}, {}, {}};
    p.ours = ours(cpu, p.at, limit);
    for (std::uint16_t pc : p.at) executed.insert(cpu.code(pc));
    programs.push_back(std::move(p));
  }
  if (programs.empty()) return usage("no program");
  int failed = 0;
  constexpr std::size_t batch = 8;  // s51 mostly waits: run several at once
  for (std::size_t first = 0; first < programs.size(); first += batch) {
    const std::size_t end = std::min(programs.size(), first + batch);
    for (std::size_t i = first; i < end; ++i) {
      // On a failure the runs already started are killed by their destructors.
      if (std::string why =
              programs[i].run.start(s51, programs[i].path, programs[i].ours.size(), timeout);
          !why.empty()) {
        std::cerr << programs[i].path << ": " << why << "\n";
        return 2;
      }
    }
    for (std::size_t i = first; i < end; ++i) {
      Program& p = programs[i];
      std::string error;
      const std::string text = p.run.output(timeout, error);
      const std::vector<State> b = parse_trace(text);
      // s51 said nothing we can compare: its failure, not a difference of our core.
      if (error.empty() && b.empty()) error = "s51 gave no trace (no 'Stop at' line)";
      if (!error.empty()) {
        const std::string said = text.substr(0, text.find('\n'));
        std::cerr << p.path << ": " << error << (said.empty() ? "" : ": " + said) << "\n";
        return 2;
      }
      const std::vector<State>& a = p.ours;
      std::size_t n = std::min(a.size(), b.size()), k = 0;
      while (k < n && a[k] == b[k]) ++k;
      if (k == n && a.size() == b.size()) {
        std::cout << fmt::format("{}: {} instructions equal\n", p.path, n);
        continue;
      }
      ++failed;
      std::cout << fmt::format("{}: instruction {} (at {:04X}) differs\n", p.path, k,
                               k < p.at.size() ? p.at[k] : 0);
      if (k > 0) std::cout << "  before  " << show(a[k - 1]) << "\n";
      std::cout << "  ours    " << (k < a.size() ? show(a[k]) : "(ended)") << "\n";
      std::cout << "  s51     " << (k < b.size() ? show(b[k]) : "(ended)") << "\n";
    }
  }
  std::cout << fmt::format("{} of {} programs equal\n",
                           programs.size() - static_cast<std::size_t>(failed), programs.size());
  // Coverage is a verdict of its own: a gap is no program that differs.
  bool gap = false;
  if (coverage) {
    std::string missing;
    for (unsigned op = 0; op < 256; ++op)
      if (op != 0xA5 && !executed.contains(op)) missing += fmt::format(" {:02X}", op);
    gap = !missing.empty();
    std::cout << (gap ? "coverage: opcodes no program ran:" + missing
                      : std::string("coverage: every opcode but A5h ran"))
              << "\n";
  }
  return failed == 0 && !gap ? 0 : 1;
}
