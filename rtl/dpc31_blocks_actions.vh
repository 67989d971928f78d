// dpc31_blocks_actions.vh -- included inside module dpc31_blocks (rtl/dpc31_blocks.v): each
// action of docs/golden-model.md as one task on the nx_* next-state values, named as in the
// spec: buffer rings, Dout actions, the DP state, Global_Control, handshakes, command reads and
// diag sending.
  // ---------------------------------------------------------------------------- helpers
  function [18:0] eoi_time;  // T
    input [15:0] m0;
    begin
      eoi_time = m0[M0_EOI_TIME_BASE] ? EOI_T_1MS : EOI_T_1US;
      if (`DPC31B_MUT(MUT_EOI_SHORT)) eoi_time = eoi_time - 19'd1;
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
  // (unless keep_n: only for the mutant NEXT_DOUT_KEEPS_N).
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

  // failsafe_clear: spc3 / vpc3plus: dout_clear. dpc31: D not fresh (outputs a Sync holds in D
  // are older than the clear; D itself is left as it is); then once per clear: if In_Clear,
  // nothing; otherwise In_Clear = 1, N_Cl = 1 and DX_Out.
  task failsafe_clear;
    begin
      if (!IS_DPC31) begin
        dout_clear;
      end else begin
        nx_d_fresh = 1'b0;
        if (!nx_in_clear) begin
          nx_in_clear = 1'b1;
          nx_n_cl = 1'b1;
          raise(IRQ_DX_OUT);
        end
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
      nx_dx_deferred = 1'b0;
      nx_ext_prm = 1'b0;
      nx_sap_sending = 1'b0;  // the MAC reset: no response on the wire
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
        nx_dx_deferred = 1'b0;
        nx_ext_prm = 1'b0;
        if (was_dx) raise(IRQ_GO_LEAVE_DX);
        dout_clear;
      end
    end
  endtask

  // start (Start_SPC3 written 1, or a MAC_Start request, while Offline).
  task start;
    begin
      nx_started = 1'b1;
      nx_mode_reg1[M1_GO_OFFLINE] = 1'b0;
      dp_reset;
      nx_n_cl = 1'b0;
      nx_in_clear = 1'b0;
      nx_ut_cnt = user_period(nx_mode_reg0);  // first tick P cycles after this cycle
      if (`DPC31B_MUT(MUT_USER_TIMER_LATE)) nx_ut_cnt = nx_ut_cnt + 19'd1;
      // R_GC_Command preset at every start of the DP slave: FFh dpc31, 00h spc3 (the cell's reset
      // value); the VPC3+ leaves the cell alone.
      if (!IS_VPC3) nx_gc_command = GC_COMMAND_RESET;
      dout_clear;
    end
  endtask

  // go_offline (Go_Offline written 1, or a MAC_Stop request, while started).
  task go_offline;
    begin
      nx_started = 1'b0;
      nx_mode_reg1[M1_START] = 1'b0;
      // The Go_Offline bit is the write's (set again after a Start of the same write, "stays set
      // while Offline"); a MAC_Stop leaves it as it is.
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
        if (cmd[GC_CLEAR_DATA] && !(nx_sync_mode && `DPC31B_MUT(MUT_CLEAR_IGNORED_IN_SYNC)))
          failsafe_clear;
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
      if (nx_prm_pending && !`DPC31B_MUT(MUT_NO_CONFLICT)) nx_prm_newer = 1'b1;
      nx_prm_pending = 1'b1;
    end
  endtask

  task cfg_arrived;
    begin
      if (nx_cfg_pending && !`DPC31B_MUT(MUT_NO_CONFLICT)) nx_cfg_newer = 1'b1;
      nx_cfg_pending = 1'b1;
    end
  endtask

  // The OK / Not_OK reads: 11 when not pending (and the event bit cleared: a leave_master may
  // have discarded what it announced); 01 (conflict, newer cleared, still pending) when a newer
  // one arrived; else 00, not pending, and the completion.
  // vpc3plus: the same reads answer a Set_Ext_Prm (ext_prm): they clear New_Ext_Prm_Data, and
  // accepting it only lets a Cfg OK that waits for it (dx_deferred) enter Data_Exchange.
  task prm_handshake(input not_ok, output [7:0] res);
    reg [15:0] ev_bit;
    begin
      ev_bit = nx_ext_prm ? IRQ_NEW_EXT_PRM : IRQ_NEW_PRM;
      if (!nx_prm_pending) begin
        res = 8'h03;
        nx_irr = nx_irr & ~ev_bit;
      end else if (nx_prm_newer) begin
        res = 8'h01;
        nx_prm_newer = 1'b0;
      end else begin
        res = 8'h00;
        nx_prm_pending = 1'b0;
        // Not an IRR / IAR write: the command's clear wins over an event of this cycle (the
        // event made the handshake pending, and this read completes it).
        nx_irr = nx_irr & ~ev_bit;
        nx_prm_fault = not_ok;
        if (not_ok) begin
          leave_master;
        end else if (!nx_ext_prm && nx_dp_state == DP_WAIT_PRM) begin
          nx_dp_state = DP_WAIT_CFG;
        end else if (nx_ext_prm && nx_dx_deferred && nx_dp_state == DP_WAIT_CFG) begin
          // VPC3+C p.48: the last parameter telegram acknowledged, a Cfg OK given meanwhile.
          nx_dx_deferred = 1'b0;
          nx_dp_state = DP_DATA_EXCHANGE;
          raise(IRQ_GO_LEAVE_DX);
        end
      end
      if (!nx_prm_pending) nx_ext_prm = 1'b0;
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
          // spc3 with a Din buffer (R_Len_Din_Buf != 0): at the next New_Din_Buffer_Cmd;
          // vpc3plus with a Set_Ext_Prm's verdict pending: at that verdict (VPC3+C p.48).
          if (nx_dp_state == DP_WAIT_CFG) begin
            if (nx_prm_pending || (IS_SPC3 && nx_len_din != 8'h00)) begin
              nx_dx_deferred = 1'b1;
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
      keep_n = `DPC31B_MUT(MUT_NEXT_DOUT_KEEPS_N);
      if (IS_DPC31 && nx_n_cl) begin
        // The substitute values supersede outputs received before the Clear: N freed unseen.
        nx_n_cl = 1'b0;
        if (nx_dout_n != NIL) begin
          nx_dout_f = nx_dout_n;
          nx_dout_n = NIL;
        end
        nx_n_cleared = 1'b0;
        if (!`DPC31B_MUT(MUT_NO_C_SWAP)) swap_c_with_u;
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
      nx_diag_flag = `DPC31B_MUT(MUT_DIAG_FLAG_STICKY) ? (nx_diag_flag | stat) : stat;
    end
  endtask

  // ev_diag_end: the buffer in Send_Mode: if the other buffer is SPC3 (the user handed a newer
  // one over meanwhile), the sent one goes to User and Diag_Buffer_Changed, Diag_Flag stays (the
  // newer one is not fetched: SPC3 p.32); else it goes back to SPC3 and Diag_Flag = stat_diag.
  // CHOICE: with no buffer in Send_Mode nothing happens (Diag_Flag unchanged); with both in
  // Send_Mode (two begins without an end) buffer 1 is the one that ends.
  task diag_end(input stat);
    begin
      if (nx_diag1 == DIAG_SEND) begin
        if (nx_diag2 == DIAG_SPC3) begin
          nx_diag1 = DIAG_USER;
          raise(IRQ_DIAG_CHANGED);
        end else begin
          diag_flag_after_send(stat);
          nx_diag1 = DIAG_SPC3;
        end
      end else if (nx_diag2 == DIAG_SEND) begin
        if (nx_diag1 == DIAG_SPC3) begin
          nx_diag2 = DIAG_USER;
          raise(IRQ_DIAG_CHANGED);
        end else begin
          diag_flag_after_send(stat);
          nx_diag2 = DIAG_SPC3;
        end
      end
    end
  endtask

  // ---------------------------------------------------------------------------- SAP list
  // vpc3plus, DPV1 (docs/dpv1.md): the indication / response buffer headers and Response_Sent in
  // the RAM mirror. The SAP list's verdict (which entry, whether the request passed its checks)
  // comes in with the events; which buffer, RR, the Control bits and the interrupts are ours.

  // The RAM cell of an address (2 KB: 800h-FFFh wraps, as the C++ decode does; bit 12 is beyond
  // the VPC3+'s 12 address bits).
  /* verilator lint_off UNUSEDSIGNAL */
  function [11:0] ram_index(input [12:0] addr);
    begin
      ram_index = nx_large_ram ? addr[11:0] : {1'b0, addr[10:0]};
    end
  endfunction
  /* verilator lint_on UNUSEDSIGNAL */

  // The header of the buffer whose segment is seg.
  function [11:0] seg_index(input [7:0] seg);
    begin
      seg_index = nx_large_ram ? {seg, 4'd0} : {1'b0, seg, 3'd0};
    end
  endfunction

  // A buffer is free with none of USER, IND, RESP, INUSE in its Control.
  function buf_free(input [7:0] seg);
    begin
      buf_free = (ram[seg_index(seg)] & (HC_USER | HC_IND | HC_RESP | HC_INUSE)) == 8'h00;
    end
  endfunction

  // The data into the first free indication buffer of the entry (Ind_Buf_Ptr[1] = 00h or equal
  // to [0]: one buffer): INUSE while the chip fills it (within this cycle), then USER + IND and
  // FDL_Ind; longer than its Max_Length, or no buffer free: RR, nothing changes.
  task sap_indicate(input [12:0] entry, input [7:0] len);
    reg [7:0] ind0, ind1, seg;
    reg found;
    begin
      ind0 = ram[ram_index(entry + SE_IND0)];
      ind1 = ram[ram_index(entry + SE_IND1)];
      found = 1'b1;
      if (ind0 != 8'h00 && buf_free(ind0)) seg = ind0;
      else if (ind1 != 8'h00 && ind1 != ind0 && buf_free(ind1)) seg = ind1;
      else if (`DPC31B_MUT(MUT_SAP_NO_RR) && ind0 != 8'h00) seg = ind0;
      else begin
        seg = 8'h00;
        found = 1'b0;
      end
      if (found && len <= ram[seg_index(seg) + SH_MAX_LENGTH]) begin
        ram[seg_index(seg)] = `DPC31B_MUT(MUT_SAP_IND_NOT_SET) ? HC_USER : (HC_USER | HC_IND);
        raise(IRQ_FDL_IND);
      end
    end
  endtask

  // An SRD: the response when the response buffer's Control has RESP and USER, else SC.
  task sap_answer(input [12:0] entry);
    reg [7:0] rp;
    begin
      rp = ram[ram_index(entry + SE_RESP)];
      if (rp != 8'h00 && (ram[seg_index(rp)] & (HC_USER | HC_RESP)) == (HC_USER | HC_RESP)) begin
        nx_sap_sending = 1'b1;
        nx_sap_sent_entry = ram_index(entry);
        nx_sap_resp = seg_index(rp);
        if (`DPC31B_MUT(MUT_SAP_POLL_END_EARLY)) raise(IRQ_POLL_END);
      end
    end
  endtask

  // The response's last stop bit is out: RESP and USER cleared, Response_Sent, Poll_End_Ind.
  task sap_response_sent;
    begin
      if (nx_sap_sending) begin
        nx_sap_sending = 1'b0;
        ram[nx_sap_resp] = ram[nx_sap_resp] &
                           ~(`DPC31B_MUT(MUT_SAP_RESP_KEPT) ? HC_USER : (HC_RESP | HC_USER));
        ram[nx_sap_sent_entry] = ram[nx_sap_sent_entry] | SE_RESPONSE_SENT;
        if (!`DPC31B_MUT(MUT_SAP_POLL_END_EARLY)) raise(IRQ_POLL_END);
      end
    end
  endtask
