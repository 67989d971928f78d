// dpc31_blocks.v -- second, independent implementation of the blocks of docs/golden-model.md:
// interrupt controller, mode registers, buffer state machines with their command reads, the DP
// handshakes. Verilog-2005, one clock, synchronous active-high reset.
//
// Structure: one combinational block computes the state after the cycle through a chain of
// intermediate values (nx_*), in the order of docs/golden-model.md "Time and order":
//   1. timers  2. event inputs in table order  3. the bus access  4. X/INT (from the registers).
// Each action of the spec is one task below, named as in the spec (d_to_n, n_to_u, dout_clear,
// failsafe_clear, leave_master, start, go_offline, global_control, handshakes). The sequential
// block only registers nx_*. All outputs are registers or combinational from registers, so after
// the clock edge of cycle c they show the state after cycle c.
//
// Where the spec leaves a choice, the choice is written at the spot, marked "CHOICE:".
//
// Mutants (each changes only the named behaviour), `define one of:
//   MUTANT_NEXT_DOUT_KEEPS_N   Next_Dout_Buffer_Cmd's n_to_u leaves N as it was
//   MUTANT_ACK_NEIGHBOUR       an acknowledge of bit k also clears bit k+1
//   MUTANT_EOI_SHORT           EOI inactive time one cycle shorter
//   MUTANT_CLEAR_IGNORED_IN_SYNC  Clear_Data has no effect while Sync_Mode
//   MUTANT_NO_C_SWAP           dpc31: the C/U pointer cells are not exchanged
//   MUTANT_ACK_BEATS_EVENT     an event and its acknowledge in one cycle: the bit ends cleared
//   MUTANT_POLARITY            INT_Pol ignored: X/INT always low-active
//   MUTANT_FREEZE_IGNORED      ev_din fetches N even in Freeze_Mode
//   MUTANT_NO_CONFLICT         the handshakes never answer 01: a newer arrival is ignored
//   MUTANT_DIAG_FLAG_STICKY    ev_diag_end leaves Diag_Flag at 1 when stat_diag is 0

`include "dpc31_regs.vh"

// Profile selection of a register-description constant: spc3, vpc3plus, dpc31.
`define DPC31B_PSEL(s3, v3, d31) ((PROFILE == 0) ? (s3) : (PROFILE == 1) ? (v3) : (d31))

module dpc31_blocks #(
  parameter PROFILE = 2  // 0 spc3, 1 vpc3plus, 2 dpc31 (any other value behaves as dpc31)
) (
  input  wire        clk,
  input  wire        rst,
  input  wire        motorola,
  // Status_Reg bits 15..12 (static): the release, 0 on spc3 / dpc31; on vpc3plus the ASIC type
  // of the variant, Bh VPC3+B, Ch VPC3+C, Eh VPC3+S
  input  wire  [3:0] asic_type,
  // bus port
  input  wire [12:0] bus_addr,
  input  wire  [7:0] bus_wdata,
  input  wire        bus_rd,
  input  wire        bus_wr,
  // event inputs (one-cycle pulses)
  input  wire [15:0] ev_irq,
  input  wire        ev_leave_master,
  input  wire        ev_gc,
  input  wire  [7:0] gc_cmd,
  input  wire        ev_dout,
  input  wire        ev_failsafe,
  input  wire        ev_din,
  input  wire        ev_diag_begin,
  input  wire        ev_diag_end,
  input  wire        stat_diag,
  input  wire        ev_prm,
  input  wire        ev_cfg,
  input  wire        ev_ssa,
  input  wire        ev_prm_fault,
  input  wire        ev_dx,
  input  wire        ev_dis,
  input  wire  [1:0] dis_bits,
  // compared outputs
  output wire        x_int,
  output reg  [15:0] irr,
  output reg  [15:0] imr,
  output reg  [15:0] mode_reg0,
  output reg   [7:0] mode_reg1,
  output reg         started,
  output reg   [1:0] dp_state,
  output reg         prm_pending,
  output reg         cfg_pending,
  output reg         ssa_free,
  output reg         prm_fault,
  output reg         cfg_fault,
  output reg         not_supported,
  output reg         sync_mode,
  output reg         freeze_mode,
  output reg         diag_flag,
  output wire  [7:0] dout_sm,
  output wire  [7:0] din_sm,
  output wire  [3:0] diag_sm,
  output reg         u_cleared,
  output reg         n_cleared,
  output reg         n_cl,
  output reg         d_fresh,
  output reg   [7:0] dout_ptr1,
  output reg   [7:0] dout_ptr2,
  output reg   [7:0] dout_ptr3,
  output reg   [7:0] dout_ptr_c,
  output reg   [7:0] cfg_ptr,
  output reg   [7:0] read_cfg_ptr,
  output reg   [7:0] gc_command,
  output reg   [7:0] bus_rdata
);

  // ===========================================================================================
  // Constants from the register description (rtl/dpc31_regs.vh), selected by PROFILE
  // ===========================================================================================
  localparam IS_DPC31 = (PROFILE != 0) && (PROFILE != 1);
  localparam IS_VPC3 = (PROFILE == 1);
  localparam IS_SPC3 = (PROFILE == 0);

  // CHOICE: address bits above the profile's bus width (11 / 12 / 13) are ignored, as in
  // docs/decisions.md. The RAM access violation (spc3 >= 600h, vpc3plus >= 800h) is not part of
  // the block and is not modelled here.
  localparam integer ADDRESS_BITS =
      `DPC31B_PSEL(`SPC3_ADDRESS_BITS, `VPC3_ADDRESS_BITS, `DPC31_ADDRESS_BITS);
  localparam [12:0] ADDR_MASK = 13'h1FFF >> (13 - ADDRESS_BITS);

  // Processor parameters (16-bit registers are matched on bits 12..1).
  localparam [12:0] A_IRR = `DPC31B_PSEL(`SPC3_ADDR_Int_Req_Reg, `VPC3_ADDR_Int_Req_Reg,
                                         `DPC31_ADDR_Int_Req_Reg);
  localparam [12:0] A_INT_REG = `DPC31B_PSEL(`SPC3_ADDR_Int_Reg, `VPC3_ADDR_Int_Reg,
                                             `DPC31_ADDR_Int_Reg);
  localparam [12:0] A_IAR = `DPC31B_PSEL(`SPC3_ADDR_Int_Ack_Reg, `VPC3_ADDR_Int_Ack_Reg,
                                         `DPC31_ADDR_Int_Ack_Reg);
  localparam [12:0] A_STATUS = `DPC31B_PSEL(`SPC3_ADDR_Status_Reg, `VPC3_ADDR_Status_Reg,
                                            `DPC31_ADDR_Status_Reg);
  localparam [12:0] A_IMR = `DPC31B_PSEL(`SPC3_ADDR_Int_Mask_Reg, `VPC3_ADDR_Int_Mask_Reg,
                                         `DPC31_ADDR_Int_Mask_Reg);
  localparam [12:0] A_MODE_REG0 = `DPC31B_PSEL(`SPC3_ADDR_Mode_Reg0, `VPC3_ADDR_Mode_Reg0,
                                               `DPC31_ADDR_Mode_Reg0);
  localparam [12:0] A_DIN_SM = `DPC31B_PSEL(`SPC3_ADDR_Din_Buffer_SM, `VPC3_ADDR_Din_Buffer_SM,
                                            `DPC31_ADDR_Din_Buffer_SM);
  localparam [12:0] A_MODE_REG1_S = `DPC31B_PSEL(`SPC3_ADDR_Mode_Reg1_S, `VPC3_ADDR_Mode_Reg1_S,
                                                 `DPC31_ADDR_Mode_Reg1_S);
  localparam [12:0] A_NEW_DIN = `DPC31B_PSEL(`SPC3_ADDR_New_Din_Buffer_Cmd,
                                             `VPC3_ADDR_New_Din_Buffer_Cmd,
                                             `DPC31_ADDR_New_Din_Buffer_Cmd);
  localparam [12:0] A_MODE_REG1_R = `DPC31B_PSEL(`SPC3_ADDR_Mode_Reg1_R, `VPC3_ADDR_Mode_Reg1_R,
                                                 `DPC31_ADDR_Mode_Reg1_R);
  localparam [12:0] A_DOUT_SM = `DPC31B_PSEL(`SPC3_ADDR_Dout_Buffer_SM,
                                             `VPC3_ADDR_Dout_Buffer_SM,
                                             `DPC31_ADDR_Dout_Buffer_SM);
  localparam [12:0] A_NEXT_DOUT = `DPC31B_PSEL(`SPC3_ADDR_Next_Dout_Buffer_Cmd,
                                               `VPC3_ADDR_Next_Dout_Buffer_Cmd,
                                               `DPC31_ADDR_Next_Dout_Buffer_Cmd);
  localparam [12:0] A_DIAG_SM = `DPC31B_PSEL(`SPC3_ADDR_Diag_Buffer_SM,
                                             `VPC3_ADDR_Diag_Buffer_SM,
                                             `DPC31_ADDR_Diag_Buffer_SM);
  localparam [12:0] A_NEW_DIAG = `DPC31B_PSEL(`SPC3_ADDR_New_Diag_Buffer_Cmd,
                                              `VPC3_ADDR_New_Diag_Buffer_Cmd,
                                              `DPC31_ADDR_New_Diag_Buffer_Cmd);
  localparam [12:0] A_PRM_OK = `DPC31B_PSEL(`SPC3_ADDR_User_Prm_Data_Okay,
                                            `VPC3_ADDR_User_Prm_Data_Okay,
                                            `DPC31_ADDR_User_Prm_Data_Okay);
  localparam [12:0] A_PRM_NOK = `DPC31B_PSEL(`SPC3_ADDR_User_Prm_Data_Not_Okay,
                                             `VPC3_ADDR_User_Prm_Data_Not_Okay,
                                             `DPC31_ADDR_User_Prm_Data_Not_Okay);
  localparam [12:0] A_CFG_OK = `DPC31B_PSEL(`SPC3_ADDR_User_Cfg_Data_Okay,
                                            `VPC3_ADDR_User_Cfg_Data_Okay,
                                            `DPC31_ADDR_User_Cfg_Data_Okay);
  localparam [12:0] A_CFG_NOK = `DPC31B_PSEL(`SPC3_ADDR_User_Cfg_Data_Not_Okay,
                                             `VPC3_ADDR_User_Cfg_Data_Not_Okay,
                                             `DPC31_ADDR_User_Cfg_Data_Not_Okay);
  localparam [12:0] A_SSA_FREE = `DPC31B_PSEL(`SPC3_ADDR_SSA_Buffer_Free_Cmd,
                                              `VPC3_ADDR_SSA_Buffer_Free_Cmd,
                                              `DPC31_ADDR_SSA_Buffer_Free_Cmd);
  // Registers of some profiles only (HAS_* guards the match).
  localparam HAS_MODE_REG1_RB = (PROFILE != 0);  // Mode_Reg1 read-back (vpc3plus, dpc31)
  localparam [12:0] A_MODE_REG1_RB = IS_VPC3 ? `VPC3_ADDR_Mode_Reg1 : `DPC31_ADDR_Mode_Reg1;
  localparam [12:0] A_MODE_REG2 = `VPC3_ADDR_Mode_Reg2;  // vpc3plus, write side
  localparam [12:0] A_PARAM_REG = `DPC31_ADDR_Param_Reg;  // dpc31

  // Mirrored organisational cells (dpc31: 0840h + (offset - 16h)).
  localparam [12:0] A_DOUT_PTR1 = `DPC31B_PSEL(`SPC3_ADDR_R_Dout_Buf_Ptr1,
                                               `VPC3_ADDR_R_Dout_Buf_Ptr1,
                                               `DPC31_ADDR_R_Dout_Buf_Ptr1);
  localparam [12:0] A_DOUT_PTR2 = `DPC31B_PSEL(`SPC3_ADDR_R_Dout_Buf_Ptr2,
                                               `VPC3_ADDR_R_Dout_Buf_Ptr2,
                                               `DPC31_ADDR_R_Dout_Buf_Ptr2);
  localparam [12:0] A_DOUT_PTR3 = `DPC31B_PSEL(`SPC3_ADDR_R_Dout_Buf_Ptr3,
                                               `VPC3_ADDR_R_Dout_Buf_Ptr3,
                                               `DPC31_ADDR_R_Dout_Buf_Ptr3);
  localparam [12:0] A_DOUT_PTR_C = `DPC31_ADDR_R_Dout_Buf_Ptr_C;  // dpc31 only
  localparam [12:0] A_CFG_PTR = `DPC31B_PSEL(`SPC3_ADDR_R_Cfg_Buf_Ptr, `VPC3_ADDR_R_Cfg_Buf_Ptr,
                                             `DPC31_ADDR_R_Cfg_Buf_Ptr);
  localparam [12:0] A_READ_CFG_PTR = `DPC31B_PSEL(`SPC3_ADDR_R_Read_Cfg_Buf_Ptr,
                                                  `VPC3_ADDR_R_Read_Cfg_Buf_Ptr,
                                                  `DPC31_ADDR_R_Read_Cfg_Buf_Ptr);
  localparam [12:0] A_GC_COMMAND = `DPC31B_PSEL(`SPC3_ADDR_R_GC_Command,
                                                `VPC3_ADDR_R_GC_Command,
                                                `DPC31_ADDR_R_GC_Command);
  localparam [12:0] A_LEN_DIN = `DPC31B_PSEL(`SPC3_ADDR_R_Len_Din_Buf, `VPC3_ADDR_R_Len_Din_Buf,
                                             `DPC31_ADDR_R_Len_Din_Buf);

  // Int_Req_Reg bit positions.
  localparam integer B_MAC_RESET = `DPC31B_PSEL(`SPC3_Int_Req_Reg_MAC_Reset_POS,
                                                `VPC3_Int_Req_Reg_MAC_Reset_POS,
                                                `DPC31_Int_Req_Reg_MAC_Reset_POS);
  localparam integer B_GO_LEAVE_DX = `DPC31B_PSEL(`SPC3_Int_Req_Reg_Go_Leave_Data_Exchange_POS,
                                                  `VPC3_Int_Req_Reg_Go_Leave_Data_Exchange_POS,
                                                  `DPC31_Int_Req_Reg_Go_Leave_Data_Exchange_POS);
  localparam integer B_BAUD_DETECT = `DPC31B_PSEL(`SPC3_Int_Req_Reg_Baudrate_Detect_POS,
                                                  `VPC3_Int_Req_Reg_Baudrate_Detect_POS,
                                                  `DPC31_Int_Req_Reg_Baudrate_Detect_POS);
  localparam integer B_WD_TIMEOUT = `DPC31B_PSEL(`SPC3_Int_Req_Reg_WD_DP_Control_Timeout_POS,
                                                 `VPC3_Int_Req_Reg_WD_DP_Control_Timeout_POS,
                                                 `DPC31_Int_Req_Reg_WD_DP_Control_Timeout_POS);
  localparam integer B_USER_TIMER = `DPC31B_PSEL(`SPC3_Int_Req_Reg_User_Timer_Clock_POS,
                                                 `VPC3_Int_Req_Reg_User_Timer_Clock_POS,
                                                 `DPC31_Int_Req_Reg_User_Timer_Clock_POS);
  localparam integer B_NEW_GC = `DPC31B_PSEL(`SPC3_Int_Req_Reg_New_GC_Command_POS,
                                             `VPC3_Int_Req_Reg_New_GC_Command_POS,
                                             `DPC31_Int_Req_Reg_New_GC_Command_POS);
  localparam integer B_NEW_SSA = `DPC31B_PSEL(`SPC3_Int_Req_Reg_New_SSA_Data_POS,
                                              `VPC3_Int_Req_Reg_New_SSA_Data_POS,
                                              `DPC31_Int_Req_Reg_New_SSA_Data_POS);
  localparam integer B_NEW_CFG = `DPC31B_PSEL(`SPC3_Int_Req_Reg_New_Cfg_Data_POS,
                                              `VPC3_Int_Req_Reg_New_Cfg_Data_POS,
                                              `DPC31_Int_Req_Reg_New_Cfg_Data_POS);
  localparam integer B_NEW_PRM = `DPC31B_PSEL(`SPC3_Int_Req_Reg_New_Prm_Data_POS,
                                              `VPC3_Int_Req_Reg_New_Prm_Data_POS,
                                              `DPC31_Int_Req_Reg_New_Prm_Data_POS);
  localparam integer B_DIAG_CHANGED = `DPC31B_PSEL(`SPC3_Int_Req_Reg_Diag_Buffer_Changed_POS,
                                                   `VPC3_Int_Req_Reg_Diag_Buffer_Changed_POS,
                                                   `DPC31_Int_Req_Reg_Diag_Buffer_Changed_POS);
  localparam integer B_DX_OUT = `DPC31B_PSEL(`SPC3_Int_Req_Reg_DX_Out_POS,
                                             `VPC3_Int_Req_Reg_DX_Out_POS,
                                             `DPC31_Int_Req_Reg_DX_Out_POS);

  localparam [15:0] IRQ_MAC_RESET = 16'd1 << B_MAC_RESET;
  localparam [15:0] IRQ_GO_LEAVE_DX = 16'd1 << B_GO_LEAVE_DX;
  localparam [15:0] IRQ_USER_TIMER = 16'd1 << B_USER_TIMER;
  localparam [15:0] IRQ_NEW_GC = 16'd1 << B_NEW_GC;
  localparam [15:0] IRQ_NEW_SSA = 16'd1 << B_NEW_SSA;
  localparam [15:0] IRQ_NEW_CFG = 16'd1 << B_NEW_CFG;
  localparam [15:0] IRQ_NEW_PRM = 16'd1 << B_NEW_PRM;
  localparam [15:0] IRQ_DIAG_CHANGED = 16'd1 << B_DIAG_CHANGED;
  localparam [15:0] IRQ_DX_OUT = 16'd1 << B_DX_OUT;

  // Writable (non-reserved) IRR / IMR bits: spc3, dpc31 3F1Fh; vpc3plus all 16 (the VPC3+'s
  // extra bits 15..14 and 7..5 are events without block state: they only come in via ev_irq).
  localparam [15:0] IRQ_COMMON = IRQ_MAC_RESET | IRQ_GO_LEAVE_DX | (16'd1 << B_BAUD_DETECT) |
                                 (16'd1 << B_WD_TIMEOUT) | IRQ_USER_TIMER | IRQ_NEW_GC |
                                 IRQ_NEW_SSA | IRQ_NEW_CFG | IRQ_NEW_PRM | IRQ_DIAG_CHANGED |
                                 IRQ_DX_OUT;
  localparam [15:0] IRQ_VPC3_EXTRA = (16'd1 << `VPC3_Int_Req_Reg_DXB_Link_Error_POS) |
                                     (16'd1 << `VPC3_Int_Req_Reg_New_Ext_Prm_Data_POS) |
                                     (16'd1 << `VPC3_Int_Req_Reg_DXB_Out_POS) |
                                     (16'd1 << `VPC3_Int_Req_Reg_Poll_End_Ind_POS) |
                                     (16'd1 << `VPC3_Int_Req_Reg_FDL_Ind_POS);
  localparam [15:0] IRR_MASK = IS_VPC3 ? (IRQ_COMMON | IRQ_VPC3_EXTRA) : IRQ_COMMON;
  // Int_Ack_Reg bits that an acknowledge does not change (IGN).
  localparam [15:0] ACK_IGN = IRQ_NEW_PRM | IRQ_NEW_CFG |
      (IS_VPC3 ? (16'd1 << `VPC3_Int_Ack_Reg_New_Ext_Prm_Data_POS) : 16'd0);

  localparam [15:0] IRR_RESET = `DPC31B_PSEL(`SPC3_Int_Req_Reg_RESET, `VPC3_Int_Req_Reg_RESET,
                                             `DPC31_Int_Req_Reg_RESET);
  localparam [15:0] IMR_RESET = `DPC31B_PSEL(`SPC3_Int_Mask_Reg_RESET, `VPC3_Int_Mask_Reg_RESET,
                                             `DPC31_Int_Mask_Reg_RESET);

  // Mode_Reg0: writable bits spc3, dpc31 37FBh; vpc3plus 7FFFh.
  localparam integer M0_INT_POL = `DPC31B_PSEL(`SPC3_Mode_Reg0_INT_Pol_POS,
                                               `VPC3_Mode_Reg0_INT_Pol_POS,
                                               `DPC31_Mode_Reg0_INT_Pol_POS);
  localparam integer M0_SYNC_SUPPORTED = `DPC31B_PSEL(`SPC3_Mode_Reg0_Sync_Supported_POS,
                                                      `VPC3_Mode_Reg0_Sync_Supported_POS,
                                                      `DPC31_Mode_Reg0_Sync_Supported_POS);
  localparam integer M0_FREEZE_SUPPORTED = `DPC31B_PSEL(`SPC3_Mode_Reg0_Freeze_Supported_POS,
                                                        `VPC3_Mode_Reg0_Freeze_Supported_POS,
                                                        `DPC31_Mode_Reg0_Freeze_Supported_POS);
  localparam integer M0_EOI_TIME_BASE = `DPC31B_PSEL(`SPC3_Mode_Reg0_EOI_Time_Base_POS,
                                                     `VPC3_Mode_Reg0_EOI_Time_Base_POS,
                                                     `DPC31_Mode_Reg0_EOI_Time_Base_POS);
  localparam integer M0_USER_TIME_BASE = `DPC31B_PSEL(`SPC3_Mode_Reg0_User_Time_Base_POS,
                                                      `VPC3_Mode_Reg0_User_Time_Base_POS,
                                                      `DPC31_Mode_Reg0_User_Time_Base_POS);
  localparam [15:0] M0_COMMON = (16'd1 << `SPC3_Mode_Reg0_Dis_Start_Control_POS) |
                                (16'd1 << `SPC3_Mode_Reg0_Dis_Stop_Control_POS) |
                                (16'd1 << `SPC3_Mode_Reg0_MinTSDR_POS) |
                                (16'd1 << M0_INT_POL) |
                                (16'd1 << `SPC3_Mode_Reg0_Early_Rdy_POS) |
                                (16'd1 << M0_SYNC_SUPPORTED) | (16'd1 << M0_FREEZE_SUPPORTED) |
                                (16'd1 << `SPC3_Mode_Reg0_DP_Mode_POS) |
                                (16'd1 << M0_EOI_TIME_BASE) | (16'd1 << M0_USER_TIME_BASE) |
                                (16'd1 << `SPC3_Mode_Reg0_Spec_Prm_Buf_Mode_POS) |
                                (16'd1 << `SPC3_Mode_Reg0_Spec_Clear_Mode_POS);
  localparam [15:0] M0_VPC3_EXTRA = (16'd1 << `VPC3_Mode_Reg0_WD_Base_POS) |
                                    (16'd1 << `VPC3_Mode_Reg0_Set_Ext_Prm_Supported_POS) |
                                    (16'd1 << `VPC3_Mode_Reg0_PrmCmd_Supported_POS);
  localparam [15:0] M0_MASK = IS_VPC3 ? (M0_COMMON | M0_VPC3_EXTRA) : M0_COMMON;
  localparam [15:0] M0_RESET = `DPC31B_PSEL(`SPC3_Mode_Reg0_RESET, `VPC3_Mode_Reg0_RESET,
                                            `DPC31_Mode_Reg0_RESET);

  // Mode_Reg1 (set / reset ports): bits spc3, dpc31 3Fh; vpc3plus BFh (En_Chk_SSAP).
  localparam integer M1_START = `DPC31B_PSEL(`SPC3_Mode_Reg1_S_Start_SPC3_POS,
                                             `VPC3_Mode_Reg1_S_Start_SPC3_POS,
                                             `DPC31_Mode_Reg1_S_Start_SPC3_POS);
  localparam integer M1_EOI = `DPC31B_PSEL(`SPC3_Mode_Reg1_S_EOI_POS, `VPC3_Mode_Reg1_S_EOI_POS,
                                           `DPC31_Mode_Reg1_S_EOI_POS);
  localparam integer M1_GO_OFFLINE = `DPC31B_PSEL(`SPC3_Mode_Reg1_S_Go_Offline_POS,
                                                  `VPC3_Mode_Reg1_S_Go_Offline_POS,
                                                  `DPC31_Mode_Reg1_S_Go_Offline_POS);
  localparam integer M1_USER_LEAVE_MASTER = `DPC31B_PSEL(`SPC3_Mode_Reg1_S_User_Leave_Master_POS,
                                                         `VPC3_Mode_Reg1_S_User_Leave_Master_POS,
                                                         `DPC31_Mode_Reg1_S_User_Leave_Master_POS);
  localparam integer M1_EN_CHANGE_CFG = `DPC31B_PSEL(`SPC3_Mode_Reg1_S_En_Change_Cfg_Buffer_POS,
                                                     `VPC3_Mode_Reg1_S_En_Change_Cfg_Buffer_POS,
                                                     `DPC31_Mode_Reg1_S_En_Change_Cfg_Buffer_POS);
  localparam integer M1_RES_USER_WD = `DPC31B_PSEL(`SPC3_Mode_Reg1_S_Res_User_WD_POS,
                                                   `VPC3_Mode_Reg1_S_Res_User_WD_POS,
                                                   `DPC31_Mode_Reg1_S_Res_User_WD_POS);
  localparam [7:0] M1_COMMON = (8'd1 << M1_START) | (8'd1 << M1_EOI) | (8'd1 << M1_GO_OFFLINE) |
                               (8'd1 << M1_USER_LEAVE_MASTER) | (8'd1 << M1_EN_CHANGE_CFG) |
                               (8'd1 << M1_RES_USER_WD);
  localparam [7:0] M1_MASK =
      IS_VPC3 ? (M1_COMMON | (8'd1 << `VPC3_Mode_Reg1_S_En_Chk_SSAP_POS)) : M1_COMMON;
  localparam [7:0] M1_PULSES = (8'd1 << M1_EOI) | (8'd1 << M1_USER_LEAVE_MASTER);
  localparam [7:0] M1_RESET = `DPC31B_PSEL(`SPC3_Mode_Reg1_RESET, `VPC3_Mode_Reg1_RESET,
                                           `DPC31_Mode_Reg1_RESET);

  // Global_Control options: dpc31 Param_Reg, vpc3plus Mode_Reg2 (bit 0 interrupt on every GC,
  // bit 1 do not check the reserved bits), spc3 none.
  localparam integer OPT_EVERY_GC = IS_VPC3 ? `VPC3_Mode_Reg2_GC_Int_Mode_POS
                                            : `DPC31_Param_Reg_New_GC_Int_Mode_POS;
  localparam integer OPT_NO_CHECK = IS_VPC3 ? `VPC3_Mode_Reg2_No_Check_GC_Reserved_POS
                                            : `DPC31_Param_Reg_Check_No_GC_Reserved_POS;
  localparam [7:0] OPT_MASK =
      (PROFILE == 0) ? 8'h00 : ((8'd1 << OPT_EVERY_GC) | (8'd1 << OPT_NO_CHECK));
  localparam [7:0] OPT_RESET = IS_VPC3 ? `VPC3_Mode_Reg2_RESET :
                               IS_DPC31 ? `DPC31_Param_Reg_RESET : 8'h00;

  // Status_Reg fields.
  localparam integer ST_STARTED = `DPC31B_PSEL(`SPC3_Status_Reg_Offline_Passive_Idle_POS,
                                               `VPC3_Status_Reg_Offline_Passive_Idle_POS,
                                               `DPC31_Status_Reg_Offline_Passive_Idle_POS);
  localparam integer ST_DIAG_FLAG = `DPC31B_PSEL(`SPC3_Status_Reg_Diag_Flag_POS,
                                                 `VPC3_Status_Reg_Diag_Flag_POS,
                                                 `DPC31_Status_Reg_Diag_Flag_POS);
  localparam integer ST_DP_STATE = `DPC31B_PSEL(`SPC3_Status_Reg_DP_State_POS,
                                                `VPC3_Status_Reg_DP_State_POS,
                                                `DPC31_Status_Reg_DP_State_POS);
  localparam integer ST_RELEASE = `DPC31B_PSEL(`SPC3_Status_Reg_Release_POS,
                                               `VPC3_Status_Reg_Release_POS,
                                               `DPC31_Status_Reg_Release_POS);

  // Buffer state machine bytes.
  localparam integer SM_D = `DPC31B_PSEL(`SPC3_Dout_Buffer_SM_D_POS, `VPC3_Dout_Buffer_SM_D_POS,
                                         `DPC31_Dout_Buffer_SM_D_POS);
  localparam integer SM_N = `DPC31B_PSEL(`SPC3_Dout_Buffer_SM_N_POS, `VPC3_Dout_Buffer_SM_N_POS,
                                         `DPC31_Dout_Buffer_SM_N_POS);
  localparam integer SM_U = `DPC31B_PSEL(`SPC3_Dout_Buffer_SM_U_POS, `VPC3_Dout_Buffer_SM_U_POS,
                                         `DPC31_Dout_Buffer_SM_U_POS);
  localparam integer SM_F = `SPC3_Din_Buffer_SM_F_POS;  // the dpc31 Dout byte does not show F
  localparam integer SM_N_CL = `DPC31_Dout_Buffer_SM_N_Cl_POS;
  localparam integer ND_STATE_U = `DPC31B_PSEL(`SPC3_Next_Dout_Buffer_Cmd_State_U_Buffer_POS,
                                               `VPC3_Next_Dout_Buffer_Cmd_State_U_Buffer_POS,
                                               `DPC31_Next_Dout_Buffer_Cmd_State_U_Buffer_POS);
  localparam integer ND_U_CLEARED = `DPC31B_PSEL(`SPC3_Next_Dout_Buffer_Cmd_U_Buffer_Cleared_POS,
                                                 `VPC3_Next_Dout_Buffer_Cmd_U_Buffer_Cleared_POS,
                                                 `DPC31_Next_Dout_Buffer_Cmd_U_Buffer_Cleared_POS);
  localparam integer DG_BUF1 = `DPC31B_PSEL(`SPC3_Diag_Buffer_SM_Diag_Buf1_State_POS,
                                            `VPC3_Diag_Buffer_SM_Diag_Buf1_State_POS,
                                            `DPC31_Diag_Buffer_SM_Diag_Buf1_State_POS);
  localparam integer DG_BUF2 = `DPC31B_PSEL(`SPC3_Diag_Buffer_SM_Diag_Buf2_State_POS,
                                            `VPC3_Diag_Buffer_SM_Diag_Buf2_State_POS,
                                            `DPC31_Diag_Buffer_SM_Diag_Buf2_State_POS);

  // Reset states: Din D=1 N=0 U=2 F=3 (E1h); Dout the same (the dpc31 byte 21h omits F: F is the
  // one buffer D, N and U leave); Diag buffer 1 User, buffer 2 SPC3 (09h).
  localparam [7:0] DIN_SM_RESET = `DPC31B_PSEL(`SPC3_Din_Buffer_SM_RESET,
                                               `VPC3_Din_Buffer_SM_RESET,
                                               `DPC31_Din_Buffer_SM_RESET);
  localparam [7:0] DOUT_SM_RESET = `DPC31B_PSEL(`SPC3_Dout_Buffer_SM_RESET,
                                                `VPC3_Dout_Buffer_SM_RESET,
                                                `DPC31_Dout_Buffer_SM_RESET);
  localparam [1:0] DOUT_D_RESET = DOUT_SM_RESET[SM_D +: 2];
  localparam [1:0] DOUT_N_RESET = DOUT_SM_RESET[SM_N +: 2];
  localparam [1:0] DOUT_U_RESET = DOUT_SM_RESET[SM_U +: 2];
  localparam [1:0] DOUT_F_RESET =
      (DOUT_N_RESET != 2'd0) ? 2'd0 : (2'd2 - DOUT_D_RESET - DOUT_U_RESET);  // 6 - D - U, mod 4
  localparam [7:0] DIAG_SM_RESET = `DPC31B_PSEL(`SPC3_Diag_Buffer_SM_RESET,
                                                `VPC3_Diag_Buffer_SM_RESET,
                                                `DPC31_Diag_Buffer_SM_RESET);

  localparam [7:0] GC_COMMAND_RESET = `DPC31B_PSEL(`SPC3_R_GC_Command_RESET,
                                                   `VPC3_R_GC_Command_RESET,
                                                   `DPC31_R_GC_Command_RESET);
  localparam [7:0] DOUT_PTR1_RESET = `DPC31B_PSEL(`SPC3_R_Dout_Buf_Ptr1_RESET,
                                                  `VPC3_R_Dout_Buf_Ptr1_RESET,
                                                  `DPC31_R_Dout_Buf_Ptr1_RESET);
  localparam [7:0] DOUT_PTR2_RESET = `DPC31B_PSEL(`SPC3_R_Dout_Buf_Ptr2_RESET,
                                                  `VPC3_R_Dout_Buf_Ptr2_RESET,
                                                  `DPC31_R_Dout_Buf_Ptr2_RESET);
  localparam [7:0] DOUT_PTR3_RESET = `DPC31B_PSEL(`SPC3_R_Dout_Buf_Ptr3_RESET,
                                                  `VPC3_R_Dout_Buf_Ptr3_RESET,
                                                  `DPC31_R_Dout_Buf_Ptr3_RESET);
  localparam [7:0] DOUT_PTR_C_RESET = IS_DPC31 ? `DPC31_R_Dout_Buf_Ptr_C_RESET : 8'h00;
  localparam [7:0] CFG_PTR_RESET = `DPC31B_PSEL(`SPC3_R_Cfg_Buf_Ptr_RESET,
                                                `VPC3_R_Cfg_Buf_Ptr_RESET,
                                                `DPC31_R_Cfg_Buf_Ptr_RESET);
  localparam [7:0] READ_CFG_PTR_RESET = `DPC31B_PSEL(`SPC3_R_Read_Cfg_Buf_Ptr_RESET,
                                                     `VPC3_R_Read_Cfg_Buf_Ptr_RESET,
                                                     `DPC31_R_Read_Cfg_Buf_Ptr_RESET);

  // Model constants (docs/timing.md, 48 MHz).
  localparam [18:0] EOI_T_1US = 19'd48;       // EOI_Time_Base = 0
  localparam [18:0] EOI_T_1MS = 19'd48000;    // EOI_Time_Base = 1
  localparam [18:0] USER_P_1MS = 19'd48000;   // User_Time_Base = 0
  localparam [18:0] USER_P_10MS = 19'd480000; // User_Time_Base = 1

  // Encodings.
  localparam [1:0] DP_WAIT_PRM = 2'b00;
  localparam [1:0] DP_WAIT_CFG = 2'b01;
  localparam [1:0] DP_DATA_EXCHANGE = 2'b10;
  localparam [1:0] DIAG_USER = 2'b01;
  localparam [1:0] DIAG_SPC3 = 2'b10;
  localparam [1:0] DIAG_SEND = 2'b11;
  localparam [1:0] NIL = 2'd0;

  // Control_Command bits.
  localparam integer GC_CLEAR_DATA = 1;
  localparam integer GC_UNFREEZE = 2;
  localparam integer GC_FREEZE = 3;
  localparam integer GC_UNSYNC = 4;
  localparam integer GC_SYNC = 5;
  localparam [7:0] GC_RESERVED = 8'hC1;  // bits 7, 6, 0

  // ===========================================================================================
  // State that is not an output port
  // ===========================================================================================
  reg        prm_newer;  // Prm handshake: a newer Set_Prm arrived while pending
  reg        cfg_newer;  // Cfg handshake: a newer Chk_Cfg arrived while pending
  reg  [7:0] opt_reg;    // dpc31 Param_Reg / vpc3plus Mode_Reg2, only the OPT_MASK bits
  reg        in_clear;   // dpc31: the current clear was signalled (N_Cl, DX_Out): once per clear
  reg  [7:0] len_din;    // mirrored cell R_Len_Din_Buf (only the user writes it)
  reg        dx_on_new_din;  // spc3: Cfg OK given, Data_Exchange at the next New_Din_Buffer_Cmd
  reg [18:0] eoi_cnt;    // cycles of EOI inactive time left; X/INT may be active only at 0
  reg [18:0] ut_cnt;     // while started: cycles to the next User_Timer_Clock
  reg  [1:0] dout_d, dout_n, dout_u, dout_f;
  reg  [1:0] din_d, din_n, din_u, din_f;
  reg  [1:0] diag1, diag2;

  // ===========================================================================================
  // Outputs combinational from registers (step 4: X/INT)
  // ===========================================================================================
  wire int_active = ((irr & ~imr) != 16'h0000) && (eoi_cnt == 19'd0);
`ifdef MUTANT_POLARITY
  assign x_int = ~int_active;
`else
  // INT_Pol = 0: low-active (the reset state), 1: high-active.
  assign x_int = mode_reg0[M0_INT_POL] ? int_active : ~int_active;
`endif
  assign dout_sm = {dout_f, dout_u, dout_n, dout_d};
  assign din_sm = {din_f, din_u, din_n, din_d};
  assign diag_sm = {diag2, diag1};

  // ===========================================================================================
  // Next state: intermediate values, changed step by step
  // ===========================================================================================
  reg [15:0] nx_irr, nx_imr, nx_mode_reg0;
  reg  [7:0] nx_mode_reg1;
  reg        nx_started;
  reg  [1:0] nx_dp_state;
  reg        nx_prm_pending, nx_prm_newer, nx_cfg_pending, nx_cfg_newer;
  reg        nx_ssa_free, nx_prm_fault, nx_cfg_fault, nx_not_supported;
  reg        nx_sync_mode, nx_freeze_mode, nx_diag_flag;
  reg  [1:0] nx_dout_d, nx_dout_n, nx_dout_u, nx_dout_f;
  reg  [1:0] nx_din_d, nx_din_n, nx_din_u, nx_din_f;
  reg  [1:0] nx_diag1, nx_diag2;
  reg        nx_u_cleared, nx_n_cleared, nx_n_cl, nx_d_fresh, nx_in_clear;
  reg  [7:0] nx_len_din;
  reg        nx_dx_on_new_din;
  reg  [7:0] nx_dout_ptr1, nx_dout_ptr2, nx_dout_ptr3, nx_dout_ptr_c;
  reg  [7:0] nx_cfg_ptr, nx_read_cfg_ptr, nx_gc_command;
  reg  [7:0] nx_opt_reg;
  reg [18:0] nx_eoi_cnt, nx_ut_cnt;
  reg  [7:0] nx_bus_rdata;
  reg [15:0] ev_set;     // IRR bits latched by steps 1 and 2 of this cycle (survive IRR / IAR)

  // Bus access decode (step 3).
  wire [12:0] a = bus_addr & ADDR_MASK;
  wire lane_hi = a[0] ^ motorola;  // 16-bit registers: Intel a+0 = bits 7..0; Motorola swapped
  wire [15:0] lane = lane_hi ? 16'hFF00 : 16'h00FF;
  wire [15:0] w16 = {bus_wdata, bus_wdata} & lane;
  reg  [15:0] rd16;     // the 16-bit register a read addresses
  reg  [15:0] ack16;    // Int_Ack_Reg: the bits an acknowledge clears
  reg   [7:0] w8;       // Mode_Reg1_S / _R: the written bits that exist
  reg   [7:0] cmd_res;  // result of a command read

  // ---------------------------------------------------------------------------- helpers
  function [18:0] eoi_time;  // T
    input [15:0] m0;
    begin
      eoi_time = m0[M0_EOI_TIME_BASE] ? EOI_T_1MS : EOI_T_1US;
`ifdef MUTANT_EOI_SHORT
      eoi_time = eoi_time - 19'd1;
`endif
    end
  endfunction

  function [18:0] user_period;  // P
    input [15:0] m0;
    begin
      user_period = m0[M0_USER_TIME_BASE] ? USER_P_10MS : USER_P_1MS;
    end
  endfunction

  // Latch interrupt requests (reserved bits ignored).
  task raise(input [15:0] bits);
    begin
      nx_irr = nx_irr | (bits & IRR_MASK);
      ev_set = ev_set | (bits & IRR_MASK);
    end
  endtask

  // ---------------------------------------------------------------------------- buffer rings
  // d_to_n / u_to_n: a side hands its buffer to N; it gets back the old N if there was one,
  // else F, and F becomes Nil.
  task hand_to_n(inout [1:0] side, inout [1:0] n, inout [1:0] f);
    reg [1:0] old_n;
    begin
      old_n = n;
      n = side;
      if (old_n != NIL) begin
        side = old_n;
      end else begin
        side = f;
        f = NIL;
      end
    end
  endtask

  // n_to_u / n_to_d: a side takes N (if N is not Nil); its old buffer becomes F; N becomes Nil
  // (unless keep_n: only for MUTANT_NEXT_DOUT_KEEPS_N).
  task take_from_n(inout [1:0] side, inout [1:0] n, inout [1:0] f, input keep_n);
    begin
      if (n != NIL) begin
        f = side;
        side = n;
        if (!keep_n) n = NIL;
      end
    end
  endtask

  task d_to_n;  // Dout: the ASIC passes D on
    begin
      hand_to_n(nx_dout_d, nx_dout_n, nx_dout_f);
    end
  endtask

  task n_to_u(input keep_n);  // Dout: the user fetches N
    begin
      take_from_n(nx_dout_u, nx_dout_n, nx_dout_f, keep_n);
    end
  endtask

  task u_to_n;  // Din: the user passes U on
    begin
      hand_to_n(nx_din_u, nx_din_n, nx_din_f);
    end
  endtask

  task n_to_d;  // Din: the ASIC takes N before sending
    begin
      take_from_n(nx_din_d, nx_din_n, nx_din_f, 1'b0);
    end
  endtask

  // ---------------------------------------------------------------------------- Dout actions
  // ev_dout (and Sync / Unsync with fresh D): d_to_n, N not cleared, D not fresh, DX_Out.
  // N_Cl = 0: newer real outputs win over a clear the user has not fetched yet.
  task dout_received;
    begin
      d_to_n;
      nx_n_cl = 1'b0;
      nx_n_cleared = 1'b0;
      nx_d_fresh = 1'b0;
      raise(IRQ_DX_OUT);
    end
  endtask

  // dout_clear: d_to_n on Dout; N is cleared; D not fresh; DX_Out.
  task dout_clear;
    begin
      d_to_n;
      nx_n_cleared = 1'b1;
      nx_d_fresh = 1'b0;
      raise(IRQ_DX_OUT);
    end
  endtask

  // failsafe_clear: spc3 / vpc3plus: dout_clear. dpc31: once per clear: if In_Clear, nothing;
  // otherwise In_Clear = 1, N_Cl = 1 and DX_Out.
  // (dpc31: D and D-fresh are left as they are; the spec names nothing else.)
  task failsafe_clear;
    begin
      if (!IS_DPC31) begin
        dout_clear;
      end else if (!nx_in_clear) begin
        nx_in_clear = 1'b1;
        nx_n_cl = 1'b1;
        raise(IRQ_DX_OUT);
      end
    end
  endtask

  // The dpc31 clear buffer C: exchange the pointer cells R_Dout_Buf_Ptr_C and R_Dout_Buf_Ptr<U>.
  task swap_c_with_u;
    reg [7:0] t;
    begin
      t = nx_dout_ptr_c;
      case (nx_dout_u)
        2'd1: begin nx_dout_ptr_c = nx_dout_ptr1; nx_dout_ptr1 = t; end
        2'd2: begin nx_dout_ptr_c = nx_dout_ptr2; nx_dout_ptr2 = t; end
        2'd3: begin nx_dout_ptr_c = nx_dout_ptr3; nx_dout_ptr3 = t; end
        default: ;  // U is never Nil
      endcase
    end
  endtask

  // ---------------------------------------------------------------------------- DP state
  // The DP state machine as at start / go_offline: Wait_Prm, handshakes idle, SSA free, faults
  // cleared, Sync / Freeze off.
  task dp_reset;
    begin
      nx_dp_state = DP_WAIT_PRM;
      nx_prm_pending = 1'b0;
      nx_prm_newer = 1'b0;
      nx_cfg_pending = 1'b0;
      nx_cfg_newer = 1'b0;
      nx_ssa_free = 1'b1;
      nx_prm_fault = 1'b0;
      nx_cfg_fault = 1'b0;
      nx_not_supported = 1'b0;
      nx_sync_mode = 1'b0;
      nx_freeze_mode = 1'b0;
      nx_dx_on_new_din = 1'b0;
    end
  endtask

  // leave_master (only while started): Wait_Prm; both handshakes idle; Sync_Mode and Freeze_Mode
  // off; N_Cl = 0; Go_Leave_Data_Exchange if the state was Data_Exchange; dout_clear.
  task leave_master;
    reg was_dx;
    begin
      if (nx_started) begin
        was_dx = (nx_dp_state == DP_DATA_EXCHANGE);
        nx_dp_state = DP_WAIT_PRM;
        nx_prm_pending = 1'b0;
        nx_prm_newer = 1'b0;
        nx_cfg_pending = 1'b0;
        nx_cfg_newer = 1'b0;
        nx_sync_mode = 1'b0;
        nx_freeze_mode = 1'b0;
        nx_n_cl = 1'b0;
        nx_in_clear = 1'b0;
        nx_dx_on_new_din = 1'b0;
        if (was_dx) raise(IRQ_GO_LEAVE_DX);
        dout_clear;
      end
    end
  endtask

  // start (Start_SPC3 written 1 while Offline).
  task start;
    begin
      nx_started = 1'b1;
      nx_mode_reg1[M1_GO_OFFLINE] = 1'b0;
      dp_reset;
      nx_n_cl = 1'b0;
      nx_in_clear = 1'b0;
      nx_ut_cnt = user_period(nx_mode_reg0);  // first tick P cycles after this cycle
      // R_GC_Command preset at every start of the DP slave: FFh dpc31, 00h spc3 (the cell's reset
      // value); the VPC3+ leaves the cell alone.
      if (!IS_VPC3) nx_gc_command = GC_COMMAND_RESET;
      dout_clear;
    end
  endtask

  // go_offline (Go_Offline written 1 while started).
  task go_offline;
    begin
      nx_started = 1'b0;
      nx_mode_reg1[M1_START] = 1'b0;
      // CHOICE: the Go_Offline bit is left as it is: normally 1 (set by this write, "stays set
      // while Offline"). Start and Go_Offline in one write: the literal order of the spec (the
      // write sets both bits, start clears Go_Offline, go_offline clears Start_SPC3) ends
      // Offline with both bits 0; we keep that literal result.
      dp_reset;
      nx_ut_cnt = 19'd0;  // user timer stops
      raise(IRQ_MAC_RESET);
    end
  endtask

  // EOI: X/INT inactive from this cycle for T cycles.
  // CHOICE: an EOI while an inactive time runs restarts it (T from this cycle).
  task eoi;
    begin
      nx_eoi_cnt = eoi_time(nx_mode_reg0);
    end
  endtask

  // ---------------------------------------------------------------------------- global_control
  task global_control(input [7:0] cmd);
    reg bad;
    begin
      bad = (((cmd & GC_RESERVED) != 8'h00) && !nx_opt_reg[OPT_NO_CHECK]) ||
            (cmd[GC_SYNC] && !nx_mode_reg0[M0_SYNC_SUPPORTED]) ||
            (cmd[GC_FREEZE] && !nx_mode_reg0[M0_FREEZE_SUPPORTED]);
      if (bad) begin
        leave_master;
        // CHOICE: Not_Supported is set even when not started (leave_master itself then does
        // nothing).
        nx_not_supported = 1'b1;
      end else begin
        if (nx_opt_reg[OPT_EVERY_GC] || (cmd != nx_gc_command)) raise(IRQ_NEW_GC);
        nx_gc_command = cmd;
        if (cmd[GC_CLEAR_DATA]) begin
`ifdef MUTANT_CLEAR_IGNORED_IN_SYNC
          if (!nx_sync_mode) failsafe_clear;
`else
          failsafe_clear;
`endif
        end
        // Sync / Unsync: D to N with DX_Out; with nothing fresh in D, DX_Out alone.
        if (cmd[GC_SYNC] || cmd[GC_UNSYNC]) begin
          nx_sync_mode = !cmd[GC_UNSYNC];  // Unsync wins
          if (!cmd[GC_CLEAR_DATA]) begin
            if (nx_d_fresh) dout_received;
            else raise(IRQ_DX_OUT);
          end
        end
        if (cmd[GC_FREEZE] || cmd[GC_UNFREEZE]) begin
          nx_freeze_mode = !cmd[GC_UNFREEZE];  // Unfreeze wins
          n_to_d;
        end
      end
    end
  endtask

  // ---------------------------------------------------------------------------- handshakes
  // arrived: if pending, a newer one arrived; pending.
  task prm_arrived;
    begin
`ifndef MUTANT_NO_CONFLICT
      if (nx_prm_pending) nx_prm_newer = 1'b1;
`endif
      nx_prm_pending = 1'b1;
    end
  endtask

  task cfg_arrived;
    begin
`ifndef MUTANT_NO_CONFLICT
      if (nx_cfg_pending) nx_cfg_newer = 1'b1;
`endif
      nx_cfg_pending = 1'b1;
    end
  endtask

  // The OK / Not_OK reads: 11 when not pending (and the event bit cleared: a leave_master may
  // have discarded what it announced); 01 (conflict, newer cleared, still pending) when a newer
  // one arrived; else 00, not pending, and the completion.
  task prm_handshake(input not_ok, output [7:0] res);
    begin
      if (!nx_prm_pending) begin
        res = 8'h03;
        nx_irr = nx_irr & ~IRQ_NEW_PRM;
      end else if (nx_prm_newer) begin
        res = 8'h01;
        nx_prm_newer = 1'b0;
      end else begin
        res = 8'h00;
        nx_prm_pending = 1'b0;
        // Not an IRR / IAR write: the command's clear wins over an event of this cycle (the
        // event made the handshake pending, and this read completes it).
        nx_irr = nx_irr & ~IRQ_NEW_PRM;
        nx_prm_fault = not_ok;
        if (not_ok) leave_master;
        else if (nx_dp_state == DP_WAIT_PRM) nx_dp_state = DP_WAIT_CFG;
      end
    end
  endtask

  task cfg_handshake(input not_ok, output [7:0] res);
    reg [7:0] t;
    begin
      if (!nx_cfg_pending) begin
        res = 8'h03;
        nx_irr = nx_irr & ~IRQ_NEW_CFG;
      end else if (nx_cfg_newer) begin
        res = 8'h01;
        nx_cfg_newer = 1'b0;
      end else begin
        res = 8'h00;
        nx_cfg_pending = 1'b0;
        nx_irr = nx_irr & ~IRQ_NEW_CFG;
        nx_cfg_fault = not_ok;
        if (not_ok) begin
          leave_master;
        end else begin
          if (nx_mode_reg1[M1_EN_CHANGE_CFG]) begin
            t = nx_cfg_ptr;
            nx_cfg_ptr = nx_read_cfg_ptr;
            nx_read_cfg_ptr = t;
          end
          // spc3 with a Din buffer (R_Len_Din_Buf != 0): at the next New_Din_Buffer_Cmd.
          if (nx_dp_state == DP_WAIT_CFG) begin
            if (IS_SPC3 && nx_len_din != 8'h00) begin
              nx_dx_on_new_din = 1'b1;
            end else begin
              nx_dp_state = DP_DATA_EXCHANGE;
              raise(IRQ_GO_LEAVE_DX);
            end
          end
        end
      end
    end
  endtask

  // ---------------------------------------------------------------------------- command reads
  // 0Bh Next_Dout_Buffer_Cmd.
  task next_dout(output [7:0] res);
    reg keep_n;
    begin
`ifdef MUTANT_NEXT_DOUT_KEEPS_N
      keep_n = 1'b1;
`else
      keep_n = 1'b0;
`endif
      if (IS_DPC31 && nx_n_cl) begin
        // The substitute values supersede outputs received before the Clear: N freed unseen.
        nx_n_cl = 1'b0;
        if (nx_dout_n != NIL) begin
          nx_dout_f = nx_dout_n;
          nx_dout_n = NIL;
        end
        nx_n_cleared = 1'b0;
`ifndef MUTANT_NO_C_SWAP
        swap_c_with_u;
`endif
        nx_u_cleared = 1'b1;
        res = (8'd1 << ND_U_CLEARED) | (8'd1 << ND_STATE_U) | {6'd0, nx_dout_u};
      end else if (nx_dout_n != NIL) begin
        n_to_u(keep_n);
        nx_u_cleared = nx_n_cleared;
        nx_n_cleared = 1'b0;
        res = (8'd1 << ND_STATE_U) | ({7'd0, nx_u_cleared} << ND_U_CLEARED) | {6'd0, nx_dout_u};
      end else begin
        res = ({7'd0, nx_u_cleared} << ND_U_CLEARED) | {6'd0, nx_dout_u};
      end
    end
  endtask

  // 0Dh New_Diag_Buffer_Cmd: the first buffer (1, then 2) in state User goes to SPC3 and
  // Diag_Flag = 1; if the other is in SPC3 it goes to User, Diag_Buffer_Changed, result its
  // number; otherwise result 00.
  task new_diag(output [7:0] res);
    begin
      res = 8'h00;
      if (nx_diag1 == DIAG_USER) begin
        nx_diag1 = DIAG_SPC3;
        nx_diag_flag = 1'b1;
        if (nx_diag2 == DIAG_SPC3) begin
          nx_diag2 = DIAG_USER;
          raise(IRQ_DIAG_CHANGED);
          res = 8'h02;
        end
      end else if (nx_diag2 == DIAG_USER) begin
        nx_diag2 = DIAG_SPC3;
        nx_diag_flag = 1'b1;
        if (nx_diag1 == DIAG_SPC3) begin
          nx_diag1 = DIAG_USER;
          raise(IRQ_DIAG_CHANGED);
          res = 8'h01;
        end
      end
    end
  endtask

  // ---------------------------------------------------------------------------- diag sending
  // ev_diag_begin: the first diag buffer (1, then 2) in state SPC3 goes to SPC3_Send_Mode.
  task diag_begin;
    begin
      if (nx_diag1 == DIAG_SPC3) nx_diag1 = DIAG_SEND;
      else if (nx_diag2 == DIAG_SPC3) nx_diag2 = DIAG_SEND;
    end
  endtask

  task diag_flag_after_send(input stat);
    begin
`ifdef MUTANT_DIAG_FLAG_STICKY
      nx_diag_flag = nx_diag_flag | stat;
`else
      nx_diag_flag = stat;
`endif
    end
  endtask

  // ev_diag_end: the buffer in Send_Mode: Diag_Flag = stat_diag; if the other buffer is SPC3,
  // the sent one goes to User and Diag_Buffer_Changed, else it goes back to SPC3.
  // CHOICE: with no buffer in Send_Mode nothing happens (Diag_Flag unchanged); with both in
  // Send_Mode (two begins without an end) buffer 1 is the one that ends.
  task diag_end(input stat);
    begin
      if (nx_diag1 == DIAG_SEND) begin
        diag_flag_after_send(stat);
        if (nx_diag2 == DIAG_SPC3) begin
          nx_diag1 = DIAG_USER;
          raise(IRQ_DIAG_CHANGED);
        end else begin
          nx_diag1 = DIAG_SPC3;
        end
      end else if (nx_diag2 == DIAG_SEND) begin
        diag_flag_after_send(stat);
        if (nx_diag1 == DIAG_SPC3) begin
          nx_diag2 = DIAG_USER;
          raise(IRQ_DIAG_CHANGED);
        end else begin
          nx_diag2 = DIAG_SPC3;
        end
      end
    end
  endtask

  // ===========================================================================================
  // One cycle
  // ===========================================================================================
  always @* begin : next_state
    // ---- the registered state
    nx_irr = irr;
    nx_imr = imr;
    nx_mode_reg0 = mode_reg0;
    nx_mode_reg1 = mode_reg1;
    nx_started = started;
    nx_dp_state = dp_state;
    nx_prm_pending = prm_pending;
    nx_prm_newer = prm_newer;
    nx_cfg_pending = cfg_pending;
    nx_cfg_newer = cfg_newer;
    nx_ssa_free = ssa_free;
    nx_prm_fault = prm_fault;
    nx_cfg_fault = cfg_fault;
    nx_not_supported = not_supported;
    nx_sync_mode = sync_mode;
    nx_freeze_mode = freeze_mode;
    nx_diag_flag = diag_flag;
    nx_dout_d = dout_d;
    nx_dout_n = dout_n;
    nx_dout_u = dout_u;
    nx_dout_f = dout_f;
    nx_din_d = din_d;
    nx_din_n = din_n;
    nx_din_u = din_u;
    nx_din_f = din_f;
    nx_diag1 = diag1;
    nx_diag2 = diag2;
    nx_u_cleared = u_cleared;
    nx_n_cleared = n_cleared;
    nx_n_cl = n_cl;
    nx_d_fresh = d_fresh;
    nx_in_clear = in_clear;
    nx_len_din = len_din;
    nx_dx_on_new_din = dx_on_new_din;
    nx_dout_ptr1 = dout_ptr1;
    nx_dout_ptr2 = dout_ptr2;
    nx_dout_ptr3 = dout_ptr3;
    nx_dout_ptr_c = dout_ptr_c;
    nx_cfg_ptr = cfg_ptr;
    nx_read_cfg_ptr = read_cfg_ptr;
    nx_gc_command = gc_command;
    nx_opt_reg = opt_reg;
    nx_eoi_cnt = eoi_cnt;
    nx_ut_cnt = ut_cnt;
    nx_bus_rdata = bus_rdata;  // holds its value until the next read
    ev_set = 16'h0000;
    rd16 = 16'h0000;
    w8 = 8'h00;
    ack16 = 16'h0000;
    cmd_res = 8'h00;

    // ================================================================= step 1: timers
    // The EOI inactive time running out (0 from cycle e + T on).
    if (nx_eoi_cnt != 19'd0) nx_eoi_cnt = nx_eoi_cnt - 19'd1;
    // User_Timer_Clock: while started, in cycles s + P, s + 2P, ...
    if (nx_started) begin
      if (nx_ut_cnt <= 19'd1) begin
        raise(IRQ_USER_TIMER);
        nx_ut_cnt = user_period(nx_mode_reg0);
      end else begin
        nx_ut_cnt = nx_ut_cnt - 19'd1;
      end
    end

    // ================================================================= step 2: events
    // ev_dx: a Data_Exchange arrived; the user watchdog takes Res_User_WD (Mode_Reg1 bit 5).
    if (ev_dx) nx_mode_reg1[5] = 1'b0;

    // ev_irq: events with no block state.
    raise(ev_irq);

    // ev_leave_master
    if (ev_leave_master) leave_master;

    // ev_prm_fault: a Set_Prm failed the ASIC's checks: leave_master, Prm_Fault.
    if (ev_prm_fault) begin
      leave_master;
      nx_prm_fault = 1'b1;
    end

    // ev_gc: an accepted Global_Control.
    if (ev_gc) global_control(gc_cmd);

    // ev_dout: D holds fresh data; unless Sync_Mode: d_to_n, N not cleared, D not fresh, DX_Out.
    if (ev_dout) begin
      nx_d_fresh = 1'b1;
      nx_in_clear = 1'b0;  // the master has left Clear
      if (!nx_sync_mode) dout_received;
    end

    // ev_failsafe: Data_Exchange with no outputs.
    if (ev_failsafe) failsafe_clear;

    // ev_din: unless Freeze_Mode: n_to_d on Din.
    if (ev_din) begin
`ifdef MUTANT_FREEZE_IGNORED
      n_to_d;
`else
      if (!nx_freeze_mode) n_to_d;
`endif
    end

    if (ev_diag_begin) diag_begin;
    if (ev_diag_end) diag_end(stat_diag);

    // ev_dis: Set_Prm in DP mode writes Dis_Start_Control / Dis_Stop_Control (Mode_Reg0 1:0).
    if (ev_dis) nx_mode_reg0[1:0] = dis_bits;

    // ev_prm: the fault bits cleared; Prm handshake arrived; New_Prm_Data.
    if (ev_prm) begin
      nx_prm_fault = 1'b0;
      nx_cfg_fault = 1'b0;
      nx_not_supported = 1'b0;
      nx_dx_on_new_din = 1'b0;  // the new parameters need their verdicts again
      prm_arrived;
      raise(IRQ_NEW_PRM);
    end

    // ev_cfg: in Data_Exchange: Wait_Cfg and Go_Leave_Data_Exchange; Cfg arrived; New_Cfg_Data.
    if (ev_cfg) begin
      if (nx_dp_state == DP_DATA_EXCHANGE) begin
        nx_dp_state = DP_WAIT_CFG;
        raise(IRQ_GO_LEAVE_DX);
      end
      nx_dx_on_new_din = 1'b0;  // the new configuration needs its verdict again
      cfg_arrived;
      raise(IRQ_NEW_CFG);
    end

    // ev_ssa: SSA buffer not free; New_SSA_Data.
    if (ev_ssa) begin
      nx_ssa_free = 1'b0;
      raise(IRQ_NEW_SSA);
    end

    // ================================================================= step 3: bus access
    // CHOICE: the spec allows at most one access per cycle; should both strobes come, the read
    // is done and the write dropped.
    if (bus_rd) begin
      nx_bus_rdata = 8'h00;  // other addresses read 00h
      if (a[12:1] == A_IRR[12:1]) begin
        rd16 = nx_irr;
        nx_bus_rdata = lane_hi ? rd16[15:8] : rd16[7:0];
      end else if (a[12:1] == A_INT_REG[12:1]) begin
        rd16 = nx_irr & ~nx_imr;
        nx_bus_rdata = lane_hi ? rd16[15:8] : rd16[7:0];
      end else if (a[12:1] == A_STATUS[12:1]) begin
        rd16 = ({12'd0, asic_type} << ST_RELEASE) | ({15'd0, nx_started} << ST_STARTED) |
               ({15'd0, nx_diag_flag} << ST_DIAG_FLAG) | ({14'd0, nx_dp_state} << ST_DP_STATE);
        nx_bus_rdata = lane_hi ? rd16[15:8] : rd16[7:0];
      end else if (a[12:1] == A_MODE_REG0[12:1]) begin
        rd16 = nx_mode_reg0;
        nx_bus_rdata = lane_hi ? rd16[15:8] : rd16[7:0];
      end else if (a == A_DIN_SM) begin
        nx_bus_rdata = ({6'd0, nx_din_f} << SM_F) | ({6'd0, nx_din_u} << SM_U) |
                       ({6'd0, nx_din_n} << SM_N) | ({6'd0, nx_din_d} << SM_D);
      end else if (a == A_NEW_DIN) begin
        // u_to_n on Din; the result is the new U. spc3 after Cfg OK: Data_Exchange now.
        u_to_n;
        nx_bus_rdata = {6'd0, nx_din_u};
        if (nx_dx_on_new_din && nx_dp_state == DP_WAIT_CFG) begin
          nx_dx_on_new_din = 1'b0;
          nx_dp_state = DP_DATA_EXCHANGE;
          raise(IRQ_GO_LEAVE_DX);
        end
      end else if (a == A_DOUT_SM) begin
        if (IS_DPC31)  // bit 7 N_Cl, bits 5..0 U N D
          nx_bus_rdata = ({7'd0, nx_n_cl} << SM_N_CL) | ({6'd0, nx_dout_u} << SM_U) |
                         ({6'd0, nx_dout_n} << SM_N) | ({6'd0, nx_dout_d} << SM_D);
        else
          nx_bus_rdata = ({6'd0, nx_dout_f} << SM_F) | ({6'd0, nx_dout_u} << SM_U) |
                         ({6'd0, nx_dout_n} << SM_N) | ({6'd0, nx_dout_d} << SM_D);
      end else if (a == A_NEXT_DOUT) begin
        next_dout(cmd_res);
        nx_bus_rdata = cmd_res;
      end else if (a == A_DIAG_SM) begin
        nx_bus_rdata = ({6'd0, nx_diag2} << DG_BUF2) | ({6'd0, nx_diag1} << DG_BUF1);
      end else if (a == A_NEW_DIAG) begin
        new_diag(cmd_res);
        nx_bus_rdata = cmd_res;
      end else if (a == A_PRM_OK || a == A_PRM_NOK) begin
        prm_handshake(a == A_PRM_NOK, cmd_res);
        nx_bus_rdata = cmd_res;
      end else if (a == A_CFG_OK || a == A_CFG_NOK) begin
        cfg_handshake(a == A_CFG_NOK, cmd_res);
        nx_bus_rdata = cmd_res;
      end else if (a == A_SSA_FREE) begin
        nx_ssa_free = 1'b1;
        nx_bus_rdata = 8'h00;
      end else if (HAS_MODE_REG1_RB && a == A_MODE_REG1_RB) begin
        nx_bus_rdata = nx_mode_reg1;
      end else if (IS_DPC31 && a == A_PARAM_REG) begin
        nx_bus_rdata = nx_opt_reg;
      end else if (a == A_DOUT_PTR1) begin
        nx_bus_rdata = nx_dout_ptr1;
      end else if (a == A_DOUT_PTR2) begin
        nx_bus_rdata = nx_dout_ptr2;
      end else if (a == A_DOUT_PTR3) begin
        nx_bus_rdata = nx_dout_ptr3;
      end else if (IS_DPC31 && a == A_DOUT_PTR_C) begin
        nx_bus_rdata = nx_dout_ptr_c;
      end else if (a == A_CFG_PTR) begin
        nx_bus_rdata = nx_cfg_ptr;
      end else if (a == A_READ_CFG_PTR) begin
        nx_bus_rdata = nx_read_cfg_ptr;
      end else if (a == A_GC_COMMAND) begin
        nx_bus_rdata = nx_gc_command;
      end
    end else if (bus_wr) begin
      if (a[12:1] == A_IRR[12:1]) begin
        // Int_Req_Reg (RW): an event latched in steps 1-2 of this cycle survives.
        nx_irr = (nx_irr & ~(lane & IRR_MASK)) | (w16 & IRR_MASK);
        nx_irr = nx_irr | ev_set;
      end else if (a[12:1] == A_IAR[12:1]) begin
        // Int_Ack_Reg (W1C; New_Prm_Data / New_Cfg_Data / vpc3plus New_Ext_Prm_Data IGN).
        ack16 = w16 & IRR_MASK & ~ACK_IGN;
`ifdef MUTANT_ACK_NEIGHBOUR
        ack16 = ack16 | ((ack16 << 1) & IRR_MASK & ~ACK_IGN);
`endif
        nx_irr = nx_irr & ~ack16;
`ifndef MUTANT_ACK_BEATS_EVENT
        nx_irr = nx_irr | ev_set;
`endif
      end else if (a[12:1] == A_IMR[12:1]) begin
        // Int_Mask_Reg (WO): reserved bits keep their reset value 1.
        nx_imr = (nx_imr & ~(lane & IRR_MASK)) | (w16 & IRR_MASK);
      end else if (a[12:1] == A_MODE_REG0[12:1]) begin
        // Mode_Reg0: a write is ignored while started.
        if (!nx_started) nx_mode_reg0 = (nx_mode_reg0 & ~(lane & M0_MASK)) | (w16 & M0_MASK);
      end else if (a == A_MODE_REG1_S) begin
        // Mode_Reg1_S: a 1 sets the bit (EOI and User_Leave_Master are pulses, never stored);
        // actions in the order Start, EOI, User_Leave_Master, Go_Offline.
        w8 = bus_wdata & M1_MASK;
        nx_mode_reg1 = nx_mode_reg1 | (w8 & ~M1_PULSES);
        if (w8[M1_START] && !nx_started) start;
        if (w8[M1_EOI]) eoi;
        if (w8[M1_USER_LEAVE_MASTER]) leave_master;
        if (w8[M1_GO_OFFLINE] && nx_started) go_offline;
      end else if (a == A_MODE_REG1_R) begin
        // Mode_Reg1_R: a 1 clears the bit.
        // CHOICE: no actions: clearing Start_SPC3 does not stop the chip (decisions.md), a 1 in
        // the EOI / User_Leave_Master positions does nothing (they are pulses of the set port).
        w8 = bus_wdata & M1_MASK;
        nx_mode_reg1 = nx_mode_reg1 & ~w8;
      end else if (IS_VPC3 && a == A_MODE_REG2) begin
        // vpc3plus Mode_Reg2: only bits 0 and 1 matter here; written only while Offline.
        if (!nx_started) nx_opt_reg = bus_wdata & OPT_MASK;
      end else if (IS_DPC31 && a == A_PARAM_REG) begin
        // dpc31 Param_Reg (RW, reserved bits 7..2 not writable).
        // CHOICE: writable also while started (no restriction is documented for it).
        nx_opt_reg = bus_wdata & OPT_MASK;
      end else if (a == A_DOUT_PTR1) begin
        nx_dout_ptr1 = bus_wdata;
      end else if (a == A_DOUT_PTR2) begin
        nx_dout_ptr2 = bus_wdata;
      end else if (a == A_DOUT_PTR3) begin
        nx_dout_ptr3 = bus_wdata;
      end else if (IS_DPC31 && a == A_DOUT_PTR_C) begin
        nx_dout_ptr_c = bus_wdata;
      end else if (a == A_CFG_PTR) begin
        nx_cfg_ptr = bus_wdata;
      end else if (a == A_READ_CFG_PTR) begin
        nx_read_cfg_ptr = bus_wdata;
      end else if (a == A_GC_COMMAND) begin
        nx_gc_command = bus_wdata;
      end else if (a == A_LEN_DIN) begin
        nx_len_din = bus_wdata;
      end
      // Other write addresses (WD_Baud_Control_Val, MinTSDR_Val, reserved, RAM) are not part of
      // the block.
    end
    // ================================================================= step 4: X/INT
    // combinational from the registered result (x_int above).
  end

  // ===========================================================================================
  // Registers
  // ===========================================================================================
  always @(posedge clk) begin
    if (rst) begin
      // The hardware-reset state; nothing else happens in this cycle.
      irr <= IRR_RESET;
      imr <= IMR_RESET;
      mode_reg0 <= M0_RESET;
      mode_reg1 <= M1_RESET;
      started <= 1'b0;
      dp_state <= DP_WAIT_PRM;
      prm_pending <= 1'b0;
      prm_newer <= 1'b0;
      cfg_pending <= 1'b0;
      cfg_newer <= 1'b0;
      ssa_free <= 1'b1;
      prm_fault <= 1'b0;
      cfg_fault <= 1'b0;
      not_supported <= 1'b0;
      sync_mode <= 1'b0;
      freeze_mode <= 1'b0;
      diag_flag <= 1'b0;
      dout_d <= DOUT_D_RESET;
      dout_n <= DOUT_N_RESET;
      dout_u <= DOUT_U_RESET;
      dout_f <= DOUT_F_RESET;
      din_d <= DIN_SM_RESET[SM_D +: 2];
      din_n <= DIN_SM_RESET[SM_N +: 2];
      din_u <= DIN_SM_RESET[SM_U +: 2];
      din_f <= DIN_SM_RESET[SM_F +: 2];
      diag1 <= DIAG_SM_RESET[DG_BUF1 +: 2];
      diag2 <= DIAG_SM_RESET[DG_BUF2 +: 2];
      u_cleared <= 1'b0;
      n_cleared <= 1'b0;
      n_cl <= 1'b0;
      d_fresh <= 1'b0;
      in_clear <= 1'b0;
      len_din <= `SPC3_R_Len_Din_Buf_RESET;
      dx_on_new_din <= 1'b0;
      dout_ptr1 <= DOUT_PTR1_RESET;
      dout_ptr2 <= DOUT_PTR2_RESET;
      dout_ptr3 <= DOUT_PTR3_RESET;
      dout_ptr_c <= DOUT_PTR_C_RESET;
      cfg_ptr <= CFG_PTR_RESET;
      read_cfg_ptr <= READ_CFG_PTR_RESET;
      gc_command <= GC_COMMAND_RESET;
      opt_reg <= OPT_RESET & OPT_MASK;
      eoi_cnt <= 19'd0;
      ut_cnt <= 19'd0;
      // CHOICE: bus_rdata resets to 00h.
      bus_rdata <= 8'h00;
    end else begin
      irr <= nx_irr;
      imr <= nx_imr;
      mode_reg0 <= nx_mode_reg0;
      mode_reg1 <= nx_mode_reg1;
      started <= nx_started;
      dp_state <= nx_dp_state;
      prm_pending <= nx_prm_pending;
      prm_newer <= nx_prm_newer;
      cfg_pending <= nx_cfg_pending;
      cfg_newer <= nx_cfg_newer;
      ssa_free <= nx_ssa_free;
      prm_fault <= nx_prm_fault;
      cfg_fault <= nx_cfg_fault;
      not_supported <= nx_not_supported;
      sync_mode <= nx_sync_mode;
      freeze_mode <= nx_freeze_mode;
      diag_flag <= nx_diag_flag;
      dout_d <= nx_dout_d;
      dout_n <= nx_dout_n;
      dout_u <= nx_dout_u;
      dout_f <= nx_dout_f;
      din_d <= nx_din_d;
      din_n <= nx_din_n;
      din_u <= nx_din_u;
      din_f <= nx_din_f;
      diag1 <= nx_diag1;
      diag2 <= nx_diag2;
      u_cleared <= nx_u_cleared;
      n_cleared <= nx_n_cleared;
      n_cl <= nx_n_cl;
      d_fresh <= nx_d_fresh;
      in_clear <= nx_in_clear;
      len_din <= nx_len_din;
      dx_on_new_din <= nx_dx_on_new_din;
      dout_ptr1 <= nx_dout_ptr1;
      dout_ptr2 <= nx_dout_ptr2;
      dout_ptr3 <= nx_dout_ptr3;
      dout_ptr_c <= nx_dout_ptr_c;
      cfg_ptr <= nx_cfg_ptr;
      read_cfg_ptr <= nx_read_cfg_ptr;
      gc_command <= nx_gc_command;
      opt_reg <= nx_opt_reg;
      eoi_cnt <= nx_eoi_cnt;
      ut_cnt <= nx_ut_cnt;
      bus_rdata <= nx_bus_rdata;
    end
  end

endmodule

`undef DPC31B_PSEL
