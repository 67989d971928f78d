// The block-level events of docs/golden-model.md: what the protocol side and the CPU did to the
// blocks in one cycle. The lockstep's chip-session mode (tools/cosim/session.cpp) replays them
// into the RTL; observed through the harness interface (emu/harness.hpp), not the public API.
#pragma once

#include <cstdint>

namespace dpc31 {

struct BlockEvent {
  enum class Kind : std::uint8_t {
    dx,
    irq,
    leave_master,
    wd_expired,  // the DP watchdog expired in DP_Control (WD_DP_Control_Timeout, Leave_Master)
    prm_fault,
    gc,
    dout,
    failsafe,
    din,
    diag_begin,
    diag_end,
    dis,
    prm,
    cfg,
    ssa,
    mac_stop,   // the MAC goes Offline: a MAC_Stop request (DPC31), a RAM access violation
    mac_start,  // a MAC_Start request
    ext_prm,    // vpc3plus: a Set_Ext_Prm is in the Prm buffer (New_Ext_Prm_Data)
    sap_ind,    // vpc3plus: a request with data for a SAP-list entry passed its checks
    sap_srd,    // vpc3plus: an SRD for a SAP-list entry passed its checks: response or SC
    sap_sent,   // vpc3plus: the last stop bit of a response from a SAP-list buffer is out
    read,
    write,
    // Not an input of the golden model (it has no MAC): Go_Offline or a RAM access violation
    // during a request, the Offline waits for its end. The cosim recorder refuses such a session.
    offline_deferred
  };
  Kind kind;
  // irq bits, gc command, stat_diag, dis bits, bus address, SAP-list entry address
  std::uint16_t value = 0;
  std::uint8_t data = 0;  // bus write data, sap_ind: the request's data length
};

}  // namespace dpc31
