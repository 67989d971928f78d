#!/usr/bin/env python3
"""One name per DP SAP in every shipped decoder: the Wireshark dissector
(lib/capture/profibus_dl.lua, `dp_saps`), the sigrok decoder (lib/sigrok/profibus_dp/pd.py,
`DP_SAPS`) and the GTKWave translate filter of state.service (lib/waveform/gtkwave/service.txt).

Usage: decoder_sap_names.py SOURCE_DIR

The names: 49 MSAC_C2 Initiate, "Alarm_Ack on SAP 50 or 51", MSAC_C1 on SAP 51 (manual-quotes.md,
"DPV1": the services above the SAP list), 53 Set_Ext_Prm (manual-quotes.md, VPC3+C p.53/54),
55..62 the DP services (chip-facts.md, "DP SAPs"); SAP 50 is named as include/dpc31/dp.hpp names
it (MSAC_C1_Alarm: Alarm_Ack is the DPV1 function, which also comes on SAP 51).
Exit 0 if every decoder names each of them so, 1 with the differences.
"""

import re
import sys
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))
from waveform_sigrok_demo import fail_if  # noqa: E402

WANT = {49: "MSAC_C2_Initiate", 50: "MSAC_C1_Alarm", 51: "MSAC_C1", 53: "Set_Ext_Prm",
        55: "Set_Slave_Add", 56: "Rd_Inp", 57: "Rd_Outp", 58: "Global_Control", 59: "Get_Cfg",
        60: "Slave_Diag", 61: "Set_Prm", 62: "Chk_Cfg"}


def table(text, start, end, pattern):
    body = text.split(start, 1)[1].split(end, 1)[0]
    return {int(n, 0): name for n, name in re.findall(pattern, body)}


def main():
    src = Path(sys.argv[1])
    lua = (src / "lib/capture/profibus_dl.lua").read_text(encoding="utf-8")
    pd = (src / "lib/sigrok/profibus_dp/pd.py").read_text(encoding="utf-8")
    gtk = (src / "lib/waveform/gtkwave/service.txt").read_text(encoding="utf-8")
    have = {
        "Wireshark": table(lua, "local dp_saps = {", "}", r'\[(\d+)\] = "([^"]+)"'),
        "sigrok": table(pd, "DP_SAPS = {", "}", r"(\d+): '([^']+)'"),
        "GTKWave": {int(h, 16): n for h, n in re.findall(r"^([0-9A-F]{2}) (.+)$", gtk, re.M)
                    if int(h, 16) in WANT},
    }
    fail_if([f"{who}: SAP {sap} is {names.get(sap)!r}, not {name!r}"
             for who, names in have.items() for sap, name in WANT.items()
             if names.get(sap) != name])
    print(f"ok: {len(WANT)} SAPs named alike in {', '.join(have)}")


if __name__ == "__main__":
    main()
