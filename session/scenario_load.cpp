// Scenario files from disk, and the firmware plug-in a scenario names: loaded only after the whole
// file has parsed, and only when no other user could have changed it or the scenario
// (docs/security.md, "Code a command runs").
#include <fcntl.h>
#include <fmt/format.h>
#include <sys/stat.h>
#include <unistd.h>

#include "cpu51_module.hpp"
#include "firmware_host.hpp"
#include "outfile.hpp"
#include "scenario.hpp"
#include "textfile.hpp"
#include "trust.hpp"

namespace dpc31 {

namespace {

constexpr std::size_t kMaxFileBytes = 16u << 20;

}  // namespace

bool read_scenario_file(const std::string& path, std::string& text, std::string& untrusted,
                        ScenarioError& err) {
  err = ScenarioError{path, 0, {}};
  // Opened once: whether another user could have changed it is judged on what is read (it
  // matters when it names a plug-in: bind_plugin). An anonymous pipe is the piping user's own; a
  // named FIFO is judged as a file is (another user's FIFO could feed any plug-in's name).
  const int fd = ::open(path.c_str(), O_RDONLY | O_CLOEXEC);
  untrusted.clear();
  if (fd >= 0) untrusted = untrusted_input(fd, path);
  // (When it cannot be opened, read_text_file() says why in its words.)
  const bool read = fd >= 0 ? read_text_fd(fd, kMaxFileBytes, "scenario", text, err.message)
                            : read_text_file(path, kMaxFileBytes, "scenario", text, err.message);
  if (fd >= 0) ::close(fd);
  return read;
}

bool load_scenario(const std::string& path, Scenario& out, ScenarioError& err) {
  std::string text;
  std::string untrusted;
  return read_scenario_file(path, text, untrusted, err) &&
         parse_scenario_file(text, path, untrusted, out, err);
}

bool parse_scenario_file(std::string_view text, const std::string& path,
                         const std::string& untrusted, Scenario& out, ScenarioError& err) {
  err = ScenarioError{path, 0, {}};
  err.line = cut_or_earlier_error(text, err.message, [&](const std::string& whole, std::string& m) {
    Scenario s;
    ScenarioError e;
    if (parse_scenario(whole, path, s, e)) return 0;
    m = e.message;
    return e.line;
  });
  if (err.line != 0) return false;
  if (!parse_scenario(text, path, out, err)) return false;
  out.untrusted = untrusted;
  return true;
}

std::string plugin_refused_untrusted(const std::string& untrusted) {
  return "firmware plug-in refused: the scenario names it, and another user could have changed "
         "the scenario: " +
         untrusted;
}

bool plugin_pending(const Scenario& s) { return !s.firmware.empty() && s.firmware_desc == nullptr; }

std::vector<outfile::Named> scenario_inputs(const Scenario& s) {
  std::vector<outfile::Named> inputs;
  if (plugin_pending(s)) inputs.push_back({"the firmware plug-in", s.firmware});
  if (s.cpu) {
    inputs.push_back({fmt::format("the `cpu {}` image", s.cpu->c31 ? "c31" : "80c32"), s.cpu->hex});
    inputs.push_back({"the SDCC map", cpu51_map_path(s.cpu->hex)});
  }
  return inputs;
}

bool bind_plugin(Scenario& s, ScenarioError& err) {
  if (!plugin_pending(s)) return true;
  if (!s.untrusted.empty()) {
    err = ScenarioError{s.file, s.firmware_line, plugin_refused_untrusted(s.untrusted)};
    return false;
  }
  const dpc31_firmware* fw = nullptr;
  try {
    fw = &find_firmware(s.firmware);
  } catch (const FirmwareError& e) {
    err = ScenarioError{s.file, s.firmware_line, e.what()};
    return false;
  }
  Scenario bound;
  if (!parse_scenario(s.text, s.file, fw, bound, err)) return false;
  // What the descriptor decides: the slave's defaults (and the master's view of them in the
  // steps), and the names of its ports and inputs, checked by this second parse.
  s.user = std::move(bound.user);
  s.steps = std::move(bound.steps);
  s.firmware_desc = fw;
  s.text.clear();
  return true;
}

}  // namespace dpc31
