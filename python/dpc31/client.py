"""A client for ``dpc31 serve`` (docs/protocol.md), standard library only.

For scripts that must not load native code, or that talk to a chip in another process. The
methods have the names of ``dpc31.Chip``'s; what the protocol gives is what they give::

    from dpc31.client import Client
    with Client(tcp=("127.0.0.1", 5555)) as c:
        c.write(0x04, 0xFF)
        c.step(48000)
        print(c.cycle)

A reply ``ERR code message`` raises ``ServeError`` (``.code``, ``.message``); a connection that
ends or a line that is not the protocol's raises ``ConnectionError``. Asynchronous lines (``! irq``,
``! pb3``, ``! telegram``, ``! log``, ``! port``) reach the observers given with ``on_irq_change``,
``on_pb3_change``, ``on_telegram``, ``on_log`` and ``on_port`` while a command waits for its
reply. A server with
``--cpu`` adds the CPU's view: ``cpu()``, ``cpu_port(n)``, ``latch()``.
"""

from __future__ import annotations

import socket
from dataclasses import dataclass
from typing import Callable, Dict, List, Optional, Tuple

__all__ = ["Client", "ServeError", "Telegram"]


class ServeError(Exception):
    """An ``ERR CODE MESSAGE`` reply of the server."""

    def __init__(self, code: str, message: str) -> None:
        super().__init__(f"{code}: {message}" if message else code)
        self.code = code
        self.message = message


@dataclass(frozen=True)
class Telegram:
    """A ``! telegram START END rx|tx HEX`` line, as ``dpc31.Telegram`` has it."""

    from_chip: bool
    bytes: bytes
    start: int
    end: int


class Client:
    """One connection to ``dpc31 serve``: ``tcp=(host, port)`` or ``unix=PATH``."""

    def __init__(self, tcp: Optional[Tuple[str, int]] = None, unix: Optional[str] = None,
                 secret: Optional[str] = None, timeout: float = 60.0) -> None:
        if (tcp is None) == (unix is None):
            raise ValueError("give exactly one of tcp=(host, port) and unix=PATH")
        if tcp is not None:
            self._sock = socket.create_connection(tcp, timeout=timeout)
        else:
            self._sock = socket.socket(socket.AF_UNIX, socket.SOCK_STREAM)
            self._sock.settimeout(timeout)
            self._sock.connect(unix)
        self._file = self._sock.makefile("rb")
        self._irq: List[Callable[[int, bool], None]] = []
        self._pb3: List[Callable[[int, bool], None]] = []
        self._telegram: List[Callable[[Telegram], None]] = []
        self._log: List[Callable[[int, str, str], None]] = []
        self._port: List[Callable[[int, str, int], None]] = []
        self._observer_error: Optional[Exception] = None
        if secret is not None:
            self._call(f"auth {secret}")
        self.info: Dict[str, str] = dict(
            kv.split("=", 1) for kv in self._call("info").split())

    # --- the connection ---
    def close(self) -> None:
        self._file.close()
        self._sock.close()

    def __enter__(self) -> "Client":
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()

    def _line(self) -> str:
        raw = self._file.readline()
        if not raw.endswith(b"\n"):
            raise ConnectionError("dpc31 serve closed the connection")
        return raw.decode("ascii").rstrip("\r\n")

    def _call(self, command: str) -> str:
        # One call is one line: a line break inside an argument (a register name, a secret)
        # would send a second command, and the replies would no longer match the calls.
        if any(c in command for c in "\r\n\0"):
            # Named by its command only: the argument may be a secret.
            raise ValueError(f"an argument of '{command.split(' ', 1)[0]}' holds a line break "
                             "or NUL")
        self._sock.sendall(command.encode("ascii") + b"\n")
        while True:
            line = self._line()
            if line.startswith("!"):
                self._async(line)
                continue
            # An observer's exception once the reply is read: the next call gets its own reply.
            # A failed command or a broken reply comes first (the observer's exception its
            # cause): the caller must know the command did not run.
            error, self._observer_error = self._observer_error, None
            if line.startswith("ERR "):
                code, _, message = line[4:].partition(" ")
                raise ServeError(code, message) from error
            if line != "OK" and not line.startswith("OK "):
                raise ConnectionError(f"not a dpc31 serve reply: {line!r}") from error
            if error is not None:
                raise error
            return line[3:]

    def _async(self, line: str) -> None:
        words = line.split()
        if len(words) == 4 and words[1] == "irq":
            self._notify(self._irq, int(words[2]), words[3] == "1")
        elif len(words) == 4 and words[1] == "pb3":
            self._notify(self._pb3, int(words[2]), words[3] == "1")
        elif len(words) == 6 and words[1] == "telegram":
            t = Telegram(words[4] == "tx", bytes.fromhex(words[5]), int(words[2]), int(words[3]))
            self._notify(self._telegram, t)
        elif len(words) >= 4 and words[1] == "log":
            self._notify(self._log, int(words[2]), words[3], " ".join(words[4:]))
        elif len(words) == 5 and words[1] == "port":
            self._notify(self._port, int(words[2]), words[3], int(words[4], 16))
        elif len(words) >= 2 and words[1] == "bye":
            raise ConnectionError(f"dpc31 serve ended the connection: {' '.join(words[2:])}")

    def _notify(self, callbacks: list, *args: object) -> None:
        for cb in callbacks:
            try:
                cb(*args)
            except Exception as e:  # the first one is raised by _call, after its reply
                if self._observer_error is None:
                    self._observer_error = e

    # --- observers: a callable adds one, None removes all of that kind (as dpc31.Chip) ---
    def on_irq_change(self, callback: Optional[Callable[[int, bool], None]]) -> None:
        self._observe(self._irq, callback)

    def on_pb3_change(self, callback: Optional[Callable[[int, bool], None]]) -> None:
        """The DPC31's port PB3 (DX_Out of a Sync): (cycle, high) for each ``! pb3`` line."""
        self._observe(self._pb3, callback)

    def on_telegram(self, callback: Optional[Callable[[Telegram], None]]) -> None:
        self._observe(self._telegram, callback)

    def on_log(self, callback: Optional[Callable[[int, str, str], None]],
               level: str = "info") -> None:
        self._observe(self._log, callback)
        self._call(f"log {level if self._log else 'off'}")

    def on_port(self, callback: Optional[Callable[[int, str, int], None]]) -> None:
        """``--cpu 80c32``: (cycle, name, value) for each write of the board's output latch."""
        self._observe(self._port, callback)

    @staticmethod
    def _observe(lst: list, callback: Optional[Callable]) -> None:
        if callback is None:
            lst.clear()
        else:
            lst.append(callback)

    # --- the bus and the debugger ---
    def read(self, addr: int) -> int:
        return int(self._call(f"read {addr}"), 16)

    def write(self, addr: int, value: int) -> None:
        self._call(f"write {addr} {value}")

    def peek(self, addr: int) -> int:
        return int(self._call(f"peek {addr}"), 16)

    def poke(self, addr: int, value: int) -> bool:
        return self._store(f"poke {addr} {value}")

    def _store(self, command: str) -> bool:
        """A poke: False where the read side has no storage (ERR no_storage)."""
        try:
            self._call(command)
        except ServeError as e:
            if e.code == "no_storage":
                return False
            raise
        return True

    # An empty block is no transfer, as on dpc31.Chip (None, b''): the protocol has no empty
    # block, so only ADDR is checked, by a `peek` (no side effect): a bad one raises as for a
    # block of one byte.
    def read_block(self, addr: int, length: int) -> bytes:
        if length == 0:
            return self._no_block(addr)
        return bytes.fromhex(self._call(f"readblock {addr} {length}"))

    def write_block(self, addr: int, data: bytes) -> None:
        data = bytes(data)
        if not data:
            self._no_block(addr)
            return
        self._call(f"writeblock {addr} {data.hex()}")

    def peek_block(self, addr: int, length: int) -> bytes:
        if length == 0:
            return self._no_block(addr)
        return bytes.fromhex(self._call(f"peekblock {addr} {length}"))

    def _no_block(self, addr: int) -> bytes:
        self._call(f"peek {addr}")
        return b""

    def peek_reg(self, name: str) -> int:
        return int(self._call(f"peek_reg {name}"), 16)

    def poke_reg(self, name: str, value: int) -> bool:
        return self._store(f"poke_reg {name} {value}")

    def addr_of(self, name: str) -> Optional[int]:
        """As ``dpc31.Chip.addr_of``: None for a register without an address on the served chip
        (``ERR no_address``: another profile's, or the SPC3's Mode_Reg1), a ValueError for a name
        no profile has."""
        try:
            return int(self._call(f"addr {name}"), 16)
        except ServeError as e:
            if e.code == "unknown_register":
                raise ValueError(e.message) from e
            if e.code != "no_address":
                raise
            pending = e.__cause__
        # An observer's exception is raised here, outside the handler, as after an OK reply:
        # raised inside it, it would carry the ServeError as its __context__.
        if pending is not None:
            raise pending
        return None

    # --- time ---
    def step(self, cycles: int = 1) -> None:
        self._call(f"step {cycles}")

    def step_until_irq(self, cycles: int) -> bool:
        return self._call(f"run_until_irq {cycles}").split()[0] == "irq"

    @property
    def cycle(self) -> int:
        return int(self._call("cycle"))

    def reset(self) -> None:
        self._call("reset")

    # --- state ---
    def status(self) -> Dict[str, str]:
        return dict(kv.split("=", 1) for kv in self._call("status").split())

    @property
    def x_int(self) -> bool:
        return self.status()["xint"] == "1"

    @property
    def irq_active(self) -> bool:
        return self.status()["irq"] == "1"

    @property
    def pb3(self) -> bool:
        return self.status()["pb3"] == "1"

    @property
    def started(self) -> bool:
        return self.status()["started"] == "1"

    @property
    def dp_state(self) -> str:
        return self.status()["dp"]

    @property
    def wd_state(self) -> str:
        return self.status()["wd"]

    @property
    def station_address(self) -> int:
        return int(self.status()["station"])

    @property
    def fdl_counters(self) -> Dict[str, int]:
        return {k: int(v) for k, v in
                (kv.split("=", 1) for kv in self._call("counters").split())}

    # --- the CPU (a server with --cpu; docs/protocol.md, "A CPU on the bus") ---
    def cpu(self) -> Dict[str, object]:
        """The CPU's registers: ``core`` a name, every other key a number."""
        regs = dict(kv.split("=", 1) for kv in self._call("cpu").split())
        return {k: v if k == "core" else int(v, 0) for k, v in regs.items()}

    def cpu_port(self, n: int) -> Tuple[int, int]:
        """Port n's latch and pins."""
        kv = dict(kv.split("=", 1) for kv in self._call(f"cpu_port {n}").split())
        return int(kv["latch"], 16), int(kv["pins"], 16)

    def latch(self) -> Dict[str, int]:
        """The 80C32 board's output latch bytes by name."""
        return {k: int(v, 16) for k, v in
                (kv.split("=", 1) for kv in self._call("latch").split())}

    # --- the serial side ---
    def inject(self, data: bytes, baud: Optional[int] = None, idle: Optional[int] = None,
               fault: Optional[str] = None, fault_char: int = 0) -> Tuple[int, int]:
        """Puts bytes on RxD as UART characters; returns (first start bit, end of last stop)."""
        cmd = f"inject {bytes(data).hex()}"
        if baud is not None:
            cmd += f" baud={baud}"
        if idle is not None:
            cmd += f" idle={idle}"
        if fault is not None:
            cmd += f" fault={fault}:{fault_char}"
        start, end = self._call(cmd).split()
        return int(start), int(end)

    # --- snapshots: by name in the server's --state-dir ---
    def save_state_file(self, name: str) -> None:
        self._call(f"save {name}")

    def load_state_file(self, name: str) -> None:
        self._call(f"load {name}")

    def ping(self) -> str:
        return self._call("ping")

    def shutdown(self) -> None:
        self._call("shutdown")
