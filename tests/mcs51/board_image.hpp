// A test program of tests/mcs51/board/, as the build assembled it (BOARD_DIR): its Intel HEX image.
#pragma once

#include <gtest/gtest.h>

#include <fstream>
#include <sstream>
#include <string>

#include "mcs51/ihex.hpp"

inline mcs51::HexImage board_image(const std::string& name) {
  std::ifstream in(BOARD_DIR "/" + name + ".ihx");
  std::stringstream text;
  text << in.rdbuf();
  mcs51::HexImage img;
  std::string error;
  EXPECT_TRUE(mcs51::parse_ihex(text.str(), img, error)) << name << ": " << error;
  return img;
}
