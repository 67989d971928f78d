// Behaviour attached to one register (keyed by the RegId that is accessed, port or latch). Each
// block installs the hooks of its registers next to its behaviour (its install_hooks), bound to
// itself: a hook gets its own block and nothing else, so a register reaches only the block that
// owns it and, through it, the references the chip wired into that block (docs/architecture.md).
#pragma once

#include <array>
#include <cstdint>

#include "dpc31/reg_ids.hpp"

namespace dpc31 {

struct RegHooks {
  void* block = nullptr;  // the block the hooks below are bound to (all four: one block)
  // Derived read side without side effects (for command reads: the result they would give).
  std::uint16_t (*read)(const void* block) = nullptr;
  // Command reads: perform the command, return its result.
  std::uint16_t (*command)(void* block) = nullptr;
  // After the access-policy rule: may change what is stored (veto, keep events).
  std::uint16_t (*pre_write)(void* block, std::uint16_t old, std::uint16_t next) = nullptr;
  // After the store: actions of the write (Start, EOI, Go_Offline); `written` is the
  // lane-aligned value the CPU wrote (a command acts on the bits written as 1).
  void (*post_write)(void* block, std::uint16_t old, std::uint16_t now,
                     std::uint16_t written) = nullptr;
};

using HookTable = std::array<RegHooks, kRegIdCount>;

// The block a hook is bound to.
template <class Block>
Block& self(void* block) {
  return *static_cast<Block*>(block);
}
template <class Block>
const Block& self(const void* block) {
  return *static_cast<const Block*>(block);
}

// The hooks of register `id`, bound to `block`.
template <class Block>
RegHooks& bind_hooks(HookTable& h, RegId id, Block& block) {
  RegHooks& r = h[static_cast<std::size_t>(id)];
  r.block = &block;
  return r;
}

}  // namespace dpc31
