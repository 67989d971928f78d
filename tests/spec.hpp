// The register map as the manuals state it (chip-facts §1-§4), written by hand, independent of
// regs/dpc31_regs.json: the description and the emulator are both checked against this.
// Policy strings give bits from the most significant down: w RW, r RO, c W1C, s W1S, C/S the same
// and R the same but self-clearing (pulse), k command read, o write-only, i no effect (logged), -
// reserved, u stored but not modelled.
#pragma once

#include <cstdint>
#include <string_view>
#include <vector>

#include "dpc31/regdesc.hpp"

namespace spec {

inline constexpr unsigned S = 1, V = 2, D = 4, ALL = 7;

struct Row {
  unsigned profiles;
  std::string_view name;
  int read;   // -1 none; cells: SPC3 cell offset in both
  int write;  // -1 none
  int width;
  int reset;  // -1: none (command reads, reserved gaps)
  std::string_view policy;
  bool cell = false;
  bool reserved = false;  // a documented gap
};

inline unsigned bit(dpc31::Profile p) { return 1u << static_cast<unsigned>(p); }

// Physical address of organisational cell `off` (16h..3Fh; the DPC31's run on to 47h): SPC3/VPC3+
// in place, DPC31 from 0840h.
inline int cell_addr(dpc31::Profile p, int off) {
  return p == dpc31::Profile::dpc31 ? 0x840 + off - 0x16 : off;
}

inline const std::vector<Row>& rows() {
  static const std::vector<Row> r = {
      {S, "Int_Req_Reg", 0x00, 0x00, 16, 0x0000, "--wwwwww---wwwww"},
      // DPC31: bit 5 Indication, the Indication_Queue's interrupt (docs/dpc31.md, modelled).
      {D, "Int_Req_Reg", 0x00, 0x00, 16, 0x0000, "--wwwwww--wwwwww"},
      {V, "Int_Req_Reg", 0x00, 0x00, 16, 0x0000, "wwwwwwwwwwwwwwww"},
      {S, "Int_Reg", 0x02, -1, 16, 0x0000, "--rrrrrr---rrrrr"},
      {D, "Int_Reg", 0x02, -1, 16, 0x0000, "--rrrrrr--rrrrrr"},
      {V, "Int_Reg", 0x02, -1, 16, 0x0000, "rrrrrrrrrrrrrrrr"},
      {S, "Int_Ack_Reg", -1, 0x02, 16, 0x0000, "--cciicc---ccccc"},
      {D, "Int_Ack_Reg", -1, 0x02, 16, 0x0000, "--cciicc--cccccc"},
      {V, "Int_Ack_Reg", -1, 0x02, 16, 0x0000, "cccciicccicccccc"},
      // Bit 1 is FDL_IND_ST (manual-quotes.md, Confirmed: "SPC3 status bit 1 FDL_IND_ST").
      {S, "Status_Reg", 0x04, -1, 16, 0x0000, "rrrrrrrrrrrrrrrr"},
      // DPC31 p.12: "status displays are stored (status register, ...)" in the parameter cells,
      // as is the "Param Register" (below); both places modelled (docs/dpc31.md).
      {D, "Status_Reg", 0x0874, -1, 16, 0x0000, "rrrrrrrrrrrrrr-r"},
      {V, "Status_Reg", 0x04, -1, 16, 0xC000, "rrrrrrrrrrrrrr-r"},
      {S, "Int_Mask_Reg", -1, 0x04, 16, 0xFFFF, "--oooooo---ooooo"},
      {D, "Int_Mask_Reg", -1, 0x04, 16, 0xFFFF, "--oooooo--oooooo"},
      {V, "Int_Mask_Reg", -1, 0x04, 16, 0xFFFF, "oooooooooooooooo"},
      {S | D, "Mode_Reg0", 0x06, 0x06, 16, 0x0000, "--wu-wwwwwuwu-ww"},
      {V, "Mode_Reg0", 0x06, 0x06, 16, 0x0000, "-wwuwwwwwwuwuwww"},
      {ALL, "Din_Buffer_SM", 0x08, -1, 8, 0xE1, "rrrrrrrr"},
      {S, "Mode_Reg1_S", -1, 0x08, 8, 0x00, "--ssSsSs"},
      // DPC31: start, stop, Leave_Master and the user watchdog are requests (p.22, Table 5.1-3).
      {D, "Mode_Reg1_S", -1, 0x08, 8, 0x00, "--isiiSi"},
      {V, "Mode_Reg1_S", -1, 0x08, 8, 0x00, "s-ssSsSs"},
      {ALL, "New_Din_Buffer_Cmd", 0x09, -1, 8, -1, "------kk"},
      {S, "Mode_Reg1_R", -1, 0x09, 8, 0x00, "--ccCcCc"},
      {D, "Mode_Reg1_R", -1, 0x09, 8, 0x00, "--iciiCi"},
      {V, "Mode_Reg1_R", -1, 0x09, 8, 0x00, "c-ccCcCc"},
      {S | V, "Dout_Buffer_SM", 0x0A, -1, 8, 0xE1, "rrrrrrrr"},
      {D, "Dout_Buffer_SM", 0x0A, -1, 8, 0x21, "r-rrrrrr"},
      {ALL, "WD_Baud_Control_Val", -1, 0x0A, 8, 0x00, "oooooooo"},
      {ALL, "Next_Dout_Buffer_Cmd", 0x0B, -1, 8, -1, "----kkkk"},
      {ALL, "MinTSDR_Val", -1, 0x0B, 8, 0x0B, "oooooooo"},
      {ALL, "Diag_Buffer_SM", 0x0C, -1, 8, 0x09, "----rrrr"},
      {S | D, "Reserved_0Ch_W", -1, 0x0C, 8, -1, "--------", false, true},
      {V, "Mode_Reg2", -1, 0x0C, 8, 0x01, "oouuuooo"},  // GC_Int_Mode = 1 "(default)", VPC3+C p.50
      {ALL, "New_Diag_Buffer_Cmd", 0x0D, -1, 8, -1, "------kk"},
      {S | D, "Reserved_0Dh_W", -1, 0x0D, 8, -1, "--------", false, true},
      {V, "Sync_PW_Reg", -1, 0x0D, 8, 0x00, "uuuuuuuu"},
      {ALL, "User_Prm_Data_Okay", 0x0E, -1, 8, -1, "------kk"},
      {S | D, "Reserved_0Eh_W", -1, 0x0E, 8, -1, "--------", false, true},
      {V, "Control_Command_Reg", -1, 0x0E, 8, 0x00, "uuuuuuuu"},
      {ALL, "User_Prm_Data_Not_Okay", 0x0F, -1, 8, -1, "------kk"},
      {S | D, "Reserved_0Fh_W", -1, 0x0F, 8, -1, "--------", false, true},
      {V, "Group_Select_Reg", -1, 0x0F, 8, 0x00, "uuuuuuuu"},
      {ALL, "User_Cfg_Data_Okay", 0x10, -1, 8, -1, "------kk"},
      {ALL, "Reserved_10h_W", -1, 0x10, 8, -1, "--------", false, true},
      {ALL, "User_Cfg_Data_Not_Okay", 0x11, -1, 8, -1, "------kk"},
      {ALL, "Reserved_11h_W", -1, 0x11, 8, -1, "--------", false, true},
      {S | D, "Reserved_12h_R", 0x12, -1, 8, -1, "--------", false, true},
      {V, "DXBout_Buffer_SM", 0x12, -1, 8, 0x00, "uuuuuuuu"},
      {S | D, "Reserved_12h_W", -1, 0x12, 8, -1, "--------", false, true},
      {V, "Mode_Reg3", -1, 0x12, 8, 0x00, "uuuuuuou"},  // bit 1 DX_Int_Mode_2 (Profichip DpCfg.h)
      {S | D, "Reserved_13h_R", 0x13, -1, 8, -1, "--------", false, true},
      {V, "Next_DXBout_Buffer_Cmd", 0x13, -1, 8, 0x00, "uuuuuuuu"},
      {ALL, "Reserved_13h_W", -1, 0x13, 8, -1, "--------", false, true},
      {S | V, "SSA_Buffer_Free_Cmd", 0x14, -1, 8, -1, "kkkkkkkk"},
      // DPC31 p.26: "User_SSA_OK Cmd" with a 2-bit result (00, 01, 11, 10).
      {D, "SSA_Buffer_Free_Cmd", 0x14, -1, 8, -1, "------kk"},
      {ALL, "Reserved_14h_W", -1, 0x14, 8, -1, "--------", false, true},
      {S, "Reserved_15h_R", 0x15, -1, 8, -1, "--------", false, true},
      {S, "Mode_Reg1", -1, -1, 8, 0x00, "--rrRrRr"},
      {D, "Mode_Reg1", 0x15, -1, 8, 0x00, "---r--R-"},
      {V, "Mode_Reg1", 0x15, -1, 8, 0x00, "u-rrRrRr"},
      {ALL, "Reserved_15h_W", -1, 0x15, 8, -1, "--------", false, true},
      {D, "Param_Reg", 0x0872, 0x0872, 8, 0x00, "------ww"},
      {D, "C31_Control", 0x17, 0x17, 8, 0x00, "-------w"},
      // Organisational parameters: RAM cells (SPC3 offsets).
      {ALL, "R_TS_Adr", 0x16, 0x16, 8, 0x00, "wwwwwwww", true},
      {S | D, "Reserved_17h", 0x17, 0x17, 8, 0x00, "wwwwwwww", true, true},
      {V, "R_FDL_SAP_List_Ptr", 0x17, 0x17, 8, 0x00, "wwwwwwww", true},
      {ALL, "R_User_WD_Value", 0x18, 0x18, 16, 0x0000, "wwwwwwwwwwwwwwww", true},
      {ALL, "R_Len_Dout_Buf", 0x1A, 0x1A, 8, 0x00, "wwwwwwww", true},
      {ALL, "R_Dout_Buf_Ptr1", 0x1B, 0x1B, 8, 0x00, "wwwwwwww", true},
      {ALL, "R_Dout_Buf_Ptr2", 0x1C, 0x1C, 8, 0x00, "wwwwwwww", true},
      {ALL, "R_Dout_Buf_Ptr3", 0x1D, 0x1D, 8, 0x00, "wwwwwwww", true},
      {ALL, "R_Len_Din_Buf", 0x1E, 0x1E, 8, 0x00, "wwwwwwww", true},
      {ALL, "R_Din_Buf_Ptr1", 0x1F, 0x1F, 8, 0x00, "wwwwwwww", true},
      {ALL, "R_Din_Buf_Ptr2", 0x20, 0x20, 8, 0x00, "wwwwwwww", true},
      {ALL, "R_Din_Buf_Ptr3", 0x21, 0x21, 8, 0x00, "wwwwwwww", true},
      {S, "Reserved_22h", 0x22, 0x22, 8, 0x00, "wwwwwwww", true, true},
      {D, "R_Dout_Buf_Ptr_C", 0x22, 0x22, 8, 0x00, "wwwwwwww", true},
      {V, "R_Len_DXBout_Buf", 0x22, 0x22, 8, 0x00, "wwwwwwww", true},
      {S | D, "Reserved_23h", 0x23, 0x23, 8, 0x00, "wwwwwwww", true, true},
      {V, "R_DXBout_Buf_Ptr1", 0x23, 0x23, 8, 0x00, "wwwwwwww", true},
      {ALL, "R_Len_Diag_Buf1", 0x24, 0x24, 8, 0x00, "wwwwwwww", true},
      {ALL, "R_Len_Diag_Buf2", 0x25, 0x25, 8, 0x00, "wwwwwwww", true},
      {ALL, "R_Diag_Buf_Ptr1", 0x26, 0x26, 8, 0x00, "wwwwwwww", true},
      {ALL, "R_Diag_Buf_Ptr2", 0x27, 0x27, 8, 0x00, "wwwwwwww", true},
      {ALL, "R_Len_Cntrl_Buf1", 0x28, 0x28, 8, 0x00, "wwwwwwww", true},
      {ALL, "R_Len_Cntrl_Buf2", 0x29, 0x29, 8, 0x00, "wwwwwwww", true},
      {ALL, "R_Aux_Buf_Sel", 0x2A, 0x2A, 8, 0x00, "wwwwwwww", true},
      {ALL, "R_Aux_Buf_Ptr1", 0x2B, 0x2B, 8, 0x00, "wwwwwwww", true},
      {ALL, "R_Aux_Buf_Ptr2", 0x2C, 0x2C, 8, 0x00, "wwwwwwww", true},
      {ALL, "R_Len_SSA_Data", 0x2D, 0x2D, 8, 0x00, "wwwwwwww", true},
      {ALL, "R_SSA_Buf_Ptr", 0x2E, 0x2E, 8, 0x00, "wwwwwwww", true},
      {ALL, "R_Len_Prm_Data", 0x2F, 0x2F, 8, 0x00, "wwwwwwww", true},
      {ALL, "R_Prm_Buf_Ptr", 0x30, 0x30, 8, 0x00, "wwwwwwww", true},
      {ALL, "R_Len_Cfg_Data", 0x31, 0x31, 8, 0x00, "wwwwwwww", true},
      {ALL, "R_Cfg_Buf_Ptr", 0x32, 0x32, 8, 0x00, "wwwwwwww", true},
      {ALL, "R_Len_Read_Cfg_Data", 0x33, 0x33, 8, 0x00, "wwwwwwww", true},
      {ALL, "R_Read_Cfg_Buf_Ptr", 0x34, 0x34, 8, 0x00, "wwwwwwww", true},
      {S | D, "Reserved_35h", 0x35, 0x35, 8, 0x00, "wwwwwwww", true, true},
      {S | D, "Reserved_36h", 0x36, 0x36, 8, 0x00, "wwwwwwww", true, true},
      {S | D, "Reserved_37h", 0x37, 0x37, 8, 0x00, "wwwwwwww", true, true},
      {S | D, "Reserved_38h", 0x38, 0x38, 8, 0x00, "wwwwwwww", true, true},
      {V, "R_Len_DXB_Link_Buf", 0x35, 0x35, 8, 0x00, "wwwwwwww", true},
      {V, "R_DXB_Link_Buf_Ptr", 0x36, 0x36, 8, 0x00, "wwwwwwww", true},
      {V, "R_Len_DXB_Status_Buf", 0x37, 0x37, 8, 0x00, "wwwwwwww", true},
      {V, "R_DXB_Status_Buf_Ptr", 0x38, 0x38, 8, 0x00, "wwwwwwww", true},
      {ALL, "R_Real_No_Add_Change", 0x39, 0x39, 8, 0x00, "wwwwwwww", true},
      {ALL, "R_Ident_Low", 0x3A, 0x3A, 8, 0x00, "wwwwwwww", true},
      {ALL, "R_Ident_High", 0x3B, 0x3B, 8, 0x00, "wwwwwwww", true},
      {S | V, "R_GC_Command", 0x3C, 0x3C, 8, 0x00, "wwwwwwww", true},
      {D, "R_GC_Command", 0x3C, 0x3C, 8, 0xFF, "wwwwwwww", true},
      // DPC31 queue cells (p.22: InstQ_Base, InstQ_Wr, InstQ_Rd and the Indication_Queue's; places
      // and the lengths modelled, docs/dpc31.md), among the parameter cells from 086Ah.
      {D, "InstQ_Base", 0x40, 0x40, 8, 0x00, "wwwwwwww", true},
      {D, "InstQ_Len", 0x41, 0x41, 8, 0x00, "wwwwwwww", true},
      {D, "InstQ_Wr", 0x42, 0x42, 8, 0x00, "wwwwwwww", true},
      {D, "InstQ_Rd", 0x43, 0x43, 8, 0x00, "wwwwwwww", true},
      {D, "IndQ_Base", 0x44, 0x44, 8, 0x00, "wwwwwwww", true},
      {D, "IndQ_Len", 0x45, 0x45, 8, 0x00, "wwwwwwww", true},
      {D, "IndQ_Wr", 0x46, 0x46, 8, 0x00, "wwwwwwww", true},
      {D, "IndQ_Rd", 0x47, 0x47, 8, 0x00, "wwwwwwww", true},
      {ALL, "R_Len_Spec_Prm_Buf", 0x3D, 0x3D, 8, 0x00, "wwwwwwww", true},
      {S | D, "Reserved_3Eh", 0x3E, 0x3E, 8, 0x00, "wwwwwwww", true, true},
      {S | D, "Reserved_3Fh", 0x3F, 0x3F, 8, 0x00, "wwwwwwww", true, true},
      {V, "R_DXBout_Buf_Ptr2", 0x3E, 0x3E, 8, 0x00, "wwwwwwww", true},
      {V, "R_DXBout_Buf_Ptr3", 0x3F, 0x3F, 8, 0x00, "wwwwwwww", true},
  };
  return r;
}

inline std::vector<Row> rows_for(dpc31::Profile p) {
  std::vector<Row> out;
  for (const Row& r : rows()) {
    if ((r.profiles & bit(p)) == 0) continue;
    Row x = r;
    if (x.cell) {
      x.read = cell_addr(p, x.read);
      x.write = cell_addr(p, x.write);
    }
    out.push_back(x);
  }
  return out;
}

inline Row row(dpc31::Profile p, std::string_view name) {
  for (const Row& r : rows_for(p)) {
    if (r.name == name) return r;
  }
  return Row{0, name, -1, -1, 0, -1, ""};
}

// The manuals' byte order: Intel puts bits 7..0 at the lower address, Motorola bits 15..8.
inline int byte_index_at(dpc31::BusMode m, int offset) {
  return m == dpc31::BusMode::intel ? offset : 1 - offset;
}

// Mask of bits whose policy letter is one of `letters`.
inline std::uint16_t mask_of(std::string_view policy, std::string_view letters) {
  std::uint16_t m = 0;
  const auto n = policy.size();
  for (std::size_t i = 0; i < n; ++i) {
    if (letters.find(policy[i]) != std::string_view::npos)
      m |= static_cast<std::uint16_t>(1u << (n - 1 - i));
  }
  return m;
}

}  // namespace spec
