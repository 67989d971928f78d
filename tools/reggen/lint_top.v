// Lint target for the generated register include (ctest verilog_include_lint).
// Command: verilator --lint-only -Wall -I<repo>/rtl tools/reggen/lint_top.v
`include "dpc31_regs.vh"

module lint_top (
    input  wire [12:0] addr,
    output wire        hit
);
  assign hit = (addr == `DPC31_ADDR_R_TS_Adr);
endmodule
