#include "plugin_symbol.hpp"

#include <dlfcn.h>
#include <fmt/format.h>
#include <link.h>

namespace dpc31 {

std::string symbol_problem(void* sym, const char* name, SymbolKind want, const char* header) {
  Dl_info info{};
  void* found = nullptr;  // dladdr1 stores the symbol table entry's address here
  if (::dladdr1(sym, &info, &found, RTLD_DL_SYMENT) == 0 || found == nullptr) {
    return {};  // no table entry to judge by: dlsym found it by name, as a linker would
  }
  const auto* entry = static_cast<const ElfW(Sym)*>(found);
  const unsigned type = ELF64_ST_TYPE(entry->st_info);
  const bool function = type == STT_FUNC || type == STT_GNU_IFUNC;
  if (want == SymbolKind::function ? function
                                   : type == STT_OBJECT && entry->st_size == sizeof(void*)) {
    return {};
  }
  const std::string is = function             ? std::string("a function")
                         : type == STT_OBJECT ? fmt::format("data of {} bytes", entry->st_size)
                         : type == STT_TLS    ? std::string("thread-local data")
                                              : fmt::format("a symbol of ELF type {}", type);
  return fmt::format("{} is {}, not the {} {} declares", name, is,
                     want == SymbolKind::function ? "function" : "pointer", header);
}

}  // namespace dpc31
