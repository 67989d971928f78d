// The names the session layer and the tools print and read, in one place: DP and watchdog
// states, the FDL counters, DP services and FDL responses of a telegram, UART faults. The walk
// of a scenario, the trace files, the bridge's log and the serve protocol all use these.
#pragma once

#include <cstddef>
#include <cstdint>
#include <span>
#include <string>
#include <string_view>
#include <vector>

#include "dpc31/chip.hpp"
#include "dpc31/dp.hpp"
#include "dpc31/fdl.hpp"
#include "dpc31/fdl_counters.hpp"
#include "dpc31/pdu.hpp"
#include "dpc31/uart.hpp"
#include "responder_dpv1.hpp"

namespace dpc31 {

std::string_view dp_state_name(DpState s);
std::string_view wd_state_name(WdState s);

// The FdlCounters fields by name, in declaration order (expect counter, JSON summaries).
std::span<const CounterField> fdl_counter_fields();
// The counters that are not 0, "name:N,name:N", or "-" (a trace's `state ... fdl=`).
std::string counters_text(const FdlCounters& c);

// The DP service a request asks for ("Set_Prm", "Data_Exchange", "MSAC_C1", "SAP 12", ...): a
// SAP of include/dpc31/dp.hpp by the name every decoder gives it (tests/decoder_sap_names.py).
std::string service_name(const fdl::Frame& request);
// Where a scenario's firmware runs, for the lines of its fault and its hang (`dpc31 run`, `dpc31
// cosim --session`, Python's FirmwareError): "FILE:LINE" at the `firmware` line while a single
// chip's init runs, "FILE" (line 0) while a segment's stations start, then "FILE:LINE: KEYWORD"
// of the step it runs in (the step's first word: "x.scn:10: dpv1_read"); the default one is
// nowhere (the demo's own session has no file). The runner calls enter() as each step begins.
// It holds copies, not pointers into the scenario: the steps are gone once a fault has unwound
// the run (a pointer version crashed Python).
class FirmwarePlace {
 public:
  FirmwarePlace() = default;
  FirmwarePlace(std::string file, int line);
  void enter(int line, std::string_view step_text);

  // The place's text ("" nowhere): board::HangPlace keeps its address while the firmware runs.
  [[nodiscard]] const std::string& text() const { return text_; }
  [[nodiscard]] const std::string& file() const { return file_; }
  [[nodiscard]] int line() const { return line_; }                 // 0: none
  [[nodiscard]] const std::string& step() const { return step_; }  // "": before the first step
  // The fault's line: "PLACE: WHAT", WHAT alone where the place is nowhere.
  [[nodiscard]] std::string message(std::string_view what) const;

 private:
  std::string file_;
  int line_ = 0;
  std::string step_;
  std::string text_;
};
// An FDL request function: "SRD_high", "SDN_low", "FDL_Status", ...
std::string_view function_name(fdl::Function f);
// An FDL response code: "OK", "DL", "RS", ...
std::string_view response_name(fdl::Response r);
// A UART fault as the walk tells it ("parity error") and as trace files write it ("parity").
std::string_view fault_name(UartFault::Kind k);
std::string_view fault_kind_name(UartFault::Kind k);
// The kind named by fault_kind_name ("parity", "start", "stop"); false for any other name.
bool parse_fault_kind(std::string_view name, UartFault::Kind& kind);
// Puts a fault into a telegram of `chars` characters, as a scenario's `corrupt` and Python's
// fault= mean it: no character named (char_index < 0) is the last one (the ED). "" when the
// fault has its character (or there is no fault), else why not, the index named `what`.
[[nodiscard]] std::string place_fault(UartFault& f, std::size_t chars, std::string_view what);
// A master's or sender's telegram: place_fault's refusal as std::invalid_argument (nothing sent).
void place_fault(UartFault& f, std::size_t chars);

// A number a scenario line and the Python module both take, with its range and its name in the
// scenario parser's words (docs/scenario-format.md), so that both doors refuse it alike.
struct ValueRange {
  std::string_view what;
  std::uint64_t min;
  std::uint64_t max;
  [[nodiscard]] constexpr bool holds(std::uint64_t v) const { return v >= min && v <= max; }
};
inline constexpr ValueRange kStationAddress{"station address", 0, 125};
inline constexpr ValueRange kSlaveAddress{"slave address", 0, 125};
inline constexpr ValueRange kMasterAddress{"master address", 0, 126};
inline constexpr ValueRange kWdFactor1{"wd factor 1", 1, 255};
inline constexpr ValueRange kWdFactor2{"wd factor 2", 1, 255};
// The slave's parameters beside them (`slave` and `set_prm` options, Python's SlaveConfig).
inline constexpr ValueRange kIdent{"ident", 0, 0xFFFF};
inline constexpr ValueRange kGroupIdent{"group", 0, 255};
inline constexpr ValueRange kMinTsdr{"min_tsdr", 0, 255};
inline constexpr ValueRange kInLen{"in", 0, fdl::kMaxDpData};
inline constexpr ValueRange kOutLen{"out", 0, fdl::kMaxDpData};
// Set_Slave_Add's new address (`set_slave_address`): 126 is the default of an unset slave.
inline constexpr ValueRange kNewAddress{"new address", 0, 126};
// An 80C32 board's (or the C31's) clock in Hz (`cpu ... clock=`).
inline constexpr ValueRange kCpuClock{"clock", 1'000'000, 40'000'000};
// The master's slot and idle times in bit times (a single chip's `master slot= idle=`). The slot
// time has the range of a segment's `segment slot=`: the bus parameter TSL's in EN 50170 part 2.
inline constexpr ValueRange kSlotBits{"slot", 37, 16383};
inline constexpr ValueRange kIdleBits{"idle", 1, 65535};
// A start-up's or restart's attempts (`startup tries=`, Python's startup / restart / startup_all).
inline constexpr ValueRange kTries{"tries", 1, 100'000};
// The token rules of a segment's master (TTR, the GAP factor, HSA: the ranges of the bus
// parameters in EN 50170 part 2).
inline constexpr ValueRange kTtrBits{"ttr", 256, 16'777'215};
inline constexpr ValueRange kGapFactor{"gap", 1, 100};
inline constexpr ValueRange kHsa{"hsa", 1, 126};
// The built-in master's DPV1 rules (`dpv1 c1_timeout= c2_ssap=`, `master retries=`) and its
// DPV1 services' numbers (docs/dpv1.md): C2_SSAP below the SAPs 63 (the default SAP) and up.
inline constexpr ValueRange kRetries{"retries", 0, 8};
inline constexpr ValueRange kC1Timeout{"c1_timeout", 1, 65535};
inline constexpr ValueRange kC2Ssap{"c2_ssap", 0, 62};
inline constexpr ValueRange kRecordSlot{"slot", 0, 254};
inline constexpr ValueRange kRecordIndex{"index", 0, 255};
inline constexpr ValueRange kRecordLength{"length", 1, 240};  // a record's data, at most 240
inline constexpr ValueRange kAlarmType{"type", 1, 127};
inline constexpr ValueRange kAlarmSpec{"spec", 0, 3};  // the Specifier's bits 1..0
// Alarm_Ack's SAP at the slave: "SAP 50 or 51" (manual-quotes.md, "DPV1"), `alarm_ack sap=`.
inline constexpr ValueRange kAlarmSap{"sap", sap::MSAC_C1_Alarm, sap::MSAC_C1};
// The built-in user side's work per DPV1 request in clocks (`dpv1 work=`, Python's
// run_responder(work_cycles=)), one range for both doors: at most 1 s at 48 MHz.
inline constexpr ValueRange kWorkCycles{"work", 0, 48'000'000};
// The built-in user side's R_User_WD_Value and WD_Baud_Control_Val (x 10 ms): the `user` step's
// `user_wd_value=` and `wd_baud_control=`, a segment `station`'s `user_wd_value=`, Python's
// run_responder(user_wd_value=, wd_baud_control=).
inline constexpr ValueRange kUserWdValue{"user_wd_value", 0, 0xFFFF};
inline constexpr ValueRange kWdBaudControl{"wd_baud_control", 0, 255};
inline constexpr ValueRange kSendTimeout{"send_timeout", 1, 65535};
// An Initiate's Add_Addr_Param (`c2_initiate s_type= s_addr= d_type= d_addr=`, Python's
// c2_initiate()): a Type is one byte; S_Addr and D_Addr together (a Type 1 address: API, SCL,
// Network_Address and MAC_Address) at most what the built-in user side's resource-manager buffer
// (Max_Length 32, as public slave stacks have it) holds past the request's 16 fixed bytes: 16.
inline constexpr ValueRange kAddrType{"type", 0, 255};
inline constexpr std::size_t kAddrMax = Dpv1User::kRmMax - pdu::kInitiateReqFixed;
// The refusal of a pair of addresses longer than kAddrMax together ("" when they fit).
std::string addresses_too_long(std::size_t s_len, std::size_t d_len);
inline constexpr ValueRange kAbortReason{"reason", 0, 15};
inline constexpr ValueRange kAbortInstance{"instance", 0, 3};  // 0 FDL, 1 MSAC_C2, 2 user
// An 80C32 board's XDATA window for the chip (`cpu base=`): its 4 KB below the top of XDATA.
inline constexpr ValueRange kBoardBase{"base", 0, 0xF000};
// The C31's code area (`cpu c31 code=`): in the DPC31's RAM, its user area (docs/dpc31.md).
inline constexpr ValueRange kC31Code{"code", 0x08A0, 0x1FFF};
// "(MIN..MAX)" in the base `value` is written in: 0x hex (as many digits as MAX has) or decimal.
[[nodiscard]] std::string range_text(std::uint64_t min, std::uint64_t max, std::string_view value);
// "WHAT VALUE out of range (MIN..MAX)", VALUE as the user wrote it, the range in its base.
[[nodiscard]] std::string out_of_range(const ValueRange& r, std::string_view value);
// "WHAT VALUE is out of range (MIN..MAX)": `dpc31 serve`'s words for a command's number (ERR
// range), which the Python module's Chip gives for the same calls.
[[nodiscard]] std::string range_error_text(std::string_view what, std::string_view value,
                                           std::uint64_t min, std::uint64_t max);
// A register some profile has (by name or alias): another profile's register is no typo but has
// no address on this chip (serve's `addr`: ERR no_address; Python's Chip.addr_of: None).
[[nodiscard]] bool any_profile_has(std::string_view register_name);
// The ten PROFIBUS rates the chips' baud search knows, slowest first: "9600, 19200, ..., 12000000".
[[nodiscard]] std::string profibus_rates();
// "" for one of them, else why not: "baud 12345 is not a PROFIBUS rate (9600, ...)".
[[nodiscard]] std::string not_a_profibus_rate(std::uint64_t baud);
// The same for a rate as an option gives it, read as every door reads a whole number (decimal,
// or 0x hex): "" with its number in `baud`, else why not, the text as written ("'1.5e6' is not a
// PROFIBUS rate (9600, ...)").
[[nodiscard]] std::string not_a_profibus_rate(std::string_view text, std::uint32_t& baud);
// "" for a master's hsa= it may take (beside a gap=, not below its own address), else why not.
[[nodiscard]] std::string hsa_refused(std::uint8_t hsa, std::uint8_t gap_factor,
                                      std::uint8_t address);
// A segment's station names (a chip's, a sender's, a master's) are its scopes in the waveforms
// and name it in the log, in collisions and in `send from=`: each is one station's. A built-in
// master's sender is "master ADDR"; a name taken is "a second station named 'NAME'".
[[nodiscard]] std::string master_station_name(std::uint8_t address);
[[nodiscard]] std::string second_station_named(std::string_view name);
// A chip station's scope in a segment's waveform: station5 (the address), station5_spc3 when its
// name is not the default "station 5" (other characters than letters and digits made '_').
[[nodiscard]] std::string station_scope(std::uint8_t address, std::string_view name);
// Two chip stations whose names differ only where the scope has '_' (`a/b`, `a_b` at one address)
// would share one scope and one --record file: the second is refused as a second name is, "a
// second station named 'a_b' in the waveform scope of 'a/b' (station5_a_b)".
[[nodiscard]] std::string second_station_in_scope(std::string_view name, std::string_view first,
                                                  std::string_view scope);
// A master is a station too: none shares its address with a chip station (two chips may: they
// collide). The refusal of the one that came second: "master 5 at the address of station 5",
// "station 5 at the address of master 5".
[[nodiscard]] std::string master_at_station(std::uint8_t address);
[[nodiscard]] std::string station_at_master(std::uint8_t address);
// A station's name is at most this many bytes: it is the station's scope in the waveforms (beside
// "stationADDR_") and names its --record file (FILE.stationADDR_NAME.trace: a file name is at most
// 255 bytes on Linux), its log lines and its packets' comments in a capture.
inline constexpr std::size_t kMaxStationName = 64;
// "" for a name WHOSE ("station 5", "a sender") may have, else why not: "empty name for WHOSE", "a
// name of 65 bytes for WHOSE: at most 64", "the name for WHOSE has a control character, byte 1Bh
// at offset 0".
[[nodiscard]] std::string station_name_refused(std::string_view name, std::string_view whose);
// A name shown in logs and walks, one entry a line, holds no control character (below 20h, 7Fh):
// "" or which one, "byte 0Ah at offset 3" (a newline would forge a line of its own).
[[nodiscard]] std::string control_character_in(std::string_view name);
// The options of the DPC31 alone, refused on the other profiles (No silent options), `option` as
// the door writes it (a scenario's "user substitute=", Python's "substitute="): "OPTION is for
// profile dpc31: only the DPC31 has ...".
[[nodiscard]] std::string substitute_is_for_dpc31(std::string_view option);
[[nodiscard]] std::string dx_out_port_is_for_dpc31(std::string_view option);
// A single chip's master and its slave at one address (a scenario's `master address=` and `slave
// address=`, Python's Master(address=, slave=)): two stations at one address are no PROFIBUS.
[[nodiscard]] std::string master_and_slave_at(std::uint8_t address);
// The VPC3+ takes WD_Base from Set_Prm's DPV1_Status_1 only with DPV1_Enable; without it
// Mode_Reg0.WD_Base decides (VPC3+C p.53, docs/dpv1.md): a watchdog base asked of Set_Prm there.
[[nodiscard]] std::string wd_base_needs_dpv1(std::string_view option);
// wd_base=10ms beside a user_prm byte 0 with bit 2 (the 1 ms base): both are Set_Prm byte 7 bit 2.
[[nodiscard]] std::string wd_base_contradicts_user_prm();
// The built-in user side's records are served through the VPC3+'s SAP list, which only a Set_Prm
// with DPV1_Enable switches on: "" for a slave `user_prm` with it, else why records (`option`:
// "record", "records=") are refused.
[[nodiscard]] std::string records_need_dpv1(std::string_view option,
                                            const std::vector<std::uint8_t>& user_prm);

}  // namespace dpc31
