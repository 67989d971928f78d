// dpc31_blocks.v -- second, independent implementation of the blocks of docs/golden-model.md:
// interrupt controller, mode registers, buffer state machines with their command reads, the DP
// handshakes. Verilog-2005, one clock, synchronous active-high reset.
//
// Structure: one combinational block computes the state after the cycle through a chain of
// intermediate values (nx_*), in the order of docs/golden-model.md "Time and order":
//   1. timers  2. event inputs in table order  3. the bus access  4. X/INT (from the registers).
// Each action is one task of dpc31_blocks_actions.vh, named as in the spec (d_to_n, dout_clear,
// leave_master, global_control...); the constants: dpc31_blocks_constants.vh. The sequential
// block only registers nx_*. All outputs are registers or combinational from registers, so after
// the clock edge of cycle c they show the state after cycle c.
//
// Where the spec leaves a choice, the choice is written at the spot, marked "CHOICE:".
//
// Mutants (each changes only the named behaviour, docs/golden-model.md): with `define MUTANTS the
// module has one more input, mutant_sel, whose value (MUT_* in dpc31_blocks_constants.vh, 0 none)
// switches one of them on at run time, so one Verilated model carries all ten. Without MUTANTS
// (the profile models) every mutant condition is the constant 0: no port, no logic; Verilator
// generates for them the same C++ as from the model before it had mutants.

`include "dpc31_regs.vh"

// Profile selection of a register-description constant: spc3, vpc3plus, dpc31.
`define DPC31B_PSEL(s3, v3, d31) ((PROFILE == 0) ? (s3) : (PROFILE == 1) ? (v3) : (d31))
// Is mutant m (a MUT_* value) switched on?
`ifdef MUTANTS
`define DPC31B_MUT(m) (mutant_sel == (m))
`else
`define DPC31B_MUT(m) 1'b0
`endif

module dpc31_blocks #(
  parameter PROFILE = 2  // 0 spc3, 1 vpc3plus, 2 dpc31 (any other value behaves as dpc31)
) (
  input  wire        clk,
  input  wire        rst,
`ifdef MUTANTS
  input  wire  [3:0] mutant_sel,  // constant during a run: MUT_* or 0
`endif
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
  input  wire        ev_wd_expired,  // the DP watchdog expired in DP_Control
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
  input  wire        ev_mac_stop,   // dpc31: a MAC_Stop request (the Instruction_Queue)
  input  wire        ev_mac_start,  // dpc31: a MAC_Start request
  // vpc3plus, DPV1: the SAP-buffer header machine (docs/golden-model.md)
  input  wire        ev_ext_prm,   // a Set_Ext_Prm is in the Prm buffer
  input  wire        ev_sap_sent,  // the last stop bit of a SAP-list response is out
  input  wire        ev_sap_ind,   // a request with sap_len data bytes for the entry at sap_entry
  input  wire        ev_sap_srd,   // an SRD for the entry at sap_entry: response or SC
  input  wire [12:0] sap_entry,
  input  wire  [7:0] sap_len,
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

  `include "dpc31_blocks_constants.vh"

  // ===========================================================================================
  // State that is not an output port
  // ===========================================================================================
  reg        prm_newer;  // Prm handshake: a newer Set_Prm arrived while pending
  reg        cfg_newer;  // Cfg handshake: a newer Chk_Cfg arrived while pending
  reg  [7:0] opt_reg;    // dpc31 Param_Reg / vpc3plus Mode_Reg2, only the OPT_MASK bits
  reg        in_clear;   // dpc31: the current clear was signalled (N_Cl, DX_Out): once per clear
  reg  [7:0] len_din;    // mirrored cell R_Len_Din_Buf (only the user writes it)
  reg        dx_deferred;  // Cfg OK given, DX waits: spc3 New_Din_Buffer_Cmd, vpc3plus Ext_Prm OK
  reg [18:0] eoi_cnt;    // cycles of EOI inactive time left; X/INT may be active only at 0
  reg [18:0] ut_cnt;     // while started: cycles to the next User_Timer_Clock
  reg  [1:0] dout_d, dout_n, dout_u, dout_f;
  reg  [1:0] din_d, din_n, din_u, din_f;
  reg  [1:0] diag1, diag2;
  // vpc3plus, DPV1
  reg        ext_prm;         // the Prm verdict pending is a Set_Ext_Prm's (New_Ext_Prm_Data)
  reg        large_ram;       // Mode_Reg2.4kB_Mode: 16-byte segments
  reg        sap_sending;     // a response buffer is on the wire
  reg [11:0] sap_sent_entry;  // its entry (RAM index)
  reg [11:0] sap_resp;        // its header (RAM index)
  // The user area of the RAM as the user writes it and the header machine changes it. Written
  // with blocking assignments inside the clocked process (one evaluation per cycle, in order).
  reg  [7:0] ram [0:RAM_WORDS-1];
  integer    ram_i;

  // ===========================================================================================
  // Outputs combinational from registers (step 4: X/INT)
  // ===========================================================================================
  wire int_active = ((irr & ~imr) != 16'h0000) && (eoi_cnt == 19'd0);
  // INT_Pol = 0: low-active (the reset state), 1: high-active.
  assign x_int = (mode_reg0[M0_INT_POL] && !`DPC31B_MUT(MUT_POLARITY)) ? int_active : ~int_active;
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
  reg        nx_dx_deferred;
  reg  [7:0] nx_dout_ptr1, nx_dout_ptr2, nx_dout_ptr3, nx_dout_ptr_c;
  reg  [7:0] nx_cfg_ptr, nx_read_cfg_ptr, nx_gc_command;
  reg  [7:0] nx_opt_reg;
  reg [18:0] nx_eoi_cnt, nx_ut_cnt;
  reg  [7:0] nx_bus_rdata;
  reg [15:0] ev_set;     // IRR bits latched by steps 1 and 2 of this cycle (survive IRR / IAR)
  reg        nx_ext_prm, nx_large_ram, nx_sap_sending;
  reg [11:0] nx_sap_sent_entry, nx_sap_resp;

  // Bus access decode (step 3).
  wire [12:0] a = bus_addr & ADDR_MASK;
  wire lane_hi = a[0] ^ motorola;  // 16-bit registers: Intel a+0 = bits 7..0; Motorola swapped
  wire [15:0] lane = lane_hi ? 16'hFF00 : 16'h00FF;
  wire [15:0] w16 = {bus_wdata, bus_wdata} & lane;
  reg  [15:0] rd16;     // the 16-bit register a read addresses
  reg  [15:0] ack16;    // Int_Ack_Reg: the bits an acknowledge clears
  reg   [7:0] w8;       // Mode_Reg1_S / _R: the written bits that exist
  reg   [7:0] cmd_res;  // result of a command read

  // The actions and next_state below assign the nx_* values with blocking assignments inside the
  // clocked process, on purpose (one evaluation per cycle); only the registers take '<='.
  /* verilator lint_off BLKSEQ */
  `include "dpc31_blocks_actions.vh"

  // ===========================================================================================
  // One cycle: the next state from the registered state and this cycle's inputs. A task called
  // by the clocked process, not an always @* block: a simulator then computes it once per cycle
  // (Verilator ran a combinational block at every eval and again after every register update:
  // three times per cycle, docs/golden-model.md).
  // ===========================================================================================
  task next_state;
    begin
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
    nx_dx_deferred = dx_deferred;
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
    nx_ext_prm = ext_prm;
    nx_large_ram = large_ram;
    nx_sap_sending = sap_sending;
    nx_sap_sent_entry = sap_sent_entry;
    nx_sap_resp = sap_resp;
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

    // ev_wd_expired: WD_DP_Control_Timeout; leave_master; the DPC31 resets its SSA state machine
    // ("the watchdog has expired in the mode 'DP_Control'", DPC31 p.26): SSA free.
    if (ev_wd_expired) begin
      raise(IRQ_WD_TIMEOUT);
      leave_master;
      if (IS_DPC31) nx_ssa_free = 1'b1;
    end

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
      if (!nx_freeze_mode || `DPC31B_MUT(MUT_FREEZE_IGNORED)) n_to_d;
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
      nx_dx_deferred = 1'b0;  // the new parameters need their verdicts again
      nx_ext_prm = 1'b0;
      prm_arrived;
      raise(IRQ_NEW_PRM);
    end

    // ev_ext_prm (vpc3plus): Prm handshake arrived, for a Set_Ext_Prm; New_Ext_Prm_Data.
    if (IS_VPC3 && ev_ext_prm) begin
      prm_arrived;
      nx_ext_prm = 1'b1;
      raise(IRQ_NEW_EXT_PRM);
    end

    // ev_cfg: in Data_Exchange: Wait_Cfg and Go_Leave_Data_Exchange; Cfg arrived; New_Cfg_Data.
    if (ev_cfg) begin
      if (nx_dp_state == DP_DATA_EXCHANGE) begin
        nx_dp_state = DP_WAIT_CFG;
        raise(IRQ_GO_LEAVE_DX);
      end
      nx_dx_deferred = 1'b0;  // the new configuration needs its verdict again
      cfg_arrived;
      raise(IRQ_NEW_CFG);
    end

    // ev_ssa: SSA buffer not free; New_SSA_Data.
    if (ev_ssa) begin
      nx_ssa_free = 1'b0;
      raise(IRQ_NEW_SSA);
    end

    // The SAP-buffer header machine (vpc3plus): the response that was on the wire, then the
    // request's data into an indication buffer, then its answer.
    if (IS_VPC3 && ev_sap_sent) sap_response_sent;
    if (IS_VPC3 && ev_sap_ind) sap_indicate(sap_entry, sap_len);
    if (IS_VPC3 && ev_sap_srd) sap_answer(sap_entry);

    // ev_mac_stop / ev_mac_start: the requests of the InstQ_Wr write of this cycle, after every
    // other event (the chip executes them with the bus access): Stop, then Start (a restart).
    if (ev_mac_stop && nx_started) go_offline;
    if (ev_mac_start && !nx_started) start;

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
        if (nx_dx_deferred && !nx_prm_pending && nx_dp_state == DP_WAIT_CFG) begin
          nx_dx_deferred = 1'b0;
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
        // The DPC31's User_SSA_OK Cmd: 00 finished (one was pending), 11 Not_Allowed (none).
        nx_bus_rdata = (IS_DPC31 && nx_ssa_free) ? 8'h03 : 8'h00;
        nx_ssa_free = 1'b1;
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
      end else if (IS_VPC3 && a >= USER_BASE) begin
        nx_bus_rdata = ram[ram_index(a)];
      end
    end else if (bus_wr) begin
      if (a[12:1] == A_IRR[12:1]) begin
        // Int_Req_Reg (RW): an event latched in steps 1-2 of this cycle survives.
        nx_irr = (nx_irr & ~(lane & IRR_MASK)) | (w16 & IRR_MASK);
        nx_irr = nx_irr | ev_set;
      end else if (a[12:1] == A_IAR[12:1]) begin
        // Int_Ack_Reg (W1C; New_Prm_Data / New_Cfg_Data / vpc3plus New_Ext_Prm_Data IGN).
        ack16 = w16 & IRR_MASK & ~ACK_IGN;
        if (`DPC31B_MUT(MUT_ACK_NEIGHBOUR)) ack16 = ack16 | ((ack16 << 1) & IRR_MASK & ~ACK_IGN);
        nx_irr = nx_irr & ~ack16;
        if (!`DPC31B_MUT(MUT_ACK_BEATS_EVENT)) nx_irr = nx_irr | ev_set;
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
        if (w8[M1_GO_OFFLINE]) begin
          // Go_Offline stays 1 as after its own write, though a Start of this write cleared it
          // (docs/timing.md "Start and Go_Offline in one write": as a Start then a Go_Offline).
          nx_mode_reg1[M1_GO_OFFLINE] = 1'b1;
          if (nx_started) go_offline;
        end
      end else if (a == A_MODE_REG1_R) begin
        // Mode_Reg1_R: a 1 clears the bit.
        // CHOICE: no actions: clearing Start_SPC3 does not stop the chip (decisions.md), a 1 in
        // the EOI / User_Leave_Master positions does nothing (they are pulses of the set port).
        w8 = bus_wdata & M1_MASK;
        nx_mode_reg1 = nx_mode_reg1 & ~w8;
      end else if (IS_VPC3 && a == A_MODE_REG2) begin
        // vpc3plus Mode_Reg2: only bits 0 and 1 matter here; written only while Offline.
        if (!nx_started) begin
          nx_opt_reg = bus_wdata & OPT_MASK;
          nx_large_ram = bus_wdata[M2_4KB_MODE];
        end
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
      end else if (IS_VPC3 && a >= USER_BASE) begin
        ram[ram_index(a)] = bus_wdata;
      end
      // Other write addresses (WD_Baud_Control_Val, MinTSDR_Val, reserved, RAM) are not part of
      // the block.
    end
    // ================================================================= step 4: X/INT
    // combinational from the registered result (x_int above).
    end
  endtask

  // ===========================================================================================
  // Registers (the RAM mirror is written with blocking assignments: the same process reads it)
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
      dx_deferred <= 1'b0;
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
      ext_prm <= 1'b0;
      large_ram <= 1'b0;
      sap_sending <= 1'b0;
      sap_sent_entry <= 12'd0;
      sap_resp <= 12'd0;
      // The hardware reset clears the RAM (as the C++ register file does).
      if (IS_VPC3) for (ram_i = 0; ram_i < RAM_WORDS; ram_i = ram_i + 1) ram[ram_i] = 8'h00;
    end else begin
      next_state;
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
      dx_deferred <= nx_dx_deferred;
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
      ext_prm <= nx_ext_prm;
      large_ram <= nx_large_ram;
      sap_sending <= nx_sap_sending;
      sap_sent_entry <= nx_sap_sent_entry;
      sap_resp <= nx_sap_resp;
    end
  end
  /* verilator lint_on BLKSEQ */

endmodule

`undef DPC31B_PSEL
`undef DPC31B_MUT
