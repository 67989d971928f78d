"""Your binary on the board's CPU from Python (docs/python.md, docs/cpu.md): DO4 built by SDCC
for the 80C32 reaches Data_Exchange with the module's master, its port write at the cycle derived
by hand; the DPC31's C31 runs tests/mcs51/board/c31_ack.asm from the chip's RAM.

Expected cycles: docs/timing.md (the line), docs/cpu.md ("MOVX timing", "INT0 from X/INT") and
the derivation in traces/do4_80c32.scn's comments (DO4's path from SDCC's listing)."""

import subprocess

import pytest

import dpc31
from dpc31.client import Client, ServeError

T = 256  # 187.5 kbaud at 48 MHz: round(48e6 / 187500) clocks per bit (docs/timing.md)


@pytest.fixture
def fw51(built):
    """SDCC's builds of the firmware for the 80C32 (firmware/mcs51)."""
    return built("DPC31_FW51")


@pytest.fixture
def board_programs(built):
    """The board's test programs (tests/mcs51/board)."""
    return built("DPC31_BOARD")


def test_do4_on_the_80c32_reaches_data_exchange_and_drives_its_outputs_on_time(fw51):
    chip = dpc31.Chip("spc3")
    board = dpc31.Cpu51Board(chip, hz=24_000_000, address=0x8000)
    assert board.load_hex(str(fw51 / "do4_80c32.ihx")) > 0
    board.set_port_input(1, 7)  # the address switch DO4's main() reads
    latch = []  # the module's outputs: XDATA 4000h + port (docs/cpu.md, "DO4 on the 80C32")
    board.on_ram_write(lambda addr, value, cycle: latch.append((addr, value, cycle)))
    slave = dpc31.SlaveConfig(address=7, ident=0x0D04, cfg=b"\x21\x10", in_len=1, out_len=2,
                              wd_fact1=2, wd_fact2=5, user_prm=b"\x00\x01\x05\x00")
    master = dpc31.Master(chip, address=2, baud=187_500, slave=slave)
    master.run_board(board)
    assert master.startup()
    assert chip.dp_state == dpc31.DpState.Data_Exchange
    master.idle(5 * 48_000)  # DO4's ISR of the start-up's exchange ends
    latch.clear()
    ex = master.data_exchange(b"\x0A\x01")
    master.idle(5 * 48_000)
    # Outputs 0A 01, SD2 of 11 characters: DX_Out and X/INT at the last stop sample,
    # E = X + (11 x 11 - 1) T + T/2; INT0 sampled at S5P2 of machine cycle m (chip cycle
    # 24m + 20), the first m with 24m + 20 >= E; the idle 80C32 polls in m + 1, calls in m + 2
    # and m + 3, the vector in m + 4; 1 034 machine cycles from it to the MOVX of `outputs`
    # (4000h), 22 more to `modul_ok` (4001h); WR ends at 24M + 36.
    e = ex.request_start + (11 * 11 - 1) * T + T // 2
    m = (e - 20 + 23) // 24
    movx = m + 4 + 1034
    assert (0x4000, 0x0A, 24 * movx + 36) in latch
    assert (0x4001, 0x01, 24 * (movx + 22) + 36) in latch
    assert board.xdata(0x4000) == 0x0A and board.xdata(0x4001) == 0x01
    assert board.in_service == 0


def test_the_boards_reset_starts_do4_again_to_data_exchange(fw51):
    """docs/cpu.md, "The board's reset": Cpu51Board.reset() resets CPU and chip together at the
    board's instant, and DO4 starts the chip again from its reset vector. The instant I is where
    the master's idle ended; the CPU starts in the first machine cycle at or after it, m0 = ceil(I /
    24) at 24 MHz beside 48 MHz, and DO4's start-up (traces/do4_80c32.scn, rule 5 of docs/cpu.md
    "Exact cycles") reaches Start_SPC3 22 127 machine cycles later: X/INT active with DX_Out at
    24 (m0 + 22 127) + 36. Then the master's start-up reaches Data_Exchange again. (A reset of the
    chip alone, Chip.reset(), leaves the firmware idle in its main loop and the chip Offline.)"""
    chip = dpc31.Chip("spc3")
    board = dpc31.Cpu51Board(chip, hz=24_000_000, address=0x8000)
    board.load_hex(str(fw51 / "do4_80c32.ihx"))
    board.set_port_input(1, 7)
    slave = dpc31.SlaveConfig(address=7, ident=0x0D04, cfg=b"\x21\x10", in_len=1, out_len=2,
                              wd_fact1=2, wd_fact2=5, user_prm=b"\x00\x01\x05\x00")
    master = dpc31.Master(chip, address=2, baud=187_500, slave=slave)
    master.run_board(board)
    assert master.startup()
    master.idle(5 * 48_000 + 7)  # an instant that is no machine cycle's start
    edges = []
    chip.on_irq_change(lambda cycle, active: edges.append((cycle, active)))
    instant = chip.cycle
    board.reset()
    assert chip.cycle == instant and board.pc == 0
    assert chip.dp_state != dpc31.DpState.Data_Exchange
    m0 = (instant + 23) // 24
    assert board.machine_cycles == m0
    master.idle(20 * 48_000)
    assert (24 * (m0 + 22_127) + 36, True) in edges
    assert master.startup()
    assert chip.dp_state == dpc31.DpState.Data_Exchange


def test_the_c31_runs_from_the_chips_ram(board_programs):
    # MOVX strobes at clocks 78, 162, 282, 366, 426 = chip cycles 156, 324, 564, 732, 852 at
    # 24 MHz (c31_ack.asm's machine cycles [5,7), [12,14), [22,24), [29,31), [34,36); WR ends
    # 18 clocks into a MOVX): the C31's interrupt raised at 324, acknowledged at 564.
    chip = dpc31.Chip("dpc31", irq_controller="c31")
    edges = []
    chip.on_irq_change(lambda cycle, active: edges.append((cycle, active)))
    board = dpc31.Cpu51Board.c31(chip, hz=24_000_000, code=0x1000)
    board.load_hex(str(board_programs / "c31_ack.ihx"))
    assert chip.peek(0x1000) == 0x02  # LJMP start, in the code area
    board.run_until(1000)
    assert edges == [(324, True), (564, False)]
    assert board.a == 0x77  # fetched from the C31's own rewrite of its code in the chip's RAM
    assert chip.peek(0x08A0) == 0x77
    assert board.in_service == 0


def test_a_bad_image_names_its_file_and_line(tmp_path):
    broken = tmp_path / "broken.ihx"
    broken.write_text(":0100000000FF\n:0300000002003\n")  # line 2: odd length
    board = dpc31.Cpu51Board(dpc31.Chip("spc3"))
    with pytest.raises(dpc31.InputError, match=f"^{broken}:2: "):
        board.load_hex(str(broken))
    with pytest.raises(ValueError):
        dpc31.Cpu51Board.c31(dpc31.Chip("spc3"))  # the C31 is the dpc31's


def test_the_c31_behind_dpc31_serve_from_the_pure_python_client(cli, board_programs, tmp_path):
    # The same program behind the socket: the client is no bus master (ERR cpu), the CPU's
    # registers and the interrupt edges at the same cycles.
    sock = str(tmp_path / "chip.sock")
    proc = subprocess.Popen([cli, "serve", "--unix", sock, "--profile", "dpc31", "--cpu", "c31",
                             "--firmware", str(board_programs / "c31_ack.ihx")],
                            stdout=subprocess.PIPE, text=True)
    try:
        assert proc.stdout.readline().split()[:2] == ["listening", "unix"]
        with Client(unix=sock) as c:
            assert c.info["cpu"] == "c31" and c.info["code"] == "0x1000"
            edges = []
            c.on_irq_change(lambda cycle, active: edges.append((cycle, active)))
            with pytest.raises(ServeError) as refused:
                c.read(0x08A0)
            assert refused.value.code == "cpu"
            c.step(1000)
            assert edges == [(324, True), (564, False)]
            regs = c.cpu()
            assert regs["core"] == "c31" and regs["a"] == 0x77 and regs["in_service"] == 0
            assert c.peek(0x08A0) == 0x77
            assert c.cpu_port(1) == (0xFF, 0x05)  # the address switch: station 5
            c.shutdown()
        assert proc.wait(timeout=30) == 0
    finally:
        if proc.poll() is None:
            proc.kill()
            proc.wait()


def test_a_board_needs_a_chip_at_cycle_0_and_of_its_own():
    """docs/cpu.md, "The board": the CPU's clock counts from the chip's cycle 0, and one CPU
    drives the chip's bus. On a chip that had run, the board's times were off by its cycle; a
    second board on one chip never ran (the first one's run took the chip's time)."""
    ran = dpc31.Chip("spc3")
    ran.step(1_000_000)
    with pytest.raises(ValueError, match=r"^the chip has run \(cycle 1000000\): a board starts "
                                         r"with a chip at cycle 0$"):
        dpc31.Cpu51Board(ran)
    chip = dpc31.Chip("spc3")
    first = dpc31.Cpu51Board(chip)
    with pytest.raises(ValueError,
                       match=r"^the chip has a board already: one CPU drives a chip's bus$"):
        dpc31.Cpu51Board(chip)
    with pytest.raises(ValueError, match=r"^the chip has a board already"):
        dpc31.Cpu51Board.c31(chip)
    del first  # its chip is free again
    assert dpc31.Cpu51Board(chip).chip is chip


def test_a_cpu_clock_past_the_chips_last_cycle_is_refused_not_wrapped():
    """At 24 MHz beside a 48 MHz chip, clock 2**63 is chip cycle 2**64: it came back as 0. The
    chip's time ends at 2**62 - 1 (Chip::kLastCycle), the cycle of clock 2**61 - 1."""
    board = dpc31.Cpu51Board(dpc31.Chip("spc3"), hz=24_000_000)
    assert board.chip_cycle_of(2**61 - 1) == 2**62 - 2
    for clock in (2**61, 2**63, 2**64 - 1):
        with pytest.raises(ValueError, match=rf"^cpu_clock {clock} out of range "
                                             r"\(0..2305843009213693951\): past the chip's last "
                                             r"cycle$"):
            board.chip_cycle_of(clock)


def test_the_masters_retry_does_not_depend_on_the_slaves_cpu(tmp_path):
    # docs/timing.md, "The master's wait": at 1.5 Mbaud (T = 32) the first FDL_Status starts at
    # TSYN = 33 T = 1 056; unanswered (the DIV loop, 84h DIV AB and 80h FDh SJMP, never starts
    # the chip), its 6 characters (66 T) and the slot time (100 T) end the wait, and the next
    # request starts TSYN later: 1 056 + 199 T = 7 424, whatever CPU the slave has. With an
    # 80C32 beside the chip it started where the board's step ended (7 436 at 24 MHz, 7 872 at
    # 1 MHz).
    image = tmp_path / "div.ihx"
    image.write_text(":030000008480FDFC\n:00000001FF\n")
    for hz in (1_000_000, 24_000_000):
        chip = dpc31.Chip("spc3")
        board = dpc31.Cpu51Board(chip, hz=hz)
        assert board.load_hex(str(image)) == 3
        master = dpc31.Master(chip, address=2, baud=1_500_000, slave=dpc31.SlaveConfig(address=7))
        master.run_board(board)
        first, second = master.fdl_status(), master.fdl_status()
        assert (first.request_start, second.request_start) == (1056, 7424), hz


def test_the_serial_ports_characters_reach_on_serial(tmp_path):
    """docs/cpu.md, "Serial port": MOV SBUF,#41h; SJMP $ in mode 0 sets TI at the end of machine
    cycle 10, chip cycle 264 at 24 MHz (ScenarioCpu51.TheSerialPortsCharactersReachTheWalk derives
    it from the manual); the callback gets (data, cycle) once, nothing more while SJMP spins."""
    image = tmp_path / "sbuf.ihx"
    image.write_text(":0500000075994180FE2E\n:00000001FF\n")
    chip = dpc31.Chip("spc3")
    board = dpc31.Cpu51Board(chip)
    board.load_hex(str(image))
    sent = []
    board.on_serial(lambda data, cycle: sent.append((data, cycle)))
    board.run_until(48_000)
    assert sent == [(0x41, 264)]


def test_the_boards_observers_are_removed_with_none(tmp_path):
    """docs/python.md, the observers: a callable adds one, None removes it; the board's
    on_serial(None) and on_ram_write(None) were TypeErrors naming no argument (s31 benches
    finding 9). MOV SBUF,#41h sends one character (TI at chip cycle 264, as above); MOV DPTR,
    #0100h; MOVX @DPTR,A writes the board's RAM once (0100h is outside the chip's window at
    8000h)."""
    import pytest

    sbuf, movx = tmp_path / "sbuf.ihx", tmp_path / "movx.ihx"
    sbuf.write_text(":0500000075994180FE2E\n:00000001FF\n")
    movx.write_text(":06000000900100F080FEFB\n:00000001FF\n")
    seen = {}
    for removed in (False, True):
        serial = dpc31.Cpu51Board(dpc31.Chip("spc3"))
        serial.load_hex(str(sbuf))
        ram = dpc31.Cpu51Board(dpc31.Chip("spc3"))
        ram.load_hex(str(movx))
        sent, written = [], []
        serial.on_serial(lambda data, cycle: sent.append(data))
        ram.on_ram_write(lambda addr, value, cycle: written.append(addr))
        if removed:
            serial.on_serial(None)
            ram.on_ram_write(None)
        serial.run_until(48_000)
        ram.run_until(48_000)
        seen[removed] = (sent, written)
    assert seen == {False: ([0x41], [0x0100]), True: ([], [])}
    for name in ("on_serial", "on_ram_write"):
        with pytest.raises(TypeError, match=f"^{name}: callback: a callable or None expected, "
                                            "got int$"):
            getattr(serial, name)(5)


def sbuf_board(tmp_path):
    """docs/cpu.md's example, MOV SBUF,#41h; SJMP $, on an 80C32 at 24 MHz beside an SPC3."""
    image = tmp_path / "sbuf.ihx"
    image.write_text(":0500000075994180FE2E\n:00000001FF\n")
    chip = dpc31.Chip("spc3")
    board = dpc31.Cpu51Board(chip)
    board.load_hex(str(image))
    return chip, board


def test_a_boards_run_after_an_observers_exception_ends_at_the_cycle_asked(tmp_path):
    """As Chip.step(n) (docs/python.md, "The GIL"): the exception is raised when run_until returns,
    and chip and CPU are where the run without it ends: chip cycle 48 000, CPU clock 24 000 at
    24 MHz, machine cycle 2 000 (SJMP's step [1998, 2000) samples last at chip cycle 47 996 and
    runs; the next one's first sample, 48 020, waits)."""
    chip, board = sbuf_board(tmp_path)
    calls = []

    def boom(data, cycle):
        calls.append((data, cycle))
        raise RuntimeError("serial observer failed")

    board.on_serial(boom)
    with pytest.raises(RuntimeError, match="serial observer failed"):
        board.run_until(48_000)
    assert calls == [(0x41, 264)]
    assert (chip.cycle, board.machine_cycles) == (48_000, 2000)


def test_a_running_boards_cpu_is_refused_to_another_thread(tmp_path, refused_while):
    """docs/python.md, "The GIL": one chip, one thread at a time. The CPU's registers, ports and
    RAM were read while the running thread wrote them (audit s35 aTb finding 1), where
    set_port_input and load_hex were refused. The looks happen while on_serial holds the run (TI
    at chip cycle 264); the run then ends at 48 000 as without them."""
    chip, board = sbuf_board(tmp_path)
    names = ("pc", "a", "b", "psw", "sp", "dptr", "machine_cycles", "in_service")
    looks = {name: (lambda name=name: getattr(board, name)) for name in names}
    looks.update(port=lambda: board.port(1), pins=lambda: board.pins(1),
                 xdata=lambda: board.xdata(0x100), chip_cycle_of=lambda: board.chip_cycle_of(24))
    refused = refused_while(lambda: board.run_until(48_000), looks, board.on_serial)
    assert set(refused) == set(looks)
    assert all("running in another thread" in e for e in refused.values())
    assert (chip.cycle, board.machine_cycles, board.pc) == (48_000, 2000, 3)


def test_a_load_under_a_board_takes_only_a_snapshot_of_the_boards_instant(tmp_path):
    """docs/cpu.md, "The board": under a board the chip loads only a snapshot of the board's
    instant, where its last run ended; another cycle is refused as `dpc31 serve --cpu` refuses
    `load` (SnapshotError, the chip unchanged): a chip at 96 000 under a CPU at 48 000 took the
    CPU's accesses of the gap back to back. After a reset the board's instant is still 96 000."""
    chip, board = sbuf_board(tmp_path)
    board.run_until(48_000)
    at48 = chip.save_state()
    board.run_until(96_000)
    at96 = chip.save_state()
    chip2, board2 = sbuf_board(tmp_path)
    board2.run_until(48_000)
    before = chip2.save_state()
    with pytest.raises(dpc31.SnapshotError) as e:
        chip2.load_state(at96)
    assert str(e.value) == ("snapshot of cycle 96000 under a CPU board at cycle 48000: the CPU's "
                            "state is not the chip's: it would run on against another chip")
    assert chip2.save_state() == before
    chip.reset()
    chip.load_state(at96)
    with pytest.raises(dpc31.SnapshotError):
        chip.load_state(at48)
    board.run_until(144_000)
    assert (chip.cycle, board.machine_cycles) == (144_000, 6000)


def test_a_chip_reset_under_a_board_counts_on_from_the_boards_instant(tmp_path):
    """docs/cpu.md, "The board": a reset is an event at the board's instant and the chip's clock
    counts on from there, as the CPU's does: the chip stands at 48 000 after it, a run to 10 runs
    nothing, and run_until(96 000) ends with the CPU at machine cycle 4 000."""
    chip, board = sbuf_board(tmp_path)
    board.run_until(48_000)
    chip.reset()
    assert chip.cycle == 48_000
    board.run_until(10)
    assert (chip.cycle, board.machine_cycles) == (48_000, 2000)
    board.run_until(96_000)
    assert (chip.cycle, board.machine_cycles) == (96_000, 4000)


def test_a_chip_reset_under_a_board_tells_its_edges_at_the_boards_instant(tmp_path):
    """docs/cpu.md, "The board"; docs/timing.md, "hardware reset" (it clears Int_Req_Reg: an active
    interrupt ends in the reset's cycle) and "Timers" (the first User_Timer_Clock at Start + 48 000).
    User_Timer_Clock alone unmasked and Start_SPC3 written before the board runs complete at 4, 8,
    12: the interrupt is active from 48 012 (SJMP $ never serves it). Chip.reset() after
    run_until(50 000) is at the board's instant: the interrupt ends at 50 000 (on_irq_change),
    X/INT is high again, and an access then completes at 50 004, not at 4."""
    chip, board = sbuf_board(tmp_path)
    utc = dpc31.register("spc3", "Int_Req_Reg").field("User_Timer_Clock").mask
    imr = chip.addr_of("Int_Mask_Reg")
    start = dpc31.register("spc3", "Mode_Reg1_S").field("Start_SPC3").mask
    edges = []
    chip.on_irq_change(lambda cycle, active: edges.append((cycle, active)))
    chip.write(imr, ~utc & 0xFF)
    chip.write(imr + 1, 0xFF)
    chip.write(chip.addr_of("Mode_Reg1_S"), start)
    board.run_until(50_000)
    assert edges == [(48_012, True)] and not chip.x_int
    chip.reset()
    assert edges == [(48_012, True), (50_000, False)]
    assert (chip.cycle, chip.x_int, chip.started) == (50_000, True, False)
    chip.write(imr, 0xFF)
    assert chip.cycle == 50_004
    board.run_until(96_000)
    assert (chip.cycle, board.machine_cycles) == (96_000, 4000)
