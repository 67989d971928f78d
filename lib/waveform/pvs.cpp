#include "pvs.hpp"

#include <fmt/format.h>

#include <string_view>

namespace dpc31::wave {

namespace {

// A QByteArray as QSettings writes it to an INI file (qsettings.cpp, iniEscapedString of
// "@ByteArray(...)"): control bytes and bytes from 7Fh as \xNN, a hex digit right after such an
// escape (or after \0) escaped too, so that it is not read as part of it; the whole in quotes if
// it holds ';', ',' or '='.
std::string ini_byte_array(std::string_view bytes) {
  std::string out = "@ByteArray(";
  bool escape_next_if_digit = false;
  bool quotes = false;
  constexpr std::string_view kHexDigits = "0123456789abcdefABCDEF";
  constexpr std::string_view kNamed = "\a\b\f\n\r\t\v";
  constexpr std::string_view kNames = "abfnrtv";
  for (const char c : bytes) {
    const auto u = static_cast<unsigned char>(c);
    quotes = quotes || c == ';' || c == ',' || c == '=';
    if (escape_next_if_digit && kHexDigits.find(c) != std::string_view::npos) {
      out += fmt::format("\\x{:x}", u);
      continue;
    }
    escape_next_if_digit = false;
    if (u == 0) {
      out += "\\0";
      escape_next_if_digit = true;
    } else if (const auto named = kNamed.find(c); named != std::string_view::npos) {
      out += {'\\', kNames[named]};
    } else if (c == '"' || c == '\\') {
      out += {'\\', c};
    } else if (u <= 0x1F || u >= 0x7F) {
      out += fmt::format("\\x{:x}", u);
      escape_next_if_digit = true;
    } else {
      out += c;
    }
  }
  out += ')';
  return quotes ? '"' + out + '"' : out;
}

// The UART decoder's option `i` as PulseView stores one (GlobalSettings::store_gvariant): the
// GVariant's type string and its serialised bytes.
std::string uart_option(int i, std::string_view name, std::string_view type,
                        std::string_view bytes) {
  return fmt::format(
      "decoder0\\option{0}\\name={1}\ndecoder0\\option{0}\\type={2}\n"
      "decoder0\\option{0}\\value={3}\n",
      i, name, type, ini_byte_array(bytes));
}

}  // namespace

std::string pulseview_session_text(std::uint32_t baud, const std::string& rx,
                                   const std::string& tx) {
  // The keys DecodeSignal::restore_settings and Session::restore_setup read. Options that differ
  // from the decoder's defaults only (data_bits 8, stop_bits 1.0 are the uart decoder's). Each
  // channel's initial pin state 2: SRD_INITIAL_PIN_SAME_AS_SAMPLE0 (PulseView's own default).
  std::string s =
      "; dpc31emu: the UART decoder (8E1) and PROFIBUS DP stacked on it (docs/waveforms.md)\n"
      "[General]\ndecode_signals=1\n\n[decode_signal0]\nname=PROFIBUS DP\nenabled=true\n"
      "decoders=2\ndecoder0\\id=uart\ndecoder0\\visible=true\ndecoder0\\options=2\n";
  // baudrate an int64 ("x"), little-endian: GVariant serialises in the machine's order, and the
  // machines PulseView runs on (x86, ARM) are little-endian; parity a string ("s"): its bytes and
  // the terminating NUL.
  std::string rate;
  for (int b = 0; b < 8; ++b) rate += static_cast<char>((std::uint64_t{baud} >> (8 * b)) & 0xFF);
  s += uart_option(0, "baudrate", "x", rate);
  s += uart_option(1, "parity", "s", std::string_view("even", 5));
  s += "decoder1\\id=profibus_dp\ndecoder1\\visible=true\ndecoder1\\options=0\nchannels=2\n";
  // The uart decoder's optional channels in its order: rx, tx.
  int i = 0;
  for (const std::string& name : {rx, tx}) {
    if (!name.empty()) s += fmt::format("channel{}\\assigned_signal_name={}\n", i, name);
    s += fmt::format("channel{}\\initial_pin_state=2\n", i);
    ++i;
  }
  return s;
}

}  // namespace dpc31::wave
