// dpc31_blocks_constants.vh -- included inside module dpc31_blocks (rtl/dpc31_blocks.v): the
// constants from the register description (rtl/dpc31_regs.vh) selected by PROFILE, the reset
// states, the model's timing constants and encodings.
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
  localparam [15:0] IRQ_WD_TIMEOUT = 16'd1 << B_WD_TIMEOUT;
  localparam [15:0] IRQ_USER_TIMER = 16'd1 << B_USER_TIMER;
  localparam [15:0] IRQ_NEW_GC = 16'd1 << B_NEW_GC;
  localparam [15:0] IRQ_NEW_SSA = 16'd1 << B_NEW_SSA;
  localparam [15:0] IRQ_NEW_CFG = 16'd1 << B_NEW_CFG;
  localparam [15:0] IRQ_NEW_PRM = 16'd1 << B_NEW_PRM;
  localparam [15:0] IRQ_DIAG_CHANGED = 16'd1 << B_DIAG_CHANGED;
  localparam [15:0] IRQ_DX_OUT = 16'd1 << B_DX_OUT;

  // Writable (non-reserved) IRR / IMR bits: spc3 3F1Fh, dpc31 3F3Fh; vpc3plus all 16 (the VPC3+'s
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
  // The DPC31's Indication (bit 5, docs/dpc31.md) is an event without block state here: the
  // request interface is not one of the blocks this model covers, it only comes in via ev_irq.
  localparam [15:0] IRQ_DPC31_EXTRA = 16'd1 << `DPC31_Int_Req_Reg_Indication_POS;
  localparam [15:0] IRR_MASK = IS_VPC3  ? (IRQ_COMMON | IRQ_VPC3_EXTRA) :
                               IS_DPC31 ? (IRQ_COMMON | IRQ_DPC31_EXTRA) : IRQ_COMMON;
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

  // Mode_Reg1 (set / reset ports): bits spc3 3Fh, dpc31 12h, vpc3plus BFh (En_Chk_SSAP).
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
  // dpc31: Start_SPC3, Go_Offline, User_Leave_Master and Res_User_WD are IGN (the DPC31 takes
  // them as requests, ev_mac_start / ev_mac_stop / ev_leave_master): EOI and En_Change_Cfg_Buffer.
  localparam [7:0] M1_MASK =
      IS_VPC3  ? (M1_COMMON | (8'd1 << `VPC3_Mode_Reg1_S_En_Chk_SSAP_POS)) :
      IS_DPC31 ? ((8'd1 << M1_EOI) | (8'd1 << M1_EN_CHANGE_CFG)) : M1_COMMON;
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

  // vpc3plus, DPV1: the SAP list and its buffer headers in RAM (VPC3+C pp. 54-56, docs/dpv1.md;
  // the layout of include/dpc31/dpv1.hpp). The block mirrors the user area of the RAM.
  localparam [12:0] USER_BASE = `VPC3_USER_BASE;
  localparam integer RAM_WORDS = `VPC3_RAM_SIZE_LARGE;
  localparam integer M2_4KB_MODE = `VPC3_Mode_Reg2_4kB_Mode_POS;
  localparam [15:0] IRQ_NEW_EXT_PRM = 16'd1 << `VPC3_Int_Req_Reg_New_Ext_Prm_Data_POS;
  localparam [15:0] IRQ_POLL_END = 16'd1 << `VPC3_Int_Req_Reg_Poll_End_Ind_POS;
  localparam [15:0] IRQ_FDL_IND = 16'd1 << `VPC3_Int_Req_Reg_FDL_Ind_POS;
  // Entry byte offsets (Figure 7-3) and byte 0's Response_Sent.
  localparam [12:0] SE_IND0 = 13'd4;
  localparam [12:0] SE_IND1 = 13'd5;
  localparam [12:0] SE_RESP = 13'd6;
  localparam [7:0] SE_RESPONSE_SENT = 8'h80;
  // Header (Figure 7-4): byte 0 Control, byte 1 Max_Length; the Control bits.
  localparam [11:0] SH_MAX_LENGTH = 12'd1;
  localparam [7:0] HC_USER = 8'h80;
  localparam [7:0] HC_IND = 8'h40;
  localparam [7:0] HC_RESP = 8'h20;
  localparam [7:0] HC_INUSE = 8'h10;

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

`ifdef MUTANTS
  // Mutants: the values of mutant_sel, 0 none (rtl/CMakeLists.txt reads the names and values
  // from these lines; docs/golden-model.md says what each breaks).
  // Next_Dout_Buffer_Cmd's n_to_u leaves N as it was
  localparam [3:0] MUT_NEXT_DOUT_KEEPS_N = 4'd1;
  // an acknowledge of bit k also clears bit k+1
  localparam [3:0] MUT_ACK_NEIGHBOUR = 4'd2;
  // EOI inactive time one cycle shorter
  localparam [3:0] MUT_EOI_SHORT = 4'd3;
  // Clear_Data has no effect while Sync_Mode
  localparam [3:0] MUT_CLEAR_IGNORED_IN_SYNC = 4'd4;
  // dpc31: the C/U pointer cells are not exchanged
  localparam [3:0] MUT_NO_C_SWAP = 4'd5;
  // an event and its acknowledge in one cycle: the bit ends cleared
  localparam [3:0] MUT_ACK_BEATS_EVENT = 4'd6;
  // INT_Pol ignored: X/INT always low-active
  localparam [3:0] MUT_POLARITY = 4'd7;
  // ev_din fetches N even in Freeze_Mode
  localparam [3:0] MUT_FREEZE_IGNORED = 4'd8;
  // the handshakes never answer 01: a newer arrival is ignored
  localparam [3:0] MUT_NO_CONFLICT = 4'd9;
  // ev_diag_end leaves Diag_Flag at 1 when stat_diag is 0
  localparam [3:0] MUT_DIAG_FLAG_STICKY = 4'd10;
  // the first User_Timer_Clock after a start one cycle late (P + 1)
  localparam [3:0] MUT_USER_TIMER_LATE = 4'd15;
  // The SAP-buffer header machine (vpc3plus, DPV1): the mutants below are built into the
  // vpc3plus mutants' model (rtl/CMakeLists.txt reads the trailing "vpc3plus").
  // an indication is handed over with USER alone: IND is not set
  localparam [3:0] MUT_SAP_IND_NOT_SET = 4'd11;  // vpc3plus
  // after the response is sent USER is cleared, RESP is not
  localparam [3:0] MUT_SAP_RESP_KEPT = 4'd12;  // vpc3plus
  // no free indication buffer: the request overwrites buffer 0 instead of RR
  localparam [3:0] MUT_SAP_NO_RR = 4'd13;  // vpc3plus
  // Poll_End_Ind raised when the response is chosen, before its last character is out
  localparam [3:0] MUT_SAP_POLL_END_EARLY = 4'd14;  // vpc3plus
`endif
