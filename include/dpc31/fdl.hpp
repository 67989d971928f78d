// PROFIBUS FDL telegrams (chip-facts §8): encode/decode of SD1/SD2/SD3/SD4/SC frames and an
// incremental assembler for a receiver that sees one UART character at a time. Pure: no chip
// state, no timing. Names follow IEC 61158 / the DP standard.
#pragma once

#include <array>
#include <cstddef>
#include <cstdint>
#include <optional>
#include <span>
#include <string>
#include <string_view>
#include <vector>

// Snapshots of the chip's internal state (emu/snapshot.hpp) save and load these through:
namespace dpc31::snap {
class Writer;
class Reader;
}  // namespace dpc31::snap

namespace dpc31::fdl {

// Start delimiters, short acknowledge, end delimiter.
inline constexpr std::uint8_t SD1 = 0x10;  // no data field
inline constexpr std::uint8_t SD2 = 0x68;  // variable data field, LE LEr
inline constexpr std::uint8_t SD3 = 0xA2;  // fixed 8-byte data field
inline constexpr std::uint8_t SD4 = 0xDC;  // token
inline constexpr std::uint8_t SC = 0xE5;   // short acknowledge
inline constexpr std::uint8_t ED = 0x16;

inline constexpr std::uint8_t kBroadcast = 127;
inline constexpr std::uint8_t kAddressMask = 0x7F;
// In DA/SA: a DSAP/SSAP byte is present. In a SAP byte: a further extension (unsupported).
inline constexpr std::uint8_t kExtension = 0x80;
inline constexpr std::uint8_t kSapSegment = 0x40;
inline constexpr std::uint8_t kSapMask = 0x3F;

// SD2 LE counts DA..last DU byte: DA SA FC + 1..246 DU bytes (SAP bytes included).
inline constexpr std::size_t kMinLe = 4;
inline constexpr std::size_t kMaxLe = 249;
// Longest frame: SD2 with LE = 249 plus SD LE LEr SD FCS ED.
inline constexpr std::size_t kMaxFrameLength = kMaxLe + 6;
inline constexpr std::size_t kSd3DataLength = 8;
// DP's data in one telegram: the SD2's 246 DU bytes less the two SAP bytes (DP's services use
// both; Data_Exchange's outputs and inputs keep the same limit).
inline constexpr std::size_t kMaxDpData = 244;

// FC bits 3..0 of a request (FC bit 6 = 1).
enum class Function : std::uint8_t {
  SDA_low = 0x3,
  SDN_low = 0x4,
  SDA_high = 0x5,
  SDN_high = 0x6,
  DDB = 0x7,
  FDL_Status = 0x9,
  SRD_low = 0xC,
  SRD_high = 0xD,
  Ident = 0xE,
  LSAP_Status = 0xF,
};

// FC bits 3..0 of a response / acknowledge (FC bit 6 = 0).
enum class Response : std::uint8_t {
  OK = 0x0,
  UE = 0x1,   // user error
  RR = 0x2,   // no resource
  RS = 0x3,   // no service activated (SAP)
  DL = 0x8,   // response data low
  NR = 0x9,   // no response data
  DH = 0xA,   // response data high
  RDL = 0xC,  // not received, data low
  RDH = 0xD,  // not received, data high
};

inline constexpr std::uint8_t kFcRequest = 0x40;
inline constexpr std::uint8_t kFcFcb = 0x20;
inline constexpr std::uint8_t kFcFcv = 0x10;
inline constexpr std::uint8_t kFcCodeMask = 0x0F;

[[nodiscard]] constexpr std::uint8_t make_request_fc(Function f, bool fcb, bool fcv) {
  return static_cast<std::uint8_t>(kFcRequest | (fcb ? kFcFcb : 0) | (fcv ? kFcFcv : 0) |
                                   static_cast<std::uint8_t>(f));
}
// station_type: 0 slave, 1 master not ready, 2 master ready, 3 master in ring.
[[nodiscard]] constexpr std::uint8_t make_response_fc(Response r, std::uint8_t station_type = 0) {
  return static_cast<std::uint8_t>((station_type & 0x3) << 4 | static_cast<std::uint8_t>(r));
}
[[nodiscard]] constexpr bool is_request(std::uint8_t fc) { return (fc & kFcRequest) != 0; }
// May yield a value outside the named enumerators (reserved codes): callers must handle it.
[[nodiscard]] constexpr Function request_function(std::uint8_t fc) {
  return static_cast<Function>(fc & kFcCodeMask);
}
[[nodiscard]] constexpr Response response_code(std::uint8_t fc) {
  return static_cast<Response>(fc & kFcCodeMask);
}
[[nodiscard]] constexpr std::uint8_t station_type(std::uint8_t fc) { return (fc >> 4) & 0x3; }
[[nodiscard]] constexpr bool fcb(std::uint8_t fc) { return (fc & kFcFcb) != 0; }
[[nodiscard]] constexpr bool fcv(std::uint8_t fc) { return (fc & kFcFcv) != 0; }

// SAP number and segment flag of a DSAP/SSAP byte.
[[nodiscard]] constexpr std::uint8_t sap_number(std::uint8_t sap) { return sap & kSapMask; }
[[nodiscard]] constexpr bool sap_segment(std::uint8_t sap) { return (sap & kSapSegment) != 0; }

// da/sa are 7-bit station addresses (extension bit stripped); dsap/ssap are the address
// extension bytes as sent (bit 6 segment, bits 5..0 SAP; bit 7 always 0); du excludes them.
// SD4: fc = 0, no SAPs, du empty. SC: only sd is meaningful, the rest is zero/empty.
struct Frame {
  std::uint8_t sd = SD1;
  std::uint8_t da = 0;
  std::uint8_t sa = 0;
  std::uint8_t fc = 0;
  std::optional<std::uint8_t> dsap;
  std::optional<std::uint8_t> ssap;
  std::vector<std::uint8_t> du;

  friend bool operator==(const Frame&, const Frame&) = default;
};

// SD1 when there is neither data nor a SAP, else SD2 (SD3 is never chosen: build it by hand).
[[nodiscard]] Frame make_frame(std::uint8_t da, std::uint8_t sa, std::uint8_t fc,
                               std::vector<std::uint8_t> du = {},
                               std::optional<std::uint8_t> dsap = std::nullopt,
                               std::optional<std::uint8_t> ssap = std::nullopt);
[[nodiscard]] Frame sc();
[[nodiscard]] Frame token(std::uint8_t da, std::uint8_t sa);

// Sum mod 256 of DA..last DU byte (the bytes as sent, extension bits and SAP bytes included).
[[nodiscard]] std::uint8_t fcs(std::span<const std::uint8_t> bytes);

// Uses frame.sd as given and sets the DA/SA extension bits when dsap/ssap are present. Returns
// an empty vector when the frame cannot be sent as it stands (data or SAPs the SD has no room
// for, SD3 not exactly 8 bytes incl. SAPs, SD2 LE outside 4..249, address > 127, SAP byte with
// bit 7 set, unknown SD), so decode(encode(f)) == f for every non-empty result.
[[nodiscard]] std::vector<std::uint8_t> encode(const Frame& frame);
// The same into `out` (its old contents replaced, its capacity kept: a sender that encodes every
// request reuses one buffer). False, with `out` empty, where encode() gives an empty vector.
bool encode(const Frame& frame, std::vector<std::uint8_t>& out);
// Why encode() refuses `frame`: its first bad field by name with that field's range, in the
// frame's order (SD, DA, SA, the SAPs, the data unit). The one wording of every door (Python
// Frame.encode, serve inject_fdl, DpMaster); empty where encode() takes the frame.
[[nodiscard]] std::string encode_refusal(const Frame& frame);

enum class Error : std::uint8_t {
  none,
  bad_sd,       // unknown SD, or the SD2 repeated after LEr is not 68h
  truncated,    // fewer bytes than SD/LE say
  le_mismatch,  // LE != LEr
  bad_le,       // LE outside 4..249, or too short for the SAP bytes the extension bits announce
  bad_fcs,
  wrong_ed,
  oversize,  // more bytes than SD/LE say
  bad_sap,   // SAP byte with further extension, or an extension bit where no DU can carry it
};
[[nodiscard]] std::string_view error_name(Error e);

struct Decoded {
  Error error = Error::none;
  // Valid only for Error::none; otherwise holds what was parsed before the error (diagnostics).
  Frame frame;
  // As a default Decoded, its DU's capacity kept.
  void clear();
};

// bytes = exactly one (possibly broken) frame. Checks in this order, so that the contents of a
// broken frame are never interpreted: framing in byte order (SD, LE/LEr, SD repeat, length),
// then FCS, ED, then the address extension.
[[nodiscard]] Decoded decode(std::span<const std::uint8_t> bytes);
// The same into `out` (its old contents replaced, its DU's capacity kept).
void decode(std::span<const std::uint8_t> bytes, Decoded& out);

// Collects one frame character by character. The length is known from the SD (and LE for SD2),
// so the receiver sees the end of a frame without waiting for idle. Framing errors are reported
// as soon as the offending byte arrives (bad_sd, le_mismatch and bad_le at LEr, bad_sd at the
// repeated SD2); after `complete` the caller runs decode(bytes()) for FCS/ED/SAP checks. A push
// after complete is `oversize`. In the error state bytes are no longer stored until reset(), so
// the buffer never exceeds kMaxFrameLength. For any state except oversize, decode(bytes())
// reports the same error (truncated while need_more).
class Assembler {
 public:
  enum class Status : std::uint8_t { need_more, complete, error };

  Status push(std::uint8_t byte);
  // push() of the bytes in order up to the verdict (complete or error), a telegram's characters
  // taken at once: the framing checked where push() checks it, the bytes after that copied in one
  // go. Returns how many bytes it took (all of them while the frame needs more).
  std::size_t push_block(std::span<const std::uint8_t> bytes);
  // Total frame length in bytes; 0 until known (SD2: until a valid LEr has arrived).
  [[nodiscard]] std::size_t expected_length() const { return expected_; }
  [[nodiscard]] std::span<const std::uint8_t> bytes() const { return {buf_.data(), size_}; }
  [[nodiscard]] Status status() const { return status_; }
  [[nodiscard]] Error error() const { return error_; }
  void reset();

  // Snapshots (emu/snapshot.hpp): the bytes collected so far, length, status, error.
  void save_state(snap::Writer& w) const;
  void load_state(snap::Reader& r);

 private:
  Status fail(Error e);
  template <typename Ar, typename Self>
  static void fields(Ar& ar, Self& s);

  std::array<std::uint8_t, kMaxFrameLength> buf_{};
  std::size_t size_ = 0;
  std::size_t expected_ = 0;
  Status status_ = Status::need_more;
  Error error_ = Error::none;
};

}  // namespace dpc31::fdl
