// RTL models loaded at run time: a shared object with the C entry point of
// rtl_model/dpc31_rtl_model.h (made by dpc31emu_verilate_model() or `dpc31 cosim --rtl`), and
// the build of such a model from Verilog sources into a cache (docs/golden-model.md, "Putting
// your own RTL under the harness").
#pragma once

#include <cstdio>
#include <memory>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "dpc31_rtl_model.h"
#include "dut.hpp"

namespace dpc31::cosim {

class RtlLibrary {
 public:
  // dlopen + dpc31_rtl_model_get(); nullptr with a one-line reason when it is no such model.
  static std::shared_ptr<const RtlLibrary> load(const std::string& path, std::string& error);
  ~RtlLibrary();
  RtlLibrary(const RtlLibrary&) = delete;
  RtlLibrary& operator=(const RtlLibrary&) = delete;

  [[nodiscard]] std::unique_ptr<Dut> make_dut(const DutOptions& o, unsigned mutant_sel) const;
  [[nodiscard]] bool has_mutant_sel() const { return model_->has_mutant_sel != 0; }
  [[nodiscard]] std::string top() const { return model_->top; }
  [[nodiscard]] const std::string& path() const { return path_; }
  // The profile the model is built for (PROFILE of dpc31emu_verilate_model, -GPROFILE=).
  [[nodiscard]] Profile profile() const { return profile_; }

 private:
  RtlLibrary(void* handle, const dpc31_rtl_model* model, Profile profile, std::string path)
      : handle_(handle), model_(model), profile_(profile), path_(std::move(path)) {}
  void* handle_;
  const dpc31_rtl_model* model_;
  Profile profile_;
  std::string path_;
};

// The cycle's inputs in the C layout of the entry point.
dpc31_rtl_inputs rtl_inputs(const Inputs& in);
// The mutant_sel value of a mutant of rtl/dpc31_blocks.v by name ("" = 0), or a number 1..15
// given as text; nullopt for anything else.
std::optional<unsigned> mutant_sel(std::string_view mutant);

struct RtlBuild {
  std::vector<std::string> sources;  // Verilog files
  std::string top;                   // the top module
  std::vector<std::string> defines;  // NAME or NAME=VALUE (Verilator -D)
  Profile profile = Profile::dpc31;  // -GPROFILE=
  // $system, $c, `systemc_* and DPI imports run code of the host inside dpc31: refused unless
  // asked for (--rtl-host-code).
  bool host_code = false;
};

// $DPC31EMU_RTL_CACHE, else $XDG_CACHE_HOME/dpc31emu/rtl, else <home>/.cache/dpc31emu/rtl ($HOME,
// else the password database's); empty if there is no home. build_rtl_model refuses a cache that
// is not owned by the user or is writable by others.
std::string rtl_cache_dir();

// Verilates and compiles the sources into <rtl_cache_dir()>/<key>/model.so, unless that is there
// already (key: a hash of what Verilator's preprocessor makes of the named sources, each bounded,
// and the files they `include; their names, the top, defines, profile, the Verilator version and
// the adapter's own files). The cache and every directory above it must be ours alone; what is
// made in it is mode 0700/0600 whatever the umask. `progress` gets one line when a
// build starts (nullptr: silent). False with one line in `error`: a missing file, Verilator's own
// first error, a port missing or of the wrong width, a failed C++ build.
bool build_rtl_model(const RtlBuild& b, std::string& model_path, std::string& error,
                     std::FILE* progress);

}  // namespace dpc31::cosim
