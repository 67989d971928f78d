#!/bin/sh
# The VCD writer's output, byte for byte, against files written by the writer before it was made
# fast (commit 3c78365, issue 19 item 7): the full form at 1 ps (do4_osp_replace: about 15 000
# changes, so the recorder drains its buffer several times during the run), the form for
# logic-analyser tools, and a window of some signals (at 100 us until s22-wave, now 10 ns). The two do4_osp_replace files were
# written again after issue 16 changed that run itself (the DPC31 firmware's requests and its
# Indication interrupt: other bus accesses); the writer was the same as for the window file,
# which stayed byte for byte as the old writer's. All three were written again when the DPC31
# started by MAC_Start (issue 16 item 2: the same run 28 cycles later, the writer unchanged).
# do4_osp_replace.vcd once more when the DPC31's status register moved to the parameter cells
# (0874h, DPC31 p.12): the only change is bus.addr 0004h/0005h -> 0874h/0875h at the firmware's
# five Status_Reg reads, each at the same time as before.
# Both do4_osp_replace files once more when the pins set at the window's first cycle stopped being
# dumped twice at #0 (issue 33: 0 in $dumpvars, then 1 in the same #0): diffed by hand, the only
# change is $dumpvars holding each value in force at cycle 0 (rxd, txd, x_int 1; dout_sm and
# din_sm E1h, diag_sm 1001) and those second lines gone; every later line is as before.
# do4_osp_replace.vcd once more for the new signal state.service (issue 33: 8 bits, VCD id `0`,
# declared after baud_code): diffed by hand, the only changes are its $var, FFh in $dumpvars and
# 22 values, each at the stop sample of a request's last character (the first, FDL_Status 81h,
# at #2591166667 = cycle 124376 = the pcapng's end 124392 - 32 + 16), in the order of the DP
# start-up: 81h FDL_Status, 3Ch Slave_Diag, 3Dh Set_Prm, 3Eh Chk_Cfg, 3Ch, 80h Data_Exchange, and
# again after the watchdog, with 3Ah Global_Control; two of them on a time line of their own.
# All three once more when the Baud_Search window became max(4096 bit times, 20 ms) (issue 31 item
# 5; the writer unchanged): the 1.5 Mbaud window opens 2 763 712 cycles later (= 434 periods of
# the unanswered FDL_Status, 6368 clocks), so the window file moved by that much (--from / --to);
# its value changes are line for line the old ones, only their 100 us time stamps round
# differently (the shift is 575.77 units). The do4_osp_replace files: the same $var header; before
# the baud rate is found the search's many more unanswered FDL_Status (about 15 600 changes);
# from the find on 4781 of the old 8441 changes recur exactly 2 763 712 cycles later, the others
# belong to DO4's work paced by its user timer (User_Timer_Clock counts from Start, not from the
# find), so they keep their phase to Start; they were not checked one by one.
# Two once more when a signal got one value per time (s22-wave, docs/decisions.md): in
# do4_osp_replace.vcd, diffed by hand, the only changes are the three times at which irr changed
# twice in one cycle (0008h then 200Ah, 0100h then 2100h, 0002h then 280Ah): each now
# holds the last value only, and its line comes first among that time's changes. The window file
# at 10 ns, as a unit longer than a cycle (its 100 us) is refused now: its value lines are line for
# line the old ones, in 1581 time stamps instead of 25.
# do4_osp_replace.vcd once more when the DP watchdog's expiry stopped looking at X/INT before
# Leave_Master (s23-wd, docs/timing.md "Order within one cycle"): diffed by hand, the only change
# is at the expiry's time #169855166667, where dp_state's line (b00, Wait_Prm) now comes first,
# before wd_state (b01), irr and x_int, instead of after x_int: the same values at the same time.
# Both do4_osp_replace files once more when X/INT came to be looked at once after a cycle's
# events (s24-xint, docs/timing.md "Order within one cycle", step 6): diffed by hand (per time
# stamp, the same set of lines; the same header and times), the only changes are the order of
# lines at 14 times of the full file and 1 of the la file: x_int's line now comes after the
# din_sm (11 times) or dout_sm (2, the DP watchdog expiry at #169855166667 among them) line of
# the buffer change latched with its event in that cycle, and at #61004833333 txd's line comes
# first, not last (in the la file: txd before x_int there).
# Usage: waveform_golden.sh path/to/dpc31 source-dir
set -eu
dpc31=$1
src=$2
d=$(mktemp -d)
trap 'rm -rf "$d"' EXIT
"$dpc31" run "$src/traces/do4_osp_replace.scn" --quiet --vcd "$d/full.vcd" --la-vcd "$d/la.vcd"
"$dpc31" run "$src/traces/startup_dpc31_1m5.scn" --quiet --vcd "$d/window.vcd" --from 2863712 \
  --to 3063712 --timescale 10ns --signals 'pins.*,bus.*'
cmp "$d/full.vcd" "$src/tests/data/waveform/do4_osp_replace.vcd"
cmp "$d/la.vcd" "$src/tests/data/waveform/do4_osp_replace.la.vcd"
cmp "$d/window.vcd" "$src/tests/data/waveform/startup_dpc31_1m5_window.vcd"
echo "3 waveforms as before"
