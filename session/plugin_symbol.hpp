// What a plug-in's entry symbol is, checked before it is used: a library not built from our
// header (another language, a wrong file) may export the name as something else, and reading
// data as a pointer, or calling data, crashes the host (docs/bring-up.md, section 3).
#pragma once

#include <cstddef>
#include <string>

namespace dpc31 {

enum class SymbolKind { function, pointer };

// "" when `sym` (dlsym's answer for `name`) is what the plug-in ABI header `header` declares:
// a function (STT_FUNC), or a pointer (STT_OBJECT of pointer size), as the library's dynamic
// symbol table says (dladdr1, RTLD_DL_SYMENT). Else the words for a one-line refusal:
// "NAME is data of 4 bytes, not the pointer dpc31/dpc31_firmware.h declares".
std::string symbol_problem(void* sym, const char* name, SymbolKind want, const char* header);

}  // namespace dpc31
