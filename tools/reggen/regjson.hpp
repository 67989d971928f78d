// Loading and validating regs/dpc31_regs.json into the compiled types of dpc31/regdesc.hpp.
// The model owns every string and array the ProfileDesc objects point into, so the emitters of
// regfmt.hpp run on it exactly as on the compiled-in tables.
#pragma once

#include <array>
#include <deque>
#include <memory>
#include <span>
#include <stdexcept>
#include <string>
#include <string_view>
#include <vector>

#include "dpc31/regdesc.hpp"

namespace dpc31::regjson {

// A rejected description. what() is one line: "<file>: register 'X': what is wrong".
class Error : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

class RegModel {
 public:
  // Reads and validates a description file; throws Error.
  static std::unique_ptr<RegModel> load(const std::string& path);
  // Validates description text; `file` is only used in messages. Throws Error.
  static std::unique_ptr<RegModel> parse(std::string_view text, const std::string& file);

  RegModel(const RegModel&) = delete;
  RegModel& operator=(const RegModel&) = delete;
  ~RegModel();

  // The profiles in Profile order (spc3, vpc3plus, dpc31), whatever the file order.
  [[nodiscard]] std::span<const ProfileDesc* const> profiles() const { return profile_ptrs_; }
  [[nodiscard]] const ProfileDesc& profile(Profile p) const;
  // Name of each RegId value: one per distinct register name, in first-appearance order.
  [[nodiscard]] std::span<const std::string> reg_names() const { return reg_names_; }
  [[nodiscard]] const ChipTiming& timing() const { return timing_; }
  [[nodiscard]] const std::string& title() const { return title_; }
  // Suspicious but accepted content, one line each ("<file>: register 'X': ...").
  [[nodiscard]] std::span<const std::string> warnings() const { return warnings_; }

 private:
  RegModel();
  friend class Loader;

  std::deque<std::string> strings_;                 // stable storage for the string_views
  std::deque<std::vector<FieldDesc>> field_lists_;  // one per register entry
  std::array<std::vector<RegDesc>, 3> regs_;        // indexed by Profile
  std::array<std::vector<RegionDesc>, 3> regions_;
  std::array<std::vector<LayoutDesc>, 3> layouts_;
  std::deque<std::vector<LayoutByte>> layout_bytes_;    // one per layout
  std::deque<std::vector<LayoutValue>> layout_values_;  // one per layout byte
  std::array<ProfileDesc, 3> profile_store_{};
  std::vector<const ProfileDesc*> profile_ptrs_;
  std::vector<std::string> reg_names_;
  ChipTiming timing_{};
  std::string title_;
  std::vector<std::string> warnings_;
};

}  // namespace dpc31::regjson
