// The host CPU (session/cpu.hpp): the firmware's ISR interleaves with the bus side one bus access
// at a time (4 clocks each, docs/timing.md), resumes where it stopped, and keeps its own HAL
// selection; an exception it throws reaches the bus side; destroying the CPU unwinds an ISR in
// progress. A main loop runs whenever no interrupt is served, a pass takes at least 1 us
// (docs/decisions.md), an enabled X/INT preempts it between two accesses and a masked one
// does not; the board hooks (dpc31_firmware.h) act on the host that runs the firmware.
#include "cpu.hpp"

#include <fmt/format.h>
#include <gtest/gtest.h>
#include <sys/resource.h>
#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <csignal>
#include <cstdlib>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

#include "board.hpp"
#include "dpc31/dpc31_firmware.h"
#include "dpc31/dpc31_hal.h"
#include "dpc31/dpc31_regs.h"
#include "dpc31/hal.hpp"
#include "firmware.h"
#include "firmware_host.hpp"
#include "harness.hpp"
#include "test_util.hpp"

namespace {

using namespace dpc31;

constexpr std::uint64_t kAccess = 4;
constexpr std::uint32_t kRam = 0x0900;  // user RAM in every profile

// A chip whose X/INT goes active at cycle 8 (DX_Out unmasked by two writes, then raised).
Chip chip_with_pending_irq() {
  Chip c({Profile::dpc31, BusMode::intel, 0});
  c.set_log_sink(nullptr);
  c.write(0x04, static_cast<std::uint8_t>(~irq::DX_Out & 0xFF));
  c.write(0x05, static_cast<std::uint8_t>(~irq::DX_Out >> 8));
  harness::asic_raise(c, irq::DX_Out);
  return c;
}

// Acknowledges DX_Out (Int_Ack_Reg high byte at 0x03 in Intel order): X/INT goes inactive.
void acknowledge(BusPort& b) { b.write(0x03, static_cast<std::uint8_t>(irq::DX_Out >> 8)); }

// An ISR that notes the cycle it is entered in, then acknowledges.
Cpu::Isr recording_isr(std::vector<std::uint64_t>& entries) {
  return [&entries](BusPort& b) {
    entries.push_back(b.cycle());
    acknowledge(b);
  };
}

TEST(HostCpu, IsrInterleavesPerAccessAndResumesWhereItStopped) {
  Chip c = chip_with_pending_irq();
  ASSERT_EQ(c.cycle(), 2 * kAccess);
  ASSERT_TRUE(c.irq_active());
  std::vector<std::uint64_t> ends;
  Cpu cpu(c, [&](BusPort& b) {
    for (int i = 0; i < 5; ++i) {
      b.read(kRam);
      ends.push_back(b.cycle());
    }
    acknowledge(b);
  });
  cpu.run_until(16);  // two accesses fit: 8..12, 12..16
  EXPECT_EQ(ends, (std::vector<std::uint64_t>{12, 16}));
  EXPECT_EQ(c.cycle(), 16u);
  cpu.run_until(100);  // three more reads and the acknowledge (ends at 32), then idle to 100
  EXPECT_EQ(ends, (std::vector<std::uint64_t>{12, 16, 20, 24, 28}));
  EXPECT_FALSE(c.irq_active());
  EXPECT_EQ(c.cycle(), 100u);
}

TEST(HostCpu, AnExceptionInTheIsrReachesTheBusSide) {
  Chip c = chip_with_pending_irq();
  int entries = 0;
  Cpu cpu(c, [&](BusPort& b) {
    ++entries;
    b.read(kRam);
    if (entries == 1) throw std::runtime_error("firmware failed");
    acknowledge(b);
  });
  try {
    cpu.run_until(100);
    FAIL() << "no exception";
  } catch (const std::runtime_error& e) {
    EXPECT_STREQ(e.what(), "firmware failed");
  }
  EXPECT_EQ(c.cycle(), 12u);  // the one read
  cpu.run_until(100);         // X/INT is still active: the ISR is entered again, and finishes
  EXPECT_EQ(entries, 2);
  EXPECT_FALSE(c.irq_active());
}

// The C HAL's selection is per side: while an ISR waits between two of its accesses, the bus
// side's Vpc3Read still reaches the chip the bus side selected, and the ISR's own next access
// reaches the chip it runs against.
TEST(HostCpu, HalSelectionStaysWithItsSide) {
  Chip fw_chip = chip_with_pending_irq();
  Chip host_chip({Profile::spc3, BusMode::intel, 0});
  host_chip.set_log_sink(nullptr);
  DirectBus host_bus(host_chip);
  const hal::Scope host_scope(host_bus, nullptr);

  Cpu cpu(fw_chip, [&](BusPort& b) {
    const hal::Scope scope(b, nullptr);
    Vpc3Write(kRam, 0xA5);
    Vpc3Write(kRam + 1, 0x5A);
    acknowledge(b);
  });
  cpu.run_until(12);  // the first write (8..12); the ISR waits before its second
  EXPECT_EQ(fw_chip.peek(kRam), 0xA5);
  EXPECT_EQ(host_chip.cycle(), 0u);
  Vpc3Write(kRam, 0x3C);  // the bus side's selection: the SPC3
  EXPECT_EQ(host_chip.cycle(), kAccess);
  EXPECT_EQ(host_chip.peek(kRam), 0x3C);
  EXPECT_EQ(fw_chip.cycle(), 12u);
  cpu.run_until(100);
  EXPECT_EQ(fw_chip.peek(kRam + 1), 0x5A);
  EXPECT_EQ(fw_chip.peek(kRam), 0xA5);
  EXPECT_EQ(host_chip.cycle(), kAccess);  // nothing of the ISR reached the SPC3
}

TEST(HostCpu, DestroyingTheCpuUnwindsAnIsrInProgress) {
  Chip c = chip_with_pending_irq();
  struct Flag {
    bool* set;
    ~Flag() { *set = true; }
  };
  bool unwound = false;
  {
    Cpu cpu(c, [&](BusPort& b) {
      const Flag f{&unwound};
      for (;;) b.read(kRam);  // never finishes on its own
    });
    cpu.run_until(40);
    EXPECT_EQ(c.cycle(), 40u);
    EXPECT_FALSE(unwound);
  }
  EXPECT_TRUE(unwound);
}

// A pass takes at least 1 us: 48 clocks at 48 MHz, its accesses included.
constexpr std::uint64_t kPass = 48;

TEST(HostCpu, MainLoopPassTakesAtLeastOneMicrosecond) {
  Chip c({Profile::dpc31, BusMode::intel, 0});
  c.set_log_sink(nullptr);
  ASSERT_EQ(c.clock_hz(), 48'000'000u);
  int passes = 0;
  bool read = false;
  std::vector<std::uint64_t> reads;
  Cpu cpu(c, Cpu::Program{{}, [&](BusPort& b) {
                            ++passes;
                            if (read) {
                              b.read(kRam);
                              reads.push_back(b.cycle());
                            }
                          }});
  cpu.run_until(10 * kPass);
  // Ten passes of 48 clocks; the eleventh has run and waits for its microsecond at the limit.
  EXPECT_EQ(passes, 11);
  EXPECT_EQ(c.cycle(), 10 * kPass);
  read = true;  // from the twelfth pass on, one read each (4 clocks) and 44 clocks of the loop
  cpu.run_until(20 * kPass);
  EXPECT_EQ(passes, 11 + 10);
  EXPECT_EQ(reads, (std::vector<std::uint64_t>{11 * kPass + 4, 12 * kPass + 4, 13 * kPass + 4,
                                               14 * kPass + 4, 15 * kPass + 4, 16 * kPass + 4,
                                               17 * kPass + 4, 18 * kPass + 4, 19 * kPass + 4}));
  EXPECT_EQ(c.cycle(), 20 * kPass);
}

TEST(HostCpu, EnabledInterruptPreemptsTheMainLoopBetweenTwoAccesses) {
  Chip c = chip_with_pending_irq();  // X/INT active at 8
  std::vector<std::uint64_t> isr_entries;
  std::vector<std::uint64_t> main_reads;
  Cpu cpu(c, Cpu::Program{recording_isr(isr_entries), [&](BusPort& b) {
                            b.read(kRam);
                            main_reads.push_back(b.cycle());
                          }});
  cpu.run_until(8 + 2 * kPass);
  // The main loop's first access waits for the ISR (the acknowledge, 8..12): it ends at 16, and
  // the pass that began at 8 ends at 8 + 48; the next pass reads 56..60.
  EXPECT_EQ(isr_entries, (std::vector<std::uint64_t>{8}));
  EXPECT_EQ(main_reads, (std::vector<std::uint64_t>{16, 8 + kPass + 4}));
  EXPECT_FALSE(c.irq_active());
}

TEST(HostCpu, MaskedInterruptLeavesAPollingLoopAloneUntilEnabled) {
  Chip c = chip_with_pending_irq();
  bool enabled = false;  // the board's interrupt input, as dpc31_board_int_enable sets it
  std::vector<std::uint64_t> isr_entries;
  int reads = 0;
  Cpu cpu(c, Cpu::Program{recording_isr(isr_entries),
                          [&](BusPort& b) {
                            b.read(kRam);
                            ++reads;
                          },
                          &enabled});
  cpu.run_until(8 + 3 * kPass);
  EXPECT_TRUE(isr_entries.empty());
  EXPECT_EQ(reads, 3);  // 8..12, 56..60, 104..108: one per pass, the ISR never
  EXPECT_TRUE(c.irq_active());
  enabled = true;
  cpu.run_until(8 + 3 * kPass + 8);
  // Right away: the third pass was still in its loop instructions (an idle wait).
  EXPECT_EQ(isr_entries, (std::vector<std::uint64_t>{8 + 3 * kPass}));
  EXPECT_FALSE(c.irq_active());
}

TEST(HostCpu, IdleWaitIsPreemptedAndStillTakesItsTime) {
  Chip c = chip_with_pending_irq();
  std::vector<std::uint64_t> isr_entries;
  std::vector<std::uint64_t> waits_done;
  Cpu cpu(c, Cpu::Program{recording_isr(isr_entries), [&](BusPort& b) {
                            b.idle(100);
                            waits_done.push_back(b.cycle());
                          }});
  cpu.run_until(200);
  EXPECT_EQ(isr_entries, (std::vector<std::uint64_t>{8}));
  // The ISR (8..12) runs within the first wait, which still ends 100 clocks after it began.
  EXPECT_EQ(waits_done, (std::vector<std::uint64_t>{108}));
  EXPECT_EQ(c.cycle(), 200u);
}

TEST(HostCpu, AnExceptionHaltsTheMainLoopAndOnlyTheChipRunsOn) {
  Chip c({Profile::dpc31, BusMode::intel, 0});
  c.set_log_sink(nullptr);
  int passes = 0;
  Cpu cpu(c, Cpu::Program{{}, [&](BusPort& b) {
                            b.read(kRam);
                            if (++passes == 3) throw std::runtime_error("fatal");
                          }});
  EXPECT_THROW(cpu.run_until(1000), std::runtime_error);
  EXPECT_EQ(c.cycle(), 2 * kPass + 4);  // the third pass's read
  cpu.run_until(1000);
  EXPECT_EQ(passes, 3);
  EXPECT_EQ(c.cycle(), 1000u);
}

// A firmware of dpc31_firmware.h that uses every board hook (C functions, as a plug-in's).
namespace hooks_fw {
void init(const dpc31_board* /*board*/) {
  dpc31_board_reset(1);  // the chip is in its reset state: nothing to do
  dpc31_board_wait_1ms();
  dpc31_board_reset(0);
  dpc31_board_int_enable(0);
}
void step() { dpc31_board_reset(1); }  // a reset of the started chip
const std::uint8_t kCfg[] = {0x10};
const dpc31_firmware kFw = {DPC31_FIRMWARE_ABI_VERSION,
                            "HOOKS",
                            nullptr,
                            nullptr,
                            init,
                            nullptr,
                            step,
                            nullptr,
                            nullptr,
                            0x0001,
                            kCfg,
                            1,
                            1,
                            0,
                            nullptr,
                            0};
}  // namespace hooks_fw

TEST(BoardHooks, WaitResetAndInterruptInputActOnTheHost) {
  Chip c({Profile::dpc31, BusMode::intel, 0});
  c.set_log_sink(nullptr);
  DirectBus bus(c);
  FirmwareHost host(hooks_fw::kFw);
  ASSERT_TRUE(host.interrupts_enabled());  // enabled when the firmware starts
  host.init(bus, 5);
  EXPECT_EQ(c.cycle(), 48'000u);  // Vpc3Wait_1ms: clock / 1000 clocks at 48 MHz
  EXPECT_FALSE(host.interrupts_enabled());
  const std::uint64_t s = testutil::user_start(c);  // MAC_Start
  ASSERT_TRUE(c.started());
  Cpu cpu(c, host.program());
  try {
    cpu.run_until(c.cycle() + 100);
    FAIL() << "no error";
  } catch (const FirmwareError& e) {
    EXPECT_EQ(std::string(e.what()),
              fmt::format("firmware HOOKS: reset line asserted at cycle {} after the chip was "
                          "started (a reset during operation is not modelled)",
                          s));
  }
}

// The C host (dpc31_module_*): a firmware's misuse of the C HAL, in init (on the caller's stack)
// or in its ISR (on the host CPU's), is the module's error with the HAL's message, not an abort.
TEST(FirmwareModule, HalMisuseIsTheModulesError) {
  const std::pair<const char*, const char*> plugins[] = {
      {BAD_PLUGIN_HAL_INIT, "firmware BAD: CopyToVpc3: local buffer is NULL with length 4"},
      {BAD_PLUGIN_HAL_ISR, "firmware BAD: CopyFromVpc3: local buffer is NULL with length 2"},
      {BAD_PLUGIN_HAL_SWAP,
       "firmware BAD: CopyToVpc3: chip pointer 0x12345678 is not a chip address (0x0000..0xFFFF): "
       "the arguments swapped?"},
  };
  for (const auto& [lib, line] : plugins) {
    char err[256] = "";
    const dpc31_firmware* fw = dpc31_firmware_load(lib, err, sizeof err);
    ASSERT_NE(fw, nullptr) << err;
    dpc31_module* m = dpc31_module_create("vpc3plus", 0, fw, 5);
    ASSERT_NE(m, nullptr);
    EXPECT_EQ(dpc31_module_run(m, 48'000), -1) << lib;
    EXPECT_STREQ(dpc31_module_error(m), line);
    dpc31_module_destroy(m);
  }
}

// s33 audit finding 10: a NULL or empty path was taken as the current directory ("./: is a
// directory"): the one-line reason (dpc31_firmware.h) names the argument instead.
TEST(FirmwareModule, LoadWithNoPathSaysSo) {
  char err[128] = "";
  EXPECT_EQ(dpc31_firmware_load(nullptr, err, sizeof err), nullptr);
  EXPECT_STREQ(err, "cannot load firmware plug-in: no path given (NULL)");
  EXPECT_EQ(dpc31_firmware_load("", err, sizeof err), nullptr);
  EXPECT_STREQ(err, "cannot load firmware plug-in: no path given (an empty string)");
}

// A fresh start per module: a plug-in's globals are what its file gives them in every module,
// one after the other and side by side (the library copy of a module before was reused, globals
// and all: boots 1, 2, 3).
TEST(FirmwareModule, EveryModuleStartsWithTheGlobalsOfTheFile) {
  char err[256] = "";
  const dpc31_firmware* fw = dpc31_firmware_load(BAD_PLUGIN_GLOBALS, err, sizeof err);
  ASSERT_NE(fw, nullptr) << err;
  for (int i = 0; i < 3; ++i) {
    dpc31_module* m = dpc31_module_create("vpc3plus", 0, fw, 5);
    ASSERT_NE(m, nullptr);
    EXPECT_EQ(dpc31_module_port(m, "boots"), 1) << "module " << i;
    dpc31_module_destroy(m);
  }
  dpc31_module* a = dpc31_module_create("vpc3plus", 0, fw, 5);
  dpc31_module* b = dpc31_module_create("vpc3plus", 0, fw, 6);
  EXPECT_EQ(dpc31_module_port(a, "boots"), 1);
  EXPECT_EQ(dpc31_module_port(b, "boots"), 1);
  dpc31_module_destroy(a);
  dpc31_module_destroy(b);
}

// A copy that cannot be made makes dpc31_module_create return NULL, as dpc31_firmware.h says; it
// ended the process (std::terminate out of the C function: the review's `ulimit -n 6`). The copy
// fails here at its first write (a file-size limit of 0, SIGXFSZ ignored: EFBIG), the same throw
// as memfd_create's EMFILE; no descriptor limit, for a sanitizer's checks need descriptors of
// their own (UBSan's vptr check opens a pipe: CI's ASan suite, stop 49).
TEST(FirmwareModule, ACopyThatCannotBeMadeIsNull) {
  char err[256] = "";
  const dpc31_firmware* fw = dpc31_firmware_load(BAD_PLUGIN_GLOBALS, err, sizeof err);
  ASSERT_NE(fw, nullptr) << err;
  dpc31_module* a = dpc31_module_create("vpc3plus", 0, fw, 5);  // the library as loaded
  ASSERT_NE(a, nullptr);
  rlimit was{};
  ASSERT_EQ(::getrlimit(RLIMIT_FSIZE, &was), 0);
  rlimit none = was;
  none.rlim_cur = 0;
  const auto old_handler = ::signal(SIGXFSZ, SIG_IGN);
  ASSERT_EQ(::setrlimit(RLIMIT_FSIZE, &none), 0);
  dpc31_module* b = dpc31_module_create("vpc3plus", 0, fw, 6);
  ASSERT_EQ(::setrlimit(RLIMIT_FSIZE, &was), 0);
  ::signal(SIGXFSZ, old_handler);
  EXPECT_EQ(b, nullptr);
  dpc31_module_destroy(b);
  // With the limit back, the next module gets its copy.
  dpc31_module* c = dpc31_module_create("vpc3plus", 0, fw, 6);
  EXPECT_NE(c, nullptr);
  EXPECT_EQ(dpc31_module_port(c, "boots"), 1);
  dpc31_module_destroy(c);
  dpc31_module_destroy(a);
}

// A hardware input runs with no chip selected: a chip access from it is a firmware fault whose
// message says so in a plug-in's terms (a plug-in does not call dpc31_select).
TEST(FirmwareModule, AChipAccessFromAHardwareInputSaysItRunsWithNoChip) {
  FirmwareHost host(find_firmware(BAD_PLUGIN_HAL_ISR));
  try {
    (void)host.hw_input("kick", 1);
    FAIL() << "no error";
  } catch (const FirmwareError& e) {
    EXPECT_EQ(std::string(e.what()),
              "firmware BAD: Vpc3Read called with no chip selected (hw_input runs with no chip "
              "selected: it notes the input for the ISR or the main loop)");
  }
}

namespace init_fw {
// init polls the chip for 600 ms of host time (a driver waiting for a register): each access is
// progress, so the hang guard leaves it alone.
void poll(const dpc31_board*) {
  const auto end = std::chrono::steady_clock::now() + std::chrono::milliseconds(600);
  while (std::chrono::steady_clock::now() < end) (void)Vpc3Read(SPC3_Int_Reg);
}
// init waits 5 ms with User_Timer_Clock (1 ms) unmasked on a started chip: its ISR is served in
// the waits, as on the host CPU (Vpc3Wait_1ms).
unsigned g_isrs = 0;
void isr() {
  Vpc3Write(SPC3_Int_Ack_Reg, Vpc3Read(SPC3_Int_Reg));
  Vpc3Write(SPC3_Mode_Reg1_S, 0x02);  // EOI
  ++g_isrs;
}
void wait(const dpc31_board*) {
  Vpc3Write(SPC3_Int_Mask_Reg, static_cast<std::uint8_t>(~SPC3_Int_Req_Reg_User_Timer_Clock_Msk));
  Vpc3Write(SPC3_Int_Mask_Reg + 1, 0xFF);
  Vpc3Write(SPC3_Mode_Reg1_S, 0x01);  // Start
  for (int i = 0; i < 5; ++i) dpc31_board_wait_1ms();
  dpc31_port_write(0, g_isrs);
}
void step() {}
const std::uint8_t kCfg[] = {0x10};
const char* const kPorts[] = {"isrs", nullptr};
constexpr dpc31_firmware descriptor(const char* name, void (*init)(const dpc31_board*)) {
  return {DPC31_FIRMWARE_ABI_VERSION,
          name,
          nullptr,
          kPorts,
          init,
          isr,
          step,
          nullptr,
          nullptr,
          0x0001,
          kCfg,
          1,
          0,
          1,
          nullptr,
          0};
}
const dpc31_firmware kPoll = descriptor("POLL", poll);
const dpc31_firmware kWait = descriptor("WAIT", wait);
}  // namespace init_fw

TEST(FirmwareInit, AnInitPollingTheChipIsNoHang) {
  EXPECT_EXIT(
      {
        board::guard_hangs("test", "POLL", {}, std::chrono::milliseconds(100));
        Chip c({Profile::spc3, BusMode::intel, 0});
        DirectBus bus(c);
        FirmwareHost host(init_fw::kPoll);
        host.init(bus, 5);
        std::exit(0);
      },
      ::testing::ExitedWithCode(0), "");
}

TEST(FirmwareInit, WaitsInInitServeTheEnabledInterrupt) {
  Chip c({Profile::spc3, BusMode::intel, 0});
  DirectBus bus(c);
  FirmwareHost host(init_fw::kWait);
  host.init(bus, 5);
  // One per User_Timer_Clock tick inside the 5 ms, none merged into one latched bit (it was 0):
  // the ticks 1 ... 4 ms after Start; the fifth comes after the last wait has ended.
  EXPECT_EQ(host.port("isrs"), 4);
  EXPECT_EQ(host.interrupts.size(), 4u);
}

}  // namespace

// firmware.h: "NULL if there is none": a NULL name finds none, as an unknown one (it crashed).
TEST(FirmwareRegistry, ANullOrUnknownNameFindsNone) {
  EXPECT_EQ(dpc31_find_firmware(nullptr), nullptr);
  EXPECT_EQ(dpc31_find_firmware("no such firmware"), nullptr);
  ASSERT_NE(dpc31_find_firmware("do4"), nullptr);
  EXPECT_EQ(dpc31_find_firmware("do4"), dpc31_find_firmware("DO4"));
}

// s33 review finding 2: the fatal-signal handler is inherited by a forked child (util/child: a
// traced RTL model dies of SIGBUS on a full disk by design), which removed the parent's
// temporaries. Only the process that set the guard removes them (docs/bad-input.md: the JUnit of
// the seeds that ran is kept). Run in a freshly started process of its own (the guard is set
// once per process, and other tests here set it).
TEST(BoardGuardDeathTest, AForkedChildsCrashLeavesTheParentsFiles) {
  GTEST_FLAG_SET(death_test_style, "threadsafe");
  const std::string kept = ::testing::TempDir() + "dpc31_guard_kept";
  EXPECT_EXIT(
      {
        std::FILE* f = std::fopen(kept.c_str(), "w");
        if (f == nullptr) std::_Exit(3);
        std::fclose(f);
        dpc31::board::guard_hangs("guard", "X", kept, std::chrono::milliseconds(60000), -1);
        const pid_t child = ::fork();
        if (child == 0) std::raise(SIGBUS);
        int st = 0;
        ::waitpid(child, &st, 0);
        const bool ok =
            WIFSIGNALED(st) && WTERMSIG(st) == SIGBUS && ::access(kept.c_str(), F_OK) == 0;
        std::remove(kept.c_str());
        std::_Exit(ok ? 0 : 1);
      },
      ::testing::ExitedWithCode(0), "");
}
