"""The pure-Python client of `dpc31 serve` (dpc31.client, standard library only) drives a chip
in another process with the names of dpc31.Chip: the same calls give the same cycles and values
on both (docs/protocol.md; timing from docs/timing.md: 4 clocks per access, User_Timer_Clock at
Start + 48000).
"""

import contextlib
import re
import socket
import subprocess
import sys
import threading

import pytest

from dpc31.client import Client, ServeError


@pytest.fixture
def server(cli):
    proc = subprocess.Popen([cli, "serve", "--tcp", "0", "--profile", "spc3"],
                            stdout=subprocess.PIPE, text=True)
    line = proc.stdout.readline().split()
    assert line[:2] == ["listening", "tcp"]
    host, port = line[2].rsplit(":", 1)
    yield host, int(port)
    proc.terminate()
    assert proc.wait(timeout=30) == 0


def session(chip):
    """The same register-level session on either door; returns what it saw."""
    utc = 0x10  # Int_Req_Reg.User_Timer_Clock (regs/dpc31_regs.json, bit 4)
    edges = []
    chip.on_irq_change(lambda cycle, active: edges.append((cycle, active)))
    imr = chip.addr_of("Int_Mask_Reg")
    chip.write(imr, ~utc & 0xFF)
    chip.write(imr + 1, 0xFF)
    chip.write(chip.addr_of("Mode_Reg1_S"), 0x01)
    got_irq = chip.step_until_irq(100_000)
    chip.write_block(0x40, b"\x01\x02\x03")
    return (got_irq, chip.cycle, edges, chip.peek_reg("Int_Req_Reg") & utc,
            chip.read_block(0x40, 3), chip.peek(0x41), chip.started)


def test_client_and_module_agree(server):
    import dpc31

    with Client(tcp=server) as remote:
        assert remote.info["profile"] == "spc3"
        seen_remote = session(remote)
    seen_native = session(dpc31.Chip("spc3"))
    assert seen_remote == seen_native
    # Start completes at 3 x 4 = 12, the timer fires at 12 + 48000, three block writes follow
    assert seen_native[:3] == (True, 12 + 48_000 + 3 * 4, [(12 + 48_000, True)])


def test_errors_are_exceptions(server):
    with Client(tcp=server) as remote:
        with pytest.raises(ServeError) as e:
            remote.peek_reg("No_Such_Reg")
        assert e.value.code and "No_Such_Reg" in e.value.message
        assert remote.ping() == "pong"


def test_empty_blocks_are_answered_as_on_the_chip(server):
    """s31-serve, finding 7: an empty block raised ServeError on the client (the protocol has no
    empty block: `usage: writeblock ADDR HEX...`, `length 0 is out of range (1..4096)`), where
    dpc31.Chip gives None and b''. A bad address (0x800: the SPC3 has
    2 KB, chip-facts.md) still raises on both doors."""
    import dpc31

    native = dpc31.Chip("spc3")
    with Client(tcp=server) as remote:
        for chip in (native, remote):
            assert chip.write_block(0x400, b"") is None
            assert chip.read_block(0x400, 0) == b""
            assert chip.peek_block(0x400, 0) == b""
            assert chip.cycle == 0  # no bus access
        with pytest.raises(ValueError):
            native.read_block(0x800, 0)
        with pytest.raises(ServeError) as e:
            remote.read_block(0x800, 0)
        assert e.value.code == "range"
        assert remote.ping() == "pong"


# A register of the SPC3 (chip-facts.md §1.1, the register map: 08h write side Mode_Reg1_S), one
# it has at no address (Mode_Reg1: set at 08h, reset at 09h, its read-back at 15h the VPC3+'s
# only), one of another profile (manual-quotes.md, DPC31 p.22: InstQ_Base, the Instruction_Queue's
# base), a name no profile has: Chip.addr_of gives the address, None, None, a ValueError.
@pytest.mark.parametrize("name, address",
                         [("Mode_Reg1_S", 0x08), ("Mode_Reg1", None), ("InstQ_Base", None)])
def test_addr_of_gives_the_same_on_both_doors(server, name, address):
    import dpc31

    assert dpc31.Chip("spc3").addr_of(name) == address
    with Client(tcp=server) as remote:
        assert remote.addr_of(name) == address


def test_addr_of_a_name_no_profile_has_is_the_same_value_error_on_both_doors(server):
    import dpc31

    message = "^" + re.escape("no register 'No_Such_Reg' in profile spc3") + "$"
    with pytest.raises(ValueError, match=message):
        dpc31.Chip("spc3").addr_of("No_Such_Reg")
    with Client(tcp=server) as remote:
        with pytest.raises(ValueError, match=message):
            remote.addr_of("No_Such_Reg")
        assert remote.ping() == "pong"


def test_serve_tells_another_profiles_register_from_an_unknown_name(server):
    """docs/protocol.md, "Errors": no_address and unknown_register, one line each; peek_reg
    knows no other profile's register (unknown_register, as before), nor did addr: 'OK -0x001'."""
    with socket.create_connection(server, timeout=30) as s, s.makefile("rw") as f:
        for command, reply in [
                ("addr InstQ_Base",
                 "ERR no_address no register 'InstQ_Base' in profile spc3: another profile's "
                 "register"),
                ("addr Mode_Reg1", "ERR no_address Mode_Reg1 has no address in profile spc3"),
                ("peek_reg InstQ_Base", "ERR unknown_register no register 'InstQ_Base' in profile spc3"),
                ("addr No_Such_Reg", "ERR unknown_register no register 'No_Such_Reg' in profile spc3"),
                ("addr Mode_Reg1_S", "OK 0x0008")]:
            f.write(command + "\n")
            f.flush()
            assert f.readline() == reply + "\n"


def test_an_argument_cannot_send_a_second_command(server):
    """A line break inside an argument is refused before anything is sent: it would run a second
    command on the server ("Int_Reg\nreset" reset the chip) and put the replies out of step."""
    with Client(tcp=server) as remote:
        remote.step(1000)
        for call in (lambda: remote.peek_reg("Int_Reg\nreset"),
                     lambda: remote.poke_reg("Int_Mask_Reg\rreset", 1),
                     lambda: remote.addr_of("Int_Reg\0")):
            with pytest.raises(ValueError, match="line break or NUL"):
                call()
        with pytest.raises(ValueError) as e:  # named by its command: the argument may be a secret
            remote.peek_reg("s3cret\n")
        assert "s3cret" not in str(e.value) and "'peek_reg'" in str(e.value)
        assert remote.cycle == 1000  # nothing reset the chip
        assert remote.ping() == "pong"  # the replies are still in step


def test_the_client_loads_no_native_code():
    code = ("import sys, dpc31.client; "
            "sys.exit(1 if any(m.startswith('dpc31._') for m in sys.modules) else 0)")
    assert subprocess.run([sys.executable, "-c", code]).returncode == 0


def test_an_observer_exception_keeps_the_replies_in_step(server):
    """An observer's exception is raised by the call that ran the chip, after that call's own
    reply is read (as dpc31.Chip): the next call gets its own reply, not the one before."""
    with Client(tcp=server) as remote:
        remote.on_irq_change(broken)
        imr = remote.addr_of("Int_Mask_Reg")
        remote.write(imr, 0xEF)  # User_Timer_Clock unmasked
        remote.write(imr + 1, 0xFF)
        remote.write(remote.addr_of("Mode_Reg1_S"), 0x01)
        start = remote.cycle
        with pytest.raises(RuntimeError, match="observer bug"):
            remote.step(100_000)
        assert remote.ping() == "pong"  # not the reply of step
        remote.on_irq_change(None)
        assert remote.cycle == start + 100_000
        assert remote.addr_of("Int_Mask_Reg") == imr


@contextlib.contextmanager
def scripted_server(tmp_path, replies):
    """A Unix socket path where one connection gets `replies`, one for each line it sends."""
    path = str(tmp_path / "serve.sock")
    listener = socket.socket(socket.AF_UNIX, socket.SOCK_STREAM)
    listener.bind(path)
    listener.listen(1)
    listener.settimeout(30)

    def serve():
        conn, _ = listener.accept()
        with conn, conn.makefile("rb") as f:
            for reply in replies:
                f.readline()
                conn.sendall(reply)

    thread = threading.Thread(target=serve)
    thread.start()
    try:
        yield path
    finally:
        thread.join(30)
        listener.close()


def broken(cycle, active):
    raise RuntimeError("observer bug")


def test_an_err_reply_is_raised_before_an_observers_error(tmp_path):
    """A command that failed is said first, the observer's exception its __cause__: the caller
    must know the command did not run. A scripted server: the call's reply is an irq line, whose
    observer raises, then ERR."""
    with scripted_server(tmp_path, (
            b"OK profile=spc3\n",  # info
            b"! irq 12 1\nERR range cycles 0 is out of range (1..1000)\n",  # step
            b"OK pong\n")) as path:  # ping
        with Client(unix=path, timeout=30) as remote:
            remote.on_irq_change(broken)
            with pytest.raises(ServeError) as e:
                remote.step(0)
            assert e.value.code == "range"
            assert isinstance(e.value.__cause__, RuntimeError)
            assert str(e.value.__cause__) == "observer bug"
            assert remote.ping() == "pong"  # the observer's exception was not kept for it


def test_an_observers_exception_is_raised_by_an_addr_of_that_gives_none(tmp_path):
    """None is an answer, as an OK reply is: the observer's exception that came with the reply is
    raised (docs/python.md, "The dpc31 serve client"), not lost."""
    absent = b"ERR no_address no register 'InstQ_Base' in profile spc3: another profile's\n"
    with scripted_server(tmp_path, (b"OK profile=spc3\n", b"! irq 12 1\n" + absent,
                                    absent)) as path:
        with Client(unix=path, timeout=30) as remote:
            remote.on_irq_change(broken)
            with pytest.raises(RuntimeError, match="observer bug") as raised:
                remote.addr_of("InstQ_Base")
            assert raised.value.__context__ is None  # not raised while the ServeError was handled
            assert remote.addr_of("InstQ_Base") is None  # not kept for the next call


def test_pb3_reaches_the_client_as_status_and_observer(tmp_path):
    """The DPC31's DX_Out port as dpc31.Chip has it (`pb3`, `on_pb3_change`): serve's `status`
    field `pb3=` and its `! pb3 CYCLE 0|1` lines (docs/protocol.md; the server's side, a Sync's
    edges at their cycles, is tests/serve_test.cpp's ServeStartup). A scripted server: the step's
    reply comes after a PB3 edge."""
    status = (b"OK cycle=2944080 started=1 dp=Data_Exchange wd=DP_Control baud=12000000 xint=0 "
              b"irq=1 station=5 txd=1 pb3=1\n")
    with scripted_server(tmp_path, (b"OK profile=dpc31\n",  # info
                                    b"! irq 2944064 1\n! pb3 2944064 1\nOK 2944080\n",  # step
                                    status)) as path:
        with Client(unix=path, timeout=30) as remote:
            edges = []
            remote.on_pb3_change(lambda cycle, high: edges.append((cycle, high)))
            remote.step(16)
            assert edges == [(2944064, True)]
            assert remote.pb3 is True


@pytest.mark.parametrize("level", ["debug", "info"])
def test_a_log_shown_from_a_level_folds_repeats_as_that_level_shows_them(cli, level):
    """docs/protocol.md, `log`: the chip's log folds repeats as the lowest level a client asked
    for shows it. With `on_log(..., "debug")` a debug line between two equal info lines ends their
    repeats, the count right after the info line; with "info" the chip formats no debug line and
    the info line's repeats fold across them. On the DPC31 a read of its internal work cells (RAM
    the user must not touch) is an info line, a write of 1 to a bit Int_Ack_Reg ignores a debug
    line, a read of its unused register area a warning (regs/dpc31_regs.json); 4 clocks an access
    (docs/timing.md): the warning at 28 ends the last repeats."""
    import dpc31

    remark = [g.begin for g in dpc31.regions("dpc31") if g.ram and g.reserved][-1]
    unmapped = [g.begin for g in dpc31.regions("dpc31") if not g.ram and g.reserved][0]
    ack = dpc31.register("dpc31", "Int_Ack_Reg")
    bit = min(f.lsb for f in ack.fields if f.access == "IGN")  # Intel: low byte first
    proc = subprocess.Popen([cli, "serve", "--tcp", "0", "--profile", "dpc31"],
                            stdout=subprocess.PIPE, text=True)
    try:
        host, port = proc.stdout.readline().split()[2].rsplit(":", 1)
        seen = []
        with Client(tcp=(host, int(port))) as remote:
            remote.on_log(lambda cycle, lvl, text: seen.append((cycle, lvl, text)), level)
            for step in ("info", "info", "debug", "debug", "info", "info"):
                if step == "info":
                    remote.read(remark)
                else:
                    remote.write(ack.write_addr + bit // 8, 1 << (bit % 8))
            remote.read(unmapped)
    finally:
        proc.terminate()
        assert proc.wait(timeout=30) == 0
    info = seen[0][2]
    if level == "debug":
        assert seen == [(4, "info", info),
                        (12, "info", "last line repeated 1 times, at cycle 8"),
                        (12, "debug", seen[2][2]),
                        (20, "debug", "last line repeated 1 times, at cycle 16"),
                        (20, "info", info),
                        (28, "info", "last line repeated 1 times, at cycle 24"),
                        (28, "warn", seen[-1][2])]
    else:
        assert seen == [(4, "info", info),
                        (28, "info", "last line repeated 3 times, cycles 8 to 24"),
                        (28, "warn", seen[-1][2])]
    assert "unmapped address" in seen[-1][2]
