"""dpc31emu from Python: the SPC3 / VPC3+ / DPC31 PROFIBUS-DP slave ASICs, cycle-accurate.

The native part (the chip, the DP master, firmware, scenarios, wavediff; docs/python.md) is the
extension module ``dpc31._dpc31``, loaded at the first use of one of its names, so that
``import dpc31.client`` (the pure-Python ``dpc31 serve`` client) never loads native code.
"""

from typing import Any

__all__ = [
    "Chip", "Master", "SlaveConfig", "Frame", "Exchange", "MasterCounters", "Firmware",
    "Responder", "Output", "Scenario", "ScenarioResult", "ExpectResult", "StepRecord", "Step",
    "StepKind", "DpState", "WdState", "Telegram", "Probe", "Register", "Field", "Region",
    "registers", "register", "regions", "profiles", "run_scenario", "wavediff", "WaveReport",
    "SignalDiff", "Divergence", "WavePoint", "Structural", "Error", "SnapshotError",
    "ScenarioError", "FirmwareError", "InputError", "Dpv1Answer", "Dpv1Outcome", "Dpv1Rules",
    "Cpu51Board", "Segment", "Station", "SegmentMaster", "TokenVisit", "LineTelegram",
    "Collision", "BusCheck", "SegmentScenario", "SegmentScenarioResult",
]


def __getattr__(name: str) -> Any:
    if name not in __all__:
        raise AttributeError(f"module 'dpc31' has no attribute '{name}'")
    from . import _dpc31

    if name == "run_scenario":
        value: Any = _run_scenario
    else:
        value = getattr(_dpc31, name)
    globals()[name] = value
    return value


def __dir__() -> list:
    return sorted(list(globals()) + __all__)


def _run_scenario(path: str) -> Any:
    """Loads and runs a scenario file (``dpc31 run PATH``); raises ScenarioError on a bad file."""
    from . import _dpc31

    return _dpc31.Scenario.load(path).run()
