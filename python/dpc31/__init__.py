"""dpc31emu from Python: the SPC3 / VPC3+ / DPC31 PROFIBUS-DP slave ASICs, cycle-accurate.

The native part (the chip, the DP master, firmware, scenarios, wavediff; docs/python.md) is the
extension module ``dpc31._dpc31``, loaded at the first use of one of its names, so that
``import dpc31.client`` (the pure-Python ``dpc31 serve`` client) never loads native code. Python
3.7 or later: before it (no module ``__getattr__``) ``import dpc31`` loads it at once.
"""

import os
import sys
from typing import Any

__all__ = [
    "Chip", "Master", "SlaveConfig", "MasterSlave", "Frame", "Exchange", "MasterCounters",
    "Firmware", "Responder", "Output", "Scenario", "ScenarioResult", "ExpectResult", "StepRecord",
    "Step", "StepKind", "DpState", "WdState", "Telegram", "Probe", "Register", "Field", "Region",
    "registers", "register", "regions", "profiles", "run_scenario", "wavediff", "WaveReport",
    "SignalDiff", "Divergence", "WavePoint", "Structural", "Error", "SnapshotError",
    "ScenarioError", "FirmwareError", "InputError", "Dpv1Answer", "Dpv1Outcome", "Dpv1Rules",
    "Cpu51Board", "Segment", "Station", "SegmentMaster", "TokenVisit", "LineTelegram", "Collision",
    "BusCheck", "SegmentScenario", "SegmentScenarioResult",
]


def __getattr__(name: str) -> Any:
    # __version__ is the loaded libdpc31emu.so's version ("0.1.0"), from the native module.
    if name not in __all__ and name != "__version__":
        raise AttributeError(f"module 'dpc31' has no attribute '{name}'")
    if name == "run_scenario":
        value: Any = _run_scenario
    else:
        value = getattr(_native(), name)
    globals()[name] = value
    return value


def _native() -> Any:
    """The extension module, else the ImportError that says why it did not load."""
    try:
        from . import _dpc31
    except ImportError as e:
        raise ImportError(_not_loaded(e)) from e
    return _dpc31


def _not_loaded(error: ImportError) -> str:
    """Why _dpc31 did not load, with a hint where it was built for another Python: the file's
    name carries that interpreter's tag (cpython-311: 3.11), and no other one looks for it."""
    import pathlib
    import re
    import sysconfig

    built = sorted(p.name for p in pathlib.Path(__file__).parent.glob("_dpc31.*"))
    suffix = sysconfig.get_config_var("EXT_SUFFIX") or ".so"
    if not built or "_dpc31" + suffix in built:
        return str(error)
    tags = [re.match(r"_dpc31\.cpython-(\d)(\d+)", name) for name in built]
    versions = ", ".join(f"Python {m[1]}.{m[2]}" if m else "another Python"
                         for m in tags)
    here = f"{sys.version_info[0]}.{sys.version_info[1]}"
    return (f"{error}: the module was built for {versions} ({', '.join(built)}), this is "
            f"Python {here} ({sys.executable}): run the python3 it was built for, or build it "
            "with this one")


def __dir__() -> list:
    return sorted(list(globals()) + __all__)


def _run_scenario(path: "str | os.PathLike[str]") -> Any:
    """Loads and runs a scenario file (``dpc31 run PATH``); raises ScenarioError on a bad file."""
    return _native().Scenario.load(path).run()


if sys.version_info < (3, 7):
    # Before 3.7 a module has no __getattr__ (PEP 562): dpc31.Chip would be an AttributeError.
    # The names are loaded now, so `import dpc31` raises the ImportError that says why.
    for _name in __all__:
        __getattr__(_name)
    del _name
