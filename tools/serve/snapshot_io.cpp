#include "snapshot_io.hpp"

#include <exception>

#if __has_include("dpc31/snapshot.hpp")
#include "dpc31/snapshot.hpp"
#define DPC31_SERVE_HAS_SNAPSHOT 1
#else
#define DPC31_SERVE_HAS_SNAPSHOT 0
#endif

namespace dpc31::serve {

#if DPC31_SERVE_HAS_SNAPSHOT

bool snapshot_supported() { return true; }

std::string save_chip(const Chip& chip, const std::string& path) {
  try {
    chip.save_state_file(path);
  } catch (const SnapshotError& e) {
    return e.what();
  } catch (const std::exception& e) {
    return e.what();
  }
  return {};
}

std::string load_chip(Chip& chip, const std::string& path) {
  try {
    chip.load_state_file(path);
  } catch (const SnapshotError& e) {
    return e.what();
  } catch (const std::exception& e) {
    return e.what();
  }
  return {};
}

#else

bool snapshot_supported() { return false; }
std::string save_chip(const Chip&, const std::string&) { return "no snapshot support"; }
std::string load_chip(Chip&, const std::string&) { return "no snapshot support"; }

#endif

}  // namespace dpc31::serve
