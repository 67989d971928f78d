// Telegram captures: pcapng files (draft-ietf-opsawg-pcapng) of what the chip received and sent
// on its serial line, one Enhanced Packet Block per telegram, SD to ED, link type 257
// (LINKTYPE_PROFIBUS_DL), nanosecond timestamps derived from chip cycles (docs/capture.md).
// lib/capture/profibus_dl.lua dissects them in Wireshark / tshark.
//
// The file is written to a temporary next to the target and renamed over it by close(): a reader,
// or a crash, never sees half a capture. The first error (cannot create, disk full, timestamp out
// of range) is kept; every later call fails with it and close() reports it.
#pragma once

#include <cstddef>
#include <cstdint>
#include <memory>
#include <optional>
#include <span>
#include <string>
#include <vector>

#include "dpc31/chip.hpp"

namespace dpc31::capture {

inline constexpr std::uint16_t kLinkTypeProfibusDl = 257;  // LINKTYPE_PROFIBUS_DL
inline constexpr std::uint8_t kTsresolNanoseconds = 9;     // if_tsresol: 10^-9 s per unit

// epb_flags bits 1:0. Inbound: the chip received it (from the master, on RxD); outbound: the chip
// sent it (on TxD).
enum class Direction : std::uint8_t { unknown = 0, inbound = 1, outbound = 2 };

// Nanoseconds of `cycle` chip clocks at `clock_hz`: cycle * 10^9 / clock_hz rounded to the nearest
// integer, halves up, computed exactly in 64-bit integers. nullopt if clock_hz is 0 or the result
// exceeds 2^64 - 1 ns (about 584 years of simulated time).
[[nodiscard]] std::optional<std::uint64_t> cycles_to_ns(std::uint64_t cycle,
                                                        std::uint32_t clock_hz);

struct Packet {
  std::uint64_t timestamp_ns = 0;  // since the epoch of the file (cycle 0 = 1970-01-01 UTC)
  Direction direction = Direction::unknown;
  std::span<const std::uint8_t> bytes;  // SD to ED, as on the wire
  std::string comment;                  // opt_comment; "" = none
  // epb_flags bit 31 (symbol error): a character read with a parity, start or stop bit error
  // (bytes that read well are still no telegram: a receiver discards it).
  bool symbol_error = false;
};

struct WriterOptions {
  std::string application = "dpc31emu";  // shb_userappl; "" = omitted
  std::string interface_name = "dpc31";  // if_name; "" = omitted
  bool cycle_comments = true;            // telegrams get opt_comment "cycles START-END"
};

// A text option (shb_userappl, if_name, opt_comment) is at most this many bytes: its length is
// 16 bits. A longer one is refused, never cut: the encoders throw std::length_error ("opt_comment
// of 65536 bytes: a pcapng option holds at most 65535"), open() and add() fail with it.
inline constexpr std::size_t kMaxOptionBytes = 0xFFFF;

// The blocks as written (little-endian sections), for tests and other writers.
[[nodiscard]] std::vector<std::uint8_t> section_header_block(const WriterOptions& opt);
[[nodiscard]] std::vector<std::uint8_t> interface_description_block(const WriterOptions& opt);
[[nodiscard]] std::vector<std::uint8_t> enhanced_packet_block(const Packet& p);
// A telegram as a packet: start cycle as the timestamp, from_chip -> outbound, the comment per
// `cycle_comments`. nullopt where cycles_to_ns fails.
[[nodiscard]] std::optional<Packet> telegram_packet(const Telegram& t, std::uint32_t clock_hz,
                                                    bool cycle_comments);

class PcapngWriter {
 public:
  explicit PcapngWriter(WriterOptions opt = {});
  // A capture that was opened but not closed is discarded: the temporary file is removed, the
  // target left as it was.
  ~PcapngWriter();
  PcapngWriter(const PcapngWriter&) = delete;
  PcapngWriter& operator=(const PcapngWriter&) = delete;

  // Creates the temporary file (`path` + ".<pid>.tmp") and writes the section header and the
  // interface description. False with error() set; the target is not touched. A capture still
  // open is discarded first.
  bool open(const std::string& path);
  // False with error() set (not open, an earlier error, a write failure).
  bool add(const Packet& p);
  bool add(const Telegram& t, std::uint32_t clock_hz);
  // Records every telegram of `chip` from now on (Chip::on_telegram, at the chip's clock), in the
  // order of their first start bits: the chip's answers are held until a received telegram that
  // starts later, or close(). Safe when the writer goes first: the observer then does nothing;
  // telegrams after close() are ignored. Errors are kept for close().
  void attach(Chip& chip);
  // Flushes, syncs and renames the temporary over the target. False with error() set if anything
  // failed since open(); the temporary is then removed and the target left as it was.
  bool close();
  // Drops the capture: removes the temporary, leaves the target as it was.
  void discard();

  [[nodiscard]] bool is_open() const;
  // The first error since open(), "" if none: one line, naming the file and the reason.
  [[nodiscard]] const std::string& error() const;
  [[nodiscard]] std::uint64_t packets() const;  // packets written since open()

 private:
  struct State;
  std::shared_ptr<State> state_;
};

}  // namespace dpc31::capture
