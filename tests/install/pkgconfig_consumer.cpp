// Install.consumer: a C++ program built with `pkg-config --cflags --libs dpc31emu` alone, on the
// headers docs/cpu.md and docs/install.md tell a user to include: the 80C32 board by name
// (cpu51_board.hpp, its core's mcs51/ihex.hpp) and the segment outputs
// (libdpc31emu_segment_outputs). Prints one line; exit 0 only if the image loaded.
#include <cstdio>
#include <string>

#include "cpu51_board.hpp"
#include "dpc31/segment_outputs/segment_outputs.hpp"
#include "mcs51/ihex.hpp"

int main() {
  // SJMP $ (80 FE) at 0000h: the CPU loops there, 2 machine cycles an instruction.
  mcs51::HexImage img;
  std::string error;
  if (!mcs51::parse_ihex(":0200000080FE80\n:00000001FF\n", img, error)) {
    std::fprintf(stderr, "pkgconfig consumer: %s\n", error.c_str());
    return 1;
  }
  dpc31::Chip chip({dpc31::Profile::spc3, dpc31::BusMode::intel});
  dpc31::Cpu51Board board(chip, 24'000'000, 0x8000);
  board.cpu().load_code(0, img.bytes);
  board.run_until(48'000);  // 1 ms of the chip's time
  std::printf("pkgconfig consumer: %s, PC %04Xh after %llu machine cycles\n",
              dpc31::station_scope(5, "spc3").c_str(), board.cpu().pc(),
              static_cast<unsigned long long>(board.cpu().cycles()));
}
