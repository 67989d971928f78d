# Type stubs of the dpc31 package (docs/python.md): what the native module _dpc31 binds, for
# editors and type checkers. Kept equal to the bindings by the test Python.stubs.
import array
import enum
import os
from typing import Callable, Dict, List, Optional, Sequence, Tuple, Union

__version__: str

# What a bytes argument takes (bytes_like in python/bind.hpp): a bytes-like object's bytes, or
# a list of ints 0..255.
_BytesLike = Union[bytes, bytearray, memoryview, array.array[int], List[int]]

class Error(RuntimeError): ...
class SnapshotError(Error): ...
class ScenarioError(Error):
    file: Optional[str]
    line: Optional[int]
    reason: Optional[str]
class FirmwareError(Error):
    file: Optional[str]
    line: Optional[int]
    step: Optional[str]
    reason: Optional[str]
class InputError(Error): ...

class DpState(enum.Enum):
    Wait_Prm = 0
    Wait_Cfg = 1
    Data_Exchange = 2

class WdState(enum.Enum):
    Baud_Search = 0
    Baud_Control = 1
    DP_Control = 2

class Telegram:
    from_chip: bool
    bytes: bytes
    start: int
    end: int

class Probe:
    dp_state: DpState
    wd_state: WdState
    baud_code: int
    irr: int
    dout_buffer_sm: int
    din_buffer_sm: int
    diag_buffer_sm: int

class Field:
    name: str
    lsb: int
    width: int
    access: str
    pulse: bool
    desc: str
    mask: int

class Register:
    name: str
    alias: str
    kind: str
    block: str
    width: int
    reset: Optional[int]
    read_addr: Optional[int]
    write_addr: Optional[int]
    documented: bool
    source: str
    note: str
    desc: str
    fields: List[Field]
    def field(self, name: str) -> Field: ...

class Region:
    name: str
    begin: int
    end: int
    ram: bool
    reserved: bool
    desc: str

def registers(profile: str) -> List[Register]: ...
def register(profile: str, name: str) -> Register: ...
def regions(profile: str) -> List[Region]: ...
def profiles() -> List[str]: ...

class Chip:
    def __init__(self, profile: str = "dpc31", bus: str = "intel", clock_hz: int = 0,
                 engine: str = "event", variant: Optional[str] = None,
                 irq_controller: str = "external") -> None: ...
    def reset(self) -> None: ...
    # the bus: bus_access_cycles clocks per access; the GIL is released while the chip runs
    def read(self, addr: int) -> int: ...
    def write(self, addr: int, value: int) -> None: ...
    def read_block(self, addr: int, length: int) -> bytes: ...
    def write_block(self, addr: int, data: _BytesLike) -> None: ...
    def fill(self, addr: int, value: int, length: int) -> None: ...
    def equal(self, a: int, b: int, length: int) -> bool: ...
    # the debugger: no time, no side effects
    def peek(self, addr: int) -> int: ...
    def poke(self, addr: int, value: int) -> bool: ...
    def peek_block(self, addr: int, length: int) -> bytes: ...
    def peek_reg(self, name: str) -> int: ...
    def poke_reg(self, name: str, value: int) -> bool: ...
    def peek_field(self, register: str, field: str) -> int: ...
    def addr_of(self, name: str) -> Optional[int]: ...
    @property
    def registers(self) -> List[Register]: ...
    # time
    def step(self, cycles: int = 1) -> None: ...
    def step_until_irq(self, cycles: int) -> bool: ...
    @property
    def cycle(self) -> int: ...
    @property
    def clock_hz(self) -> int: ...
    @property
    def bus_access_cycles(self) -> int: ...
    # pins and state
    @property
    def x_int(self) -> bool: ...
    @property
    def irq_active(self) -> bool: ...
    @property
    def pb3(self) -> bool: ...
    @property
    def txd(self) -> bool: ...
    @property
    def started(self) -> bool: ...
    @property
    def dp_state(self) -> DpState: ...
    @property
    def wd_state(self) -> WdState: ...
    @property
    def station_address(self) -> int: ...
    @property
    def bit_cycles(self) -> int: ...
    @property
    def fdl_counters(self) -> dict: ...
    @property
    def profile(self) -> str: ...
    @property
    def bus(self) -> str: ...
    @property
    def variant(self) -> Optional[str]: ...
    def probe(self) -> Probe: ...
    @property
    def next_deadline(self) -> int: ...
    @property
    def watchdog_due(self) -> int: ...
    # the serial side
    def drive_rxd(self, cycle: int, level: bool) -> None: ...
    def drive_rxd_chars(self, data: _BytesLike, start: int, bit_cycles: int) -> int: ...
    # observers: a callable adds one, None removes all of that kind
    def on_irq_change(self, callback: Optional[Callable[[int, bool], None]]) -> None: ...
    def on_pb3_change(self, callback: Optional[Callable[[int, bool], None]]) -> None: ...
    def on_telegram(self, callback: Optional[Callable[[Telegram], None]]) -> None: ...
    def on_bus_access(self, callback: Optional[Callable[[int, bool, int, Optional[int]], None]]) -> None: ...
    # snapshots
    def save_state(self) -> bytes: ...
    def load_state(self, data: Union[bytes, bytearray, memoryview, array.array[int]]) -> None: ...
    def save_state_file(self, path: Union[str, os.PathLike[str]]) -> None: ...
    def load_state_file(self, path: Union[str, os.PathLike[str]]) -> None: ...

class Frame:
    sd: int
    da: int
    sa: int
    fc: int
    dsap: Optional[int]
    ssap: Optional[int]
    du: bytes
    def __init__(self, da: int, sa: int, fc: int, du: _BytesLike = b"", dsap: Optional[int] = None,
                 ssap: Optional[int] = None) -> None: ...
    def encode(self) -> bytes: ...
    @property
    def service(self) -> str: ...

class Exchange:
    request: Frame
    request_start: int
    request_end: int
    answer: Optional[Frame]
    stray: Optional[Frame]
    answer_start: int
    answer_end: int
    wait_end: int

class MasterCounters:
    requests: int
    answered: int
    no_answer: int
    bad_answer: int
    noise: int
    late: int

class SlaveConfig:
    address: int
    ident: int
    cfg: bytes
    in_len: int
    out_len: int
    wd_on: bool
    wd_fact1: int
    wd_fact2: int
    wd_base_1ms: bool
    group_ident: int
    sync_req: bool
    freeze_req: bool
    min_tsdr: int
    user_prm: bytes
    def __init__(self, **kwargs: object) -> None: ...

class MasterSlave(SlaveConfig): ...

class Firmware:
    @property
    def name(self) -> str: ...
    def port(self, name: str) -> int: ...
    @property
    def port_writes(self) -> List[Tuple[int, str, int]]: ...
    def take_port_writes(self) -> List[Tuple[int, str, int]]: ...
    interrupts: List[Tuple[int, int]]
    def take_interrupts(self) -> List[Tuple[int, int]]: ...
    def hw_input(self, name: str, value: int) -> None: ...

class Cpu51Board:
    def __init__(self, chip: Chip, hz: int = 24000000, address: int = 0x8000) -> None: ...
    @staticmethod
    def c31(chip: Chip, hz: int = 24000000, code: int = 0x1000) -> Cpu51Board: ...
    def load_hex(self, path: Union[str, os.PathLike[str]]) -> int: ...
    def run_until(self, cycle: int) -> None: ...
    def reset(self) -> None: ...
    def port(self, n: int) -> int: ...
    def pins(self, n: int) -> int: ...
    def set_port_input(self, n: int, value: int) -> None: ...
    def xdata(self, addr: int) -> int: ...
    def on_ram_write(self, callback: Optional[Callable[[int, int, int], None]]) -> None: ...
    def on_serial(self, callback: Optional[Callable[[int, int], None]]) -> None: ...
    def chip_cycle_of(self, cpu_clock: int) -> int: ...
    @property
    def pc(self) -> int: ...
    @property
    def a(self) -> int: ...
    @property
    def b(self) -> int: ...
    @property
    def psw(self) -> int: ...
    @property
    def sp(self) -> int: ...
    @property
    def dptr(self) -> int: ...
    @property
    def machine_cycles(self) -> int: ...
    @property
    def in_service(self) -> int: ...
    @property
    def chip(self) -> Chip: ...

class Output:
    cycle: int
    data: bytes
    cleared: bool

class Responder:
    inputs: bytes
    outputs: List[Output]
    interrupts: List[Tuple[int, int]]
    prm_accepted: int
    cfg_accepted: int
    cfg_rejected: int
    def keep_last_output(self) -> None: ...
    def take_interrupts(self) -> List[Tuple[int, int]]: ...

class Dpv1Outcome(enum.Enum):
    positive = 0
    negative = 1
    refused = 2
    no_answer = 3
    timeout = 4
    malformed = 5
    no_connection = 6
    aborted = 7

class Dpv1Rules:
    retries: int
    c1_response_timeout: int
    c2_ssap: int
    def __init__(self, **kwargs: object) -> None: ...

class Dpv1Answer:
    outcome: Dpv1Outcome
    du: bytes
    error: Optional[Tuple[int, int, int]]
    abort: Optional[Tuple[int, int, int, int]]  # aborted: Subnet, Instance, Reason_Code, detail
    last: Optional[Frame]
    polls: int
    start: int
    end: int

class Master:
    def __init__(self, chip: Chip, address: int = 2, baud: int = 1500000, slot_bits: int = 100,
                 idle_bits: int = 33, slave: Optional[SlaveConfig] = None) -> None: ...
    def run_firmware(self, firmware: Union[str, os.PathLike[str]], gsd_defaults: bool = True) -> Firmware: ...
    def run_responder(self, inputs: _BytesLike = b"", sync_supported: bool = True,
                      freeze_supported: bool = True, spec_clear_mode: bool = True,
                      substitute: _BytesLike = b"", user_watchdog: bool = False,
                      dx_out_port: bool = False,
                      records: List[Tuple[int, int, _BytesLike]] = [],
                      work_cycles: Optional[int] = None,
                      wd_baud_control: Optional[int] = None,
                      user_wd_value: Optional[int] = None) -> Responder: ...
    def run_board(self, board: Cpu51Board) -> None: ...
    @property
    def firmware(self) -> Optional[Firmware]: ...
    @property
    def responder(self) -> Optional[Responder]: ...
    @property
    def chip(self) -> Chip: ...
    @property
    def slave(self) -> MasterSlave: ...
    @property
    def bit_cycles(self) -> int: ...
    @property
    def counters(self) -> MasterCounters: ...
    @property
    def history(self) -> List[Exchange]: ...
    @property
    def locks(self) -> Dict[int, int]: ...
    def clear_history(self) -> None: ...
    def startup(self, tries: int = 1000) -> bool: ...
    def restart(self, tries: int = 1000, retries: int = 1) -> bool: ...
    def data_exchange(self, outputs: _BytesLike, fault: Optional[str] = None,
                      fault_char: Optional[int] = None) -> Exchange: ...
    def global_control(self, command: int, groups: int = 0) -> Exchange: ...
    def slave_diag(self) -> Exchange: ...
    def fdl_status(self) -> Exchange: ...
    def set_prm(self, station_status_extra: int = 0) -> Exchange: ...
    def chk_cfg(self) -> Exchange: ...
    def get_cfg(self) -> Exchange: ...
    def read_inputs(self) -> Exchange: ...
    def read_outputs(self) -> Exchange: ...
    def set_slave_address(self, new_address: int, no_add_change: bool = False) -> Exchange: ...
    def transact(self, request: Frame, fault: Optional[str] = None,
                 fault_char: Optional[int] = None) -> Exchange: ...
    def transact_raw(self, data: _BytesLike, fault: Optional[str] = None,
                     fault_char: Optional[int] = None) -> Exchange: ...
    def idle(self, cycles: int) -> None: ...
    def line_noise(self, data: _BytesLike, idle_bits: int) -> None: ...
    def glitch(self, low_cycles: int) -> None: ...
    dpv1_rules: Dpv1Rules
    @property
    def c2_sap(self) -> Optional[int]: ...
    @property
    def c2_send_timeout(self) -> Optional[int]: ...
    def dpv1_read(self, slot: int, index: int, length: int) -> Dpv1Answer: ...
    def dpv1_write(self, slot: int, index: int, data: _BytesLike) -> Dpv1Answer: ...
    def alarm_ack(self, slot: int, alarm_type: int, specifier: int,
                  sap: int = 50) -> Dpv1Answer: ...
    def c2_initiate(self, send_timeout: int = 100, features_supported: int = 0x0100,
                    s_type: int = 0, s_addr: _BytesLike = b"\x00\x00", d_type: int = 0,
                    d_addr: _BytesLike = b"\x00\x00") -> Dpv1Answer: ...
    def c2_read(self, slot: int, index: int, length: int) -> Dpv1Answer: ...
    def c2_write(self, slot: int, index: int, data: _BytesLike) -> Dpv1Answer: ...
    def c2_transport(self, slot: int, index: int, data: _BytesLike) -> Dpv1Answer: ...
    def c2_idle(self) -> Dpv1Answer: ...
    def c2_abort(self, reason: int = 0, instance: int = 2) -> Dpv1Answer: ...
    @staticmethod
    def diag_ready(diag_answer: Frame) -> bool: ...

class StepKind(enum.Enum):
    startup = 0
    restart = 1
    exchange = 2
    gc = 3
    diag = 4
    fdl_status = 5
    set_prm = 6
    chk_cfg = 7
    get_cfg = 8
    read_inputs = 9
    read_outputs = 10
    set_slave_address = 11
    foreign_master = 12
    silence = 13
    inputs = 14
    hw = 15
    corrupt = 16
    bad_fcs = 17
    expect = 18
    write = 19
    read = 20
    send = 21
    request = 22
    dpv1 = 23
    reset = 24

class Step:
    line: int
    text: str
    kind: StepKind

class ExpectResult:
    line: int
    text: str
    ok: bool
    cycle: int

class StepRecord:
    line: int
    text: str
    cycle: int

class ScenarioResult:
    ok: bool
    final_cycle: int
    dp_state: DpState
    wd_state: WdState
    passed: int
    failed: int
    failures: List[str]
    counters: dict
    walk: List[str]
    expects: List[ExpectResult]
    steps: List[StepRecord]

class Scenario:
    @staticmethod
    def load(path: Union[str, os.PathLike[str]]) -> Scenario: ...
    @staticmethod
    def parse(text: str, file: str = "<string>") -> Scenario: ...
    file: str
    profile: str
    firmware: str
    steps: List[Step]
    expects: List[Step]
    def run(self) -> ScenarioResult: ...

def run_scenario(path: Union[str, os.PathLike[str]]) -> ScenarioResult: ...

class LineTelegram:
    sender: int
    start: int
    end: int
    bytes: bytes
    fault: Optional[str]
    fault_char: Optional[int]
    collided: bool

class Collision:
    cycle: int
    first: int
    second: int
    answer: bool  # the later station's telegram could have been an answer (docs/segment.md)

class TokenVisit:
    arrived: int   # a cycle of the line
    rotation: int  # TRR in clock cycles
    hold: int      # TTH in clock cycles
    polled: List[int]
    startup: List[int]
    gap: Optional[int]
    gap_answered: bool

class BusCheck:
    def count(self, kind: str) -> int: ...
    counts: Dict[str, int]
    total: int

class Station:
    index: int
    name: str
    address: int
    slave: MasterSlave
    firmware: Optional[Firmware]
    responder: Optional[Responder]
    changes: List[Tuple[int, DpState, WdState]]
    cycle: int
    dp_state: DpState
    wd_state: WdState
    fdl_counters: Dict[str, int]
    txd: bool
    x_int: bool
    profile: str
    watchdog_due: int
    def probe(self) -> Probe: ...
    def save_state(self) -> bytes: ...
    def peek(self, addr: int) -> int: ...
    def peek_reg(self, name: str) -> int: ...
    def peek_field(self, register: str, field: str) -> int: ...
    def addr_of(self, name: str) -> Optional[int]: ...

class SegmentMaster:
    address: int
    slave_count: int
    selected: int
    slave: MasterSlave
    starting_up: bool
    started_up: bool
    token_rotation: int
    counters: MasterCounters
    history: List[Exchange]
    locks: Dict[int, int]
    def select(self, index: int) -> None: ...
    def startup_all(self, tries: int = 1000) -> bool: ...
    def startup(self, tries: int = 1000) -> bool: ...
    def begin_startup(self, tries: int = 1000) -> None: ...
    def dp_cycle(self, outputs: Optional[Sequence[_BytesLike]] = None,
                 skip: List[int] = ...) -> List[Exchange]: ...
    def data_exchange(self, outputs: _BytesLike) -> Exchange: ...
    def use_token(self, next: int,
                  outputs: Optional[Sequence[_BytesLike]] = None
                  ) -> TokenVisit: ...
    def pass_token(self, next: int) -> Exchange: ...
    def wait_token(self, timeout: int) -> bool: ...
    def fdl_status(self) -> Exchange: ...
    def slave_diag(self) -> Exchange: ...
    def global_control(self, command: int, groups: int = 0) -> Exchange: ...
    def transact(self, request: Frame) -> Exchange: ...
    def transact_raw(self, data: _BytesLike) -> Exchange: ...
    def idle(self, cycles: int) -> None: ...
    def clear_history(self) -> None: ...

class Segment:
    def __init__(self, baud: int = 1500000, clock_hz: int = 0, *,
                 vcd: Optional[Union[str, os.PathLike[str]]] = None,
                 fst: Optional[Union[str, os.PathLike[str]]] = None,
                 pcapng: Optional[Union[str, os.PathLike[str]]] = None,
                 signals: List[str] = ...) -> None: ...
    def add_station(self, address: int, profile: str = "dpc31", variant: Optional[str] = None,
                    firmware: Optional[Union[str, os.PathLike[str]]] = None, name: Optional[str] = None,
                    wd: Tuple[int, int] = (10, 10),
                    slave: Optional[SlaveConfig] = None, user_wd: Optional[bool] = None,
                    user_wd_value: Optional[int] = None) -> Station: ...
    stations: List[Station]
    def add_sender(self, name: str) -> int: ...
    def add_master(self, address: int, slaves: List[object], *, ttr: int = 0, gap: int = 0,
                   hsa: Optional[int] = None, slot_bits: int = 100,
                   idle_bits: int = 33) -> SegmentMaster: ...
    def name(self, station: int) -> str: ...
    size: int
    cycle: int
    bit_cycles: int
    clock_hz: int
    def run_until(self, cycle: int) -> None: ...
    def align(self) -> None: ...
    def send(self, sender: int, data: _BytesLike, start: Optional[int] = None,
             fault: Optional[str] = None, fault_char: Optional[int] = None) -> int: ...
    def pulse(self, sender: int, start: int, low_cycles: int) -> None: ...
    collisions: List[Collision]
    def on_telegram(self, callback: Optional[Callable[[LineTelegram], None]]) -> None: ...
    def on_collision(self, callback: Optional[Callable[[Collision], None]]) -> None: ...
    def flush(self) -> None: ...
    def close(self) -> None: ...
    def check_bus(self, *, ttr: Optional[int] = None, slot_bits: Optional[int] = None, min_tsdr_bits: int = 11,
                  tsyn_bits: int = 33, masters: Optional[List[int]] = None) -> BusCheck: ...
    bus_check: Optional[BusCheck]
    bus_log: List[str]

class SegmentScenarioResult:
    ok: bool
    exit_code: int
    walk: List[str]
    failures: List[str]

class SegmentScenario:
    @staticmethod
    def load(path: Union[str, os.PathLike[str]]) -> SegmentScenario: ...
    @staticmethod
    def parse(text: str, file: str = "<string>") -> SegmentScenario: ...
    file: str
    baud: int
    def run(self, *, vcd: Optional[Union[str, os.PathLike[str]]] = None,
            fst: Optional[Union[str, os.PathLike[str]]] = None,
            pcapng: Optional[Union[str, os.PathLike[str]]] = None,
            signals: List[str] = ...) -> SegmentScenarioResult: ...

class WavePoint:
    time: int
    time_b: int
    cycle: int
    own_a: int
    own_b: int

class Divergence:
    at: WavePoint
    a: str
    b: str
    last_common: Optional[str]
    open: bool

class SignalDiff:
    name: str
    name_b: str
    count: int
    first: Divergence
    last: WavePoint

class Structural:
    signal: str
    what: str

class WaveReport:
    same: bool
    clock_mode: bool
    pow: int
    edges: int
    compared: int
    only_a: List[str]
    only_b: List[str]
    structural: List[Structural]
    diffs: List[SignalDiff]
    warnings: List[str]
    def text(self, max_signals: int = 20) -> str: ...
    def json(self) -> str: ...

def wavediff(a: Union[str, os.PathLike[str]], b: Union[str, os.PathLike[str]], *, clock: Optional[str] = None, clock_b: Optional[str] = None,
             strip_a: str = "", strip_b: str = "", strip_auto: bool = False,
             map_file: Union[str, os.PathLike[str]] = "", include: List[str] = [], exclude: List[str] = [],
             ignore_missing: bool = False, xz: str = "strict",
             diff_vcd: Union[str, os.PathLike[str]] = "", edge: str = "rising", start: str = "", end: str = "",
             tolerance: str = "", tolerance_cycles: int = 0) -> WaveReport: ...
