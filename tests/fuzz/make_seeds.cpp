// Writes the generated part of the seed corpora (docs/robustness.md, "Seeds"): real telegrams of
// the built-in master as chip_bytes items and as chip_bits edges, and snapshots of chips in
// several states. Usage: dpc31_fuzz_make_seeds CORPUS_DIR (tests/fuzz/corpus).
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <functional>
#include <stdexcept>
#include <string>
#include <string_view>
#include <system_error>
#include <vector>

#include "cpu.hpp"
#include "dp_master.hpp"
#include "dpc31/chip.hpp"
#include "dpc31/uart.hpp"
#include "responder.hpp"

namespace {

using namespace dpc31;
namespace fs = std::filesystem;
using Bytes = std::vector<std::uint8_t>;

fs::path g_dir;

void put(const std::string& target, const std::string& name, const Bytes& b) {
  fs::create_directories(g_dir / target);
  const fs::path path = g_dir / target / name;
  std::ofstream f(path, std::ios::binary);
  f.write(reinterpret_cast<const char*>(b.data()), static_cast<std::streamsize>(b.size()));
  f.close();
  if (!f) throw std::runtime_error(path.string() + ": cannot write");
}

ResponderConfig user_config() {  // as in chip_fuzz.cpp
  ResponderConfig cfg;
  cfg.substitute = {0xA5, 0x5A, 0x0F, 0xF0};
  return cfg;
}

struct Recorded {
  std::vector<Telegram> rx;                           // error-free requests the chip received
  std::vector<std::pair<std::uint64_t, bool>> edges;  // RxD as driven
};

// A session: chip + responder + master; `prefix` runs unrecorded, `body` recorded.
Recorded session(Profile p, std::uint32_t baud, const std::function<void(DpMaster&)>& prefix,
                 const std::function<void(DpMaster&)>& body, Bytes* snapshot = nullptr) {
  Chip chip({p, BusMode::intel});
  Responder user(user_config());
  user.set_inputs({0x11, 0x22, 0x33, 0x44});
  DirectBus direct(chip);
  user.init(direct);
  MasterConfig mc;
  mc.baud = baud;
  DpMaster master(chip, mc, user_config().slave);
  master.set_firmware([&](BusPort& b) { user.isr(b); });
  prefix(master);
  if (snapshot != nullptr) *snapshot = chip.save_state();
  Recorded r;
  chip.on_telegram([&](const Telegram& t) {
    if (!t.from_chip) r.rx.push_back(t);
  });
  chip.on_rxd([&](std::uint64_t c, bool l) { r.edges.emplace_back(c, l); });
  body(master);
  return r;
}

// chip_bytes items: each telegram as a frame item (LE, FCS, ED filled in by the target).
Bytes as_bytes_items(std::uint8_t setup, const std::vector<Telegram>& rx) {
  Bytes out = {setup};
  for (const Telegram& t : rx) {
    const Bytes& b = t.bytes;
    Bytes body;
    if (b[0] == 0x10) {
      body.assign(b.begin() + 1, b.begin() + 4);
    } else if (b[0] == 0x68) {
      body.assign(b.begin() + 4, b.end() - 2);
    } else {
      continue;
    }
    out.push_back(0xC0);
    out.push_back(static_cast<std::uint8_t>(body.size()));
    out.insert(out.end(), body.begin(), body.end());
  }
  return out;
}

// chip_bits pairs: the recorded edges with their delays, in clocks (hi.6) or bit/8 units.
Bytes as_bit_pairs(std::uint8_t setup, std::uint32_t t,
                   const std::vector<std::pair<std::uint64_t, bool>>& edges) {
  Bytes out = {setup};
  if (edges.empty()) return out;
  std::uint64_t prev = edges.front().first - 40ull * t;
  for (const auto& [c, level] : edges) {
    std::uint64_t d = c - prev;
    prev = c;
    // Long idle: several edges to the same (high) level first, as many as needed.
    while (d > 0x3FFF) {
      const std::uint64_t units = std::min<std::uint64_t>(0x3FFF, d * 8 / t);
      const std::uint64_t step = std::max<std::uint64_t>(1, units * t / 8);
      if (units == 0 || step > d) break;
      out.push_back(static_cast<std::uint8_t>(units));
      out.push_back(static_cast<std::uint8_t>(0x80 | units >> 8));
      d -= step;
    }
    out.push_back(static_cast<std::uint8_t>(d));
    out.push_back(static_cast<std::uint8_t>((level ? 0x80 : 0) | 0x40 | (d >> 8 & 0x3F)));
  }
  return out;
}

void startup_prefix(DpMaster& m) {
  m.startup();
  m.data_exchange({1, 2, 3, 4});
  m.idle(2000);
}

// Every seed into g_dir; throws on a failed write.
void write_seeds() {
  const char* names[] = {"spc3", "vpc3plus", "dpc31"};
  const Profile profiles[] = {Profile::spc3, Profile::vpc3plus, Profile::dpc31};
  // Data_Exchange prefix (setup bit 3), 1.5 Mbaud: what the master does next.
  const std::vector<std::pair<std::string, std::function<void(DpMaster&)>>> dx_bodies = {
      {"dx",
       [](DpMaster& m) {
         m.data_exchange({5, 6, 7, 8});
       }},
      {"diag_inputs_cfg",
       [](DpMaster& m) {
         m.slave_diag();
         m.read_inputs();
         m.read_outputs();
         m.get_cfg();
       }},
      {"gc_clear_sync_freeze",
       [](DpMaster& m) {
         m.global_control(0x02);
         m.global_control(0x20);
         m.data_exchange({9, 9, 9, 9});
         m.global_control(0x10);
         m.global_control(0x08);
         m.read_inputs();
         m.global_control(0x04);
       }},
      {"reparameterise",
       [](DpMaster& m) {
         m.set_prm();
         m.chk_cfg();
         m.slave_diag();
         m.data_exchange({1, 1, 1, 1});
       }},
      {"failsafe", [](DpMaster& m) { m.data_exchange({}); }},
  };
  for (int i = 0; i < 3; ++i) {
    const auto setup = static_cast<std::uint8_t>(0x08 | i);
    for (const auto& [name, body] : dx_bodies) {
      const Recorded r = session(profiles[i], 1'500'000, startup_prefix, body);
      put("chip_bytes", std::string(names[i]) + "_" + name, as_bytes_items(setup, r.rx));
      put("chip_bits", std::string(names[i]) + "_" + name, as_bit_pairs(setup, 32, r.edges));
    }
  }
  // A fresh chip at 12 Mbaud, 1.5 Mbaud, 187.5 kbaud: the whole start-up.
  const std::pair<std::uint8_t, std::uint32_t> rates[] = {
      {0, 12'000'000}, {3, 1'500'000}, {5, 187'500}};
  for (int i = 0; i < 3; ++i) {
    for (const auto& [code, baud] : rates) {
      const auto setup = static_cast<std::uint8_t>(code << 4 | i);
      const Recorded r = session(
          profiles[i], baud, [](DpMaster&) {}, startup_prefix);
      const std::string n = std::string(names[i]) + "_startup_" + std::to_string(baud);
      put("chip_bytes", n, as_bytes_items(setup, r.rx));
      const std::uint32_t t =
          static_cast<std::uint32_t>((2ull * 48'000'000 + baud) / (2ull * baud));
      put("chip_bits", n, as_bit_pairs(setup, t, r.edges));
    }
  }
  // Snapshots: fresh, started, in Data_Exchange (with edges driven ahead for a later cycle).
  for (int i = 0; i < 3; ++i) {
    for (BusMode bus : {BusMode::intel, BusMode::motorola}) {
      const std::string n =
          std::string(names[i]) + (bus == BusMode::intel ? "_intel" : "_motorola");
      Chip fresh({profiles[i], bus});
      put("snapshot_loader", n + "_fresh", fresh.save_state());
      if (bus == BusMode::motorola) continue;
      Bytes dx;
      session(
          profiles[i], 1'500'000, startup_prefix, [](DpMaster&) {}, &dx);
      put("snapshot_loader", n + "_data_exchange", dx);
      Chip ahead({profiles[i], bus});
      DirectBus direct(ahead);
      Responder user(user_config());
      user.init(direct);
      send_on_rxd(ahead, Bytes{0x10, 0x05, 0x02, 0x49, 0x50, 0x16}, ahead.cycle() + 200, 4);
      ahead.step(150);
      put("snapshot_loader", n + "_rx_in_progress", ahead.save_state());
    }
  }
}

}  // namespace

int main(int argc, char** argv) {
  // Bad input is one line and exit 2 (docs/bad-input.md), and nothing is made for it.
  const char* kUsage =
      "usage: dpc31_fuzz_make_seeds CORPUS_DIR (made if missing; its parent must exist)";
  const std::string_view arg = argc == 2 ? argv[1] : "";
  if (arg == "--help" || arg == "-h") {
    std::printf("%s\n", kUsage);
    return 0;
  }
  if (argc != 2 || arg.empty() || arg[0] == '-') {
    std::fprintf(stderr, "dpc31_fuzz_make_seeds: %s\n", kUsage);
    return 2;
  }
  g_dir = argv[1];
  // One level: a mistyped parent (/nonexistent/x) is refused, not created.
  std::error_code ec;
  fs::create_directory(g_dir, ec);
  if (!fs::is_directory(g_dir)) {
    std::fprintf(stderr, "dpc31_fuzz_make_seeds: %s: %s\n", argv[1],
                 ec ? ("cannot create the directory: " + ec.message()).c_str() : "not a directory");
    return 2;
  }
  try {
    write_seeds();
  } catch (const std::exception& e) {
    std::fprintf(stderr, "dpc31_fuzz_make_seeds: %s\n", e.what());
    return 2;
  }
  return 0;
}
