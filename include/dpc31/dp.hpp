// DP layer constants of the telegrams (EN 50170 / IEC 61158 type 3): the service access points
// (SAPs) of the DP services, as a master addresses them and the slave answers from them.
#pragma once

#include <cstdint>

namespace dpc31 {

// DP service access points (DSAP at the slave) and the master's SSAP.
namespace sap {
inline constexpr std::uint8_t Set_Slave_Add = 55;
inline constexpr std::uint8_t Rd_Inp = 56;
inline constexpr std::uint8_t Rd_Outp = 57;
inline constexpr std::uint8_t Global_Control = 58;
inline constexpr std::uint8_t Get_Cfg = 59;
inline constexpr std::uint8_t Slave_Diag = 60;
inline constexpr std::uint8_t Set_Prm = 61;
inline constexpr std::uint8_t Chk_Cfg = 62;
inline constexpr std::uint8_t Master = 62;
}  // namespace sap

}  // namespace dpc31
